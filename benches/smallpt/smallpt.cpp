// smallpt, a path tracer by Kevin Beason, 2008 (http://www.kevinbeason.com/smallpt/, MIT
// licence), unchanged above main(): the baseline the performance issue measures ptui against.
// Build and run side by side with ptui (see benches/README.md; `cargo xtask bench-error
// --smallpt target/smallpt` runs it):
//   g++ -O3 -fopenmp benches/smallpt/smallpt.cpp -o target/smallpt && target/smallpt 10 out.pfm
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <omp.h>
struct Vec { double x, y, z; Vec(double x_=0, double y_=0, double z_=0){ x=x_; y=y_; z=z_; }
  Vec operator+(const Vec &b) const { return Vec(x+b.x,y+b.y,z+b.z); }
  Vec operator-(const Vec &b) const { return Vec(x-b.x,y-b.y,z-b.z); }
  Vec operator*(double b) const { return Vec(x*b,y*b,z*b); }
  Vec mult(const Vec &b) const { return Vec(x*b.x,y*b.y,z*b.z); }
  Vec& norm(){ return *this = *this * (1/sqrt(x*x+y*y+z*z)); }
  double dot(const Vec &b) const { return x*b.x+y*b.y+z*b.z; }
  Vec operator%(Vec&b){return Vec(y*b.z-z*b.y,z*b.x-x*b.z,x*b.y-y*b.x);} };
struct Ray { Vec o, d; Ray(Vec o_, Vec d_) : o(o_), d(d_) {} };
enum Refl_t { DIFF, SPEC, REFR };
struct Sphere { double rad; Vec p, e, c; Refl_t refl;
  Sphere(double rad_, Vec p_, Vec e_, Vec c_, Refl_t refl_): rad(rad_), p(p_), e(e_), c(c_), refl(refl_) {}
  double intersect(const Ray &r) const { Vec op = p-r.o; double t, eps=1e-4, b=op.dot(r.d), det=b*b-op.dot(op)+rad*rad;
    if (det<0) return 0; else det=sqrt(det); return (t=b-det)>eps ? t : ((t=b+det)>eps ? t : 0); } };
Sphere spheres[] = {
  Sphere(1e5, Vec( 1e5+1,40.8,81.6), Vec(),Vec(.75,.25,.25),DIFF),
  Sphere(1e5, Vec(-1e5+99,40.8,81.6),Vec(),Vec(.25,.25,.75),DIFF),
  Sphere(1e5, Vec(50,40.8, 1e5),     Vec(),Vec(.75,.75,.75),DIFF),
  Sphere(1e5, Vec(50,40.8,-1e5+170), Vec(),Vec(),           DIFF),
  Sphere(1e5, Vec(50, 1e5, 81.6),    Vec(),Vec(.75,.75,.75),DIFF),
  Sphere(1e5, Vec(50,-1e5+81.6,81.6),Vec(),Vec(.75,.75,.75),DIFF),
  Sphere(16.5,Vec(27,16.5,47),       Vec(),Vec(1,1,1)*.999, SPEC),
  Sphere(16.5,Vec(73,16.5,78),       Vec(),Vec(1,1,1)*.999, REFR),
  Sphere(600, Vec(50,681.6-.27,81.6),Vec(12,12,12),  Vec(), DIFF)
};
inline double clamp(double x){ return x<0 ? 0 : x>1 ? 1 : x; }
inline int toInt(double x){ return int(pow(clamp(x),1/2.2)*255+.5); }
inline bool intersect(const Ray &r, double &t, int &id){
  double n=sizeof(spheres)/sizeof(Sphere), d, inf=t=1e20;
  for(int i=int(n);i--;) if((d=spheres[i].intersect(r))&&d<t){t=d;id=i;}
  return t<inf; }
Vec radiance(const Ray &r, int depth, unsigned short *Xi){
  double t; int id=0;
  if (!intersect(r, t, id)) return Vec();
  const Sphere &obj = spheres[id];
  Vec x=r.o+r.d*t, n=(x-obj.p).norm(), nl=n.dot(r.d)<0?n:n*-1, f=obj.c;
  double p = f.x>f.y && f.x>f.z ? f.x : f.y>f.z ? f.y : f.z;
  if (++depth>5) { if (erand48(Xi)<p) f=f*(1/p); else return obj.e; }
  if (depth>100) return obj.e;
  if (obj.refl == DIFF){
    double r1=2*M_PI*erand48(Xi), r2=erand48(Xi), r2s=sqrt(r2);
    Vec w=nl, u=((fabs(w.x)>.1?Vec(0,1):Vec(1))%w).norm(), v=w%u;
    Vec d = (u*cos(r1)*r2s + v*sin(r1)*r2s + w*sqrt(1-r2)).norm();
    return obj.e + f.mult(radiance(Ray(x,d),depth,Xi));
  } else if (obj.refl == SPEC)
    return obj.e + f.mult(radiance(Ray(x,r.d-n*2*n.dot(r.d)),depth,Xi));
  Ray reflRay(x, r.d-n*2*n.dot(r.d));
  bool into = n.dot(nl)>0;
  double nc=1, nt=1.5, nnt=into?nc/nt:nt/nc, ddn=r.d.dot(nl), cos2t;
  if ((cos2t=1-nnt*nnt*(1-ddn*ddn))<0) return obj.e + f.mult(radiance(reflRay,depth,Xi));
  Vec tdir = (r.d*nnt - n*((into?1:-1)*(ddn*nnt+sqrt(cos2t)))).norm();
  double a=nt-nc, b=nt+nc, R0=a*a/(b*b), c = 1-(into?-ddn:tdir.dot(n));
  double Re=R0+(1-R0)*c*c*c*c*c,Tr=1-Re,P=.25+.5*Re,RP=Re/P,TP=Tr/(1-P);
  return obj.e + f.mult(depth>2 ? (erand48(Xi)<P ? radiance(reflRay,depth,Xi)*RP:radiance(Ray(x,tdir),depth,Xi)*TP) :
    radiance(reflRay,depth,Xi)*Re+radiance(Ray(x,tdir),depth,Xi)*Tr);
}
// Time-budgeted driver (the only change to smallpt): whole-image passes of one sample per
// subpixel (4 spp) until the budget is spent, then the mean of each subpixel
// box of four (without the clamp to [0, 1], a display step that
// would cut the lamp from 12 to 1), written as linear PFM for `ptui`'s reference tools.
int main(int argc, char *argv[]){
  if (argc != 3) { fprintf(stderr, "usage: smallpt SECONDS OUT.pfm\n"); return 2; }
  double budget = atof(argv[1]);
  int w=320, h=240;
  Ray cam(Vec(50,52,295.6), Vec(0,-0.042612,-1).norm());
  Vec cx=Vec(w*.5135/h), cy=(cx%cam.d).norm()*.5135;
  Vec *sub=new Vec[w*h*4];
  // Each row's erand48 state on its own cache line: packed, the two threads' rows share lines
  // and the false sharing costs a third of the throughput.
  const int stride=32;
  unsigned short *seeds=new unsigned short[h*stride];
  for (int y=0; y<h; y++) { seeds[stride*y]=0; seeds[stride*y+1]=0; seeds[stride*y+2]=(unsigned short)(y*y*y); }
  int passes=0;
  double t0 = omp_get_wtime(), t1 = t0;
  while (t1 - t0 < budget) {
#pragma omp parallel for schedule(dynamic, 1)
    for (int y=0; y<h; y++){
      unsigned short *Xi = seeds + stride*y;
      for (int x=0; x<w; x++)
        for (int sy=0; sy<2; sy++)
          for (int sx=0; sx<2; sx++){
            double r1=2*erand48(Xi), dx=r1<1 ? sqrt(r1)-1: 1-sqrt(2-r1);
            double r2=2*erand48(Xi), dy=r2<1 ? sqrt(r2)-1: 1-sqrt(2-r2);
            Vec d = cx*( ( (sx+.5 + dx)/2 + x)/w - .5) + cy*( ( (sy+.5 + dy)/2 + y)/h - .5) + cam.d;
            Vec &s = sub[((h-y-1)*w+x)*4 + sy*2 + sx];
            s = s + radiance(Ray(cam.o+d*140,d.norm()),0,Xi);
          }
    }
    passes++;
    t1 = omp_get_wtime();
  }
  FILE *f = fopen(argv[2], "wb");
  if (!f) { perror(argv[2]); return 1; }
  fprintf(f, "PF\n%d %d\n-1.0\n", w, h);
  for (int row=h-1; row>=0; row--)
    for (int x=0; x<w; x++) {
      Vec c;
      for (int k=0; k<4; k++) {
        Vec m = sub[(row*w+x)*4+k]*(1./passes);
        c = c + m*.25;
      }
      float px[3] = {(float)c.x, (float)c.y, (float)c.z};
      fwrite(px, sizeof(float), 3, f);
    }
  fclose(f);
  fprintf(stderr, "smallpt: %d spp in %.3f s, %.3f M paths/s\n", passes*4, t1-t0,
          (double)w*h*passes*4/(t1-t0)/1e6);
  return 0;
}
