//! Spheres in structure-of-arrays form, tested eight at a time with straight-line code the
//! compiler vectorises: run-time dispatch (`crate::cpu`) to an AVX-512F build (one 8-wide f64
//! operation per step) or an x86-64-v3 build (AVX2: two 4-wide), else the baseline SSE2 code; no
//! `target-cpu` needed.
//! Eight lanes beat four even in AVX2 (benches/HISTORY.md#sphere-lanes). Same arithmetic, in
//! the same order, as [`Sphere::intersect`], so the roots are bit-identical to the scalar test.

use crate::cpu::{avx512_copy, has_avx512f, v3_copy, ShadingCode};
use crate::geometry::Primitive;
use crate::math::{DVec3, Ray};

const LANES: usize = 8;

/// A last group this small is tested one sphere at a time: a vector pass costs the same eight
/// divisions and square roots whether one lane is real or eight, and scalar ones are cheaper.
const SCALAR_TAIL: usize = 2;

#[derive(Clone, Debug, Default)]
pub struct SphereLanes {
    /// Whether this CPU runs the x86-64-v3 / AVX-512F copies: then the same code is run compiled
    /// for 4- or 8-wide f64 vectors, with the same bits (see `crate::cpu`).
    avx2: bool,
    avx512: bool,
    cx: Vec<[f64; LANES]>,
    cy: Vec<[f64; LANES]>,
    cz: Vec<[f64; LANES]>,
    r2: Vec<[f64; LANES]>,
    prim: Vec<[u32; LANES]>,
    /// The spheres after the last full group when there are at most [`SCALAR_TAIL`] of them;
    /// their indices are above every grouped sphere's, so testing them last keeps the
    /// lowest-index-wins order of ties.
    tail: Vec<(crate::geometry::Sphere, u32)>,
    /// Every sphere once, in index order, for [`SphereLanes::closest_batch`], which runs the
    /// lanes across rays instead of across spheres.
    flat: Vec<FlatSphere>,
}

#[derive(Clone, Copy, Debug)]
struct FlatSphere {
    cx: f64,
    cy: f64,
    cz: f64,
    r2: f64,
    prim: u64,
}

/// Rays in structure-of-arrays form for [`SphereLanes::closest_batch`], in groups of [`LANES`];
/// the closest hits are written back beside them. Reused from batch to batch, so a render
/// allocates it once per band of rows.
#[derive(Clone, Debug, Default)]
pub struct RayBatch {
    len: usize,
    /// The rays, [`LANES`] a group, each component in its own column. A push writes each
    /// number straight into its column, read one at a time from the ray: the rays used to be
    /// kept whole and spread into columns before each test, and copying a ray whole read it back
    /// with wide loads from narrower stores still in flight, which stalled
    /// (benches/HISTORY.md#sphere-lanes). Groups past the used ones are spare capacity; lanes
    /// past `len` in the last used group hold stale rays, tested but never read.
    groups: Vec<RayGroup>,
    /// Distance to the closest hit of each ray (t_max when none); padded to whole groups.
    pub t: Vec<f64>,
    /// Primitive of the closest hit (u32::MAX when none); padded to whole groups.
    pub prim: Vec<u32>,
}

#[derive(Clone, Copy, Debug, Default)]
struct RayGroup {
    ox: [f64; LANES],
    oy: [f64; LANES],
    oz: [f64; LANES],
    dx: [f64; LANES],
    dy: [f64; LANES],
    dz: [f64; LANES],
    t_max: [f64; LANES],
}

impl RayBatch {
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Add `ray`, looking for hits in (0, t_max).
    #[inline]
    pub fn push(&mut self, ray: &Ray, t_max: f64) {
        let (g, k) = (self.len / LANES, self.len % LANES);
        if g == self.groups.len() {
            self.groups.push(RayGroup::default());
        }
        let group = &mut self.groups[g];
        group.ox[k] = ray.o.x;
        group.oy[k] = ray.o.y;
        group.oz[k] = ray.o.z;
        group.dx[k] = ray.d.x;
        group.dy[k] = ray.d.y;
        group.dz[k] = ray.d.z;
        group.t_max[k] = t_max;
        self.len += 1;
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    pub fn ray(&self, i: usize) -> Ray {
        assert!(i < self.len);
        let (g, k) = (&self.groups[i / LANES], i % LANES);
        Ray::new(
            DVec3::new(g.ox[k], g.oy[k], g.oz[k]),
            DVec3::new(g.dx[k], g.dy[k], g.dz[k]),
        )
    }

    /// How far ray `i` looks.
    pub fn t_max(&self, i: usize) -> f64 {
        assert!(i < self.len);
        self.groups[i / LANES].t_max[i % LANES]
    }

    /// The groups holding the rays (the last may be partly stale) and the outputs, as many
    /// lanes as the groups once prepared.
    fn split(&mut self) -> (&[RayGroup], &mut [f64], &mut [u32]) {
        let used = self.len.div_ceil(LANES);
        assert!(self.t.len() == used * LANES && self.prim.len() == used * LANES);
        (&self.groups[..used], &mut self.t, &mut self.prim)
    }

    /// Size the outputs to whole groups (each test writes every lane of them).
    #[inline(always)]
    fn prepare(&mut self) {
        let padded = self.len.div_ceil(LANES) * LANES;
        self.t.resize(padded, 0.0);
        self.prim.resize(padded, u32::MAX);
    }
}

impl SphereLanes {
    /// The spheres among `prims`; padding lanes hold a sphere of radius 0 at infinity, which no
    /// ray hits (its discriminant is NaN or negative, never >= 0 with a finite root).
    pub fn new(prims: &[Primitive]) -> Self {
        let mut s = SphereLanes {
            avx2: has_v3(),
            avx512: has_avx512f(),
            ..Default::default()
        };
        let spheres: Vec<(u32, crate::geometry::Sphere)> = prims
            .iter()
            .enumerate()
            .filter_map(|(i, p)| p.shape.as_sphere().map(|sp| (i as u32, *sp)))
            .collect();
        let tail_len = match spheres.len() % LANES {
            n if n <= SCALAR_TAIL => n,
            _ => 0,
        };
        let (grouped, tail) = spheres.split_at(spheres.len() - tail_len);
        s.tail = tail.iter().map(|(i, sp)| (*sp, *i)).collect();
        s.flat = spheres
            .iter()
            .map(|(i, sp)| FlatSphere {
                cx: sp.center.x,
                cy: sp.center.y,
                cz: sp.center.z,
                r2: sp.radius * sp.radius,
                prim: *i as u64,
            })
            .collect();
        for chunk in grouped.chunks(LANES) {
            let mut cx = [f64::INFINITY; LANES];
            let mut cy = [f64::INFINITY; LANES];
            let mut cz = [f64::INFINITY; LANES];
            let mut r2 = [0.0; LANES];
            let mut prim = [u32::MAX; LANES];
            for (k, (i, sp)) in chunk.iter().enumerate() {
                cx[k] = sp.center.x;
                cy[k] = sp.center.y;
                cz[k] = sp.center.z;
                r2[k] = sp.radius * sp.radius;
                prim[k] = *i;
            }
            s.cx.push(cx);
            s.cy.push(cy);
            s.cz.push(cz);
            s.r2.push(r2);
            s.prim.push(prim);
        }
        s
    }

    pub fn len_groups(&self) -> usize {
        self.cx.len()
    }

    /// Nearest sphere hit in (0, t_max): (t, primitive index).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<(f64, u32)> {
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: `avx512` is only set when the running CPU reports AVX-512F.
            return unsafe { self.intersect_avx512(ray, t_max) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is only set when the running CPU runs x86-64-v3 code.
            return unsafe { self.intersect_avx2(ray, t_max) };
        }
        self.intersect_portable(ray, t_max)
    }

    avx512_copy! {
        unsafe fn intersect_avx512(&self, ray: &Ray, t_max: f64) -> Option<(f64, u32)> {
            self.intersect_portable(ray, t_max)
        }
    }

    v3_copy! {
        unsafe fn intersect_avx2(&self, ray: &Ray, t_max: f64) -> Option<(f64, u32)> {
            self.intersect_portable(ray, t_max)
        }
    }

    #[inline(always)]
    fn intersect_portable(&self, ray: &Ray, t_max: f64) -> Option<(f64, u32)> {
        let (ox, oy, oz) = (ray.o.x, ray.o.y, ray.o.z);
        let (dx, dy, dz) = (ray.d.x, ray.d.y, ray.d.z);
        let mut best = t_max;
        let mut best_prim = u32::MAX;
        for g in 0..self.cx.len() {
            let (cx, cy, cz, r2) = (&self.cx[g], &self.cy[g], &self.cz[g], &self.r2[g]);
            let mut t = [f64::INFINITY; LANES];
            for k in 0..LANES {
                let fx = ox - cx[k];
                let fy = oy - cy[k];
                let fz = oz - cz[k];
                let b = fx * dx + fy * dy + fz * dz;
                let lx = fx - dx * b;
                let ly = fy - dy * b;
                let lz = fz - dz * b;
                let disc = r2[k] - (lx * lx + ly * ly + lz * lz);
                let c = (fx * fx + fy * fy + fz * fz) - r2[k];
                let q = -b - disc.max(0.0).sqrt().copysign(b);
                let t0 = c / q;
                let t1 = q;
                let lo = t0.min(t1);
                let hi = t0.max(t1);
                let root = if lo > 0.0 { lo } else { hi };
                // NaN roots (q = 0, padding lanes) fail the comparisons and are dropped.
                t[k] = if disc >= 0.0 && root > 0.0 {
                    root
                } else {
                    f64::INFINITY
                };
            }
            // Faster than lane-wise blends and a final reduction (benches/HISTORY.md#sphere-lanes).
            for (tk, prim) in t.iter().zip(&self.prim[g]) {
                if *tk < best {
                    best = *tk;
                    best_prim = *prim;
                }
            }
        }
        for (sphere, prim) in &self.tail {
            if let Some(t) = sphere.intersect(ray, best) {
                best = t;
                best_prim = *prim;
            }
        }
        (best_prim != u32::MAX).then_some((best, best_prim))
    }
}

impl SphereLanes {
    /// The closest sphere hit in (0, its t_max) of every ray of `batch`, into `batch.t` and
    /// `batch.prim`: the answer of [`SphereLanes::intersect`] for each ray, bit for bit (same
    /// arithmetic; spheres in index order with a strict `<`, so ties go to the lowest index),
    /// but with the lanes across eight rays, which share no dependency chain, and one sphere at
    /// a time: no horizontal minimum, no padding spheres.
    pub fn closest_batch(&self, batch: &mut RayBatch) {
        #[cfg(target_arch = "x86_64")]
        if self.avx512 {
            // SAFETY: `avx512` is only set when the running CPU reports AVX-512F.
            return unsafe { self.closest_batch_avx512(batch) };
        }
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is only set when the running CPU runs x86-64-v3 code.
            return unsafe { self.closest_batch_avx2(batch) };
        }
        self.closest_batch_portable(batch)
    }

    avx512_copy! {
        unsafe fn closest_batch_avx512(&self, batch: &mut RayBatch) {
            self.closest_batch_portable(batch)
        }
    }

    v3_copy! {
        unsafe fn closest_batch_avx2(&self, batch: &mut RayBatch) {
            self.closest_batch_portable(batch)
        }
    }

    /// The loop every copy compiles.
    #[inline(always)]
    fn closest_batch_portable(&self, batch: &mut RayBatch) {
        batch.prepare();
        let (groups, t, prim) = batch.split();
        let outputs = t.chunks_exact_mut(LANES).zip(prim.chunks_exact_mut(LANES));
        for (g, (t_out, prim_out)) in groups.iter().zip(outputs) {
            let (ox, oy, oz, dx, dy, dz) = (&g.ox, &g.oy, &g.oz, &g.dx, &g.dy, &g.dz);
            let mut best = g.t_max;
            let mut best_prim = [u64::MAX; LANES];
            for s in &self.flat {
                let mut fx = [0.0; LANES];
                let mut fy = [0.0; LANES];
                let mut fz = [0.0; LANES];
                let mut b = [0.0; LANES];
                let mut disc = [0.0; LANES];
                for k in 0..LANES {
                    fx[k] = ox[k] - s.cx;
                    fy[k] = oy[k] - s.cy;
                    fz[k] = oz[k] - s.cz;
                    b[k] = fx[k] * dx[k] + fy[k] * dy[k] + fz[k] * dz[k];
                    let lx = fx[k] - dx[k] * b[k];
                    let ly = fy[k] - dy[k] * b[k];
                    let lz = fz[k] - dz[k] * b[k];
                    disc[k] = s.r2 - (lx * lx + ly * ly + lz * lz);
                }
                // Most of the eight rays miss a small sphere: when all do, the square root and
                // the division (the costly part of a vector pass) change nothing.
                if !disc.iter().any(|d| *d >= 0.0) {
                    continue;
                }
                // Written so that each ray's closest hit stays in registers: a choice between
                // `s.prim` and `best_prim[k]` as two loads became a gather (`vpgatherqq`), and a
                // distance kept only where closer a masked store the next sphere's load could not
                // forward from (benches/HISTORY.md#sphere-lanes). The minimum gives the same
                // bits: `cand` is never NaN and ties are equal values.
                let prim = s.prim;
                for k in 0..LANES {
                    let (fx, fy, fz, b, disc) = (fx[k], fy[k], fz[k], b[k], disc[k]);
                    let c = (fx * fx + fy * fy + fz * fz) - s.r2;
                    let q = -b - disc.max(0.0).sqrt().copysign(b);
                    let t0 = c / q;
                    let lo = t0.min(q);
                    let hi = t0.max(q);
                    let root = if lo > 0.0 { lo } else { hi };
                    let cand = if disc >= 0.0 && root > 0.0 {
                        root
                    } else {
                        f64::INFINITY
                    };
                    best_prim[k] = if cand < best[k] { prim } else { best_prim[k] };
                    best[k] = best[k].min(cand);
                }
            }
            t_out.copy_from_slice(&best);
            for (out, p) in prim_out.iter_mut().zip(best_prim) {
                *out = p as u32;
            }
        }
    }
}

/// Whether the x86-64-v3 copies run here (the row tracer's test, in `crate::cpu`).
fn has_v3() -> bool {
    ShadingCode::detect() == ShadingCode::V3
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Shape;
    use crate::geometry::Sphere;
    use crate::math::DVec3;
    use crate::sampling::{warp, Rng};

    /// The lanes give exactly the scalar test's answer: same sphere, same bits.
    #[test]
    fn lanes_agree_with_the_scalar_test() {
        let mut rng = Rng::new(9);
        let mut prims = Vec::new();
        for i in 0..11 {
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 10.0 - 5.0;
            let r = if i == 3 {
                1e5
            } else {
                0.2 + 2.0 * rng.next_f64()
            };
            let c = if i == 3 {
                c + DVec3::X * (1e5 + 8.0)
            } else {
                c
            };
            prims.push(Primitive {
                shape: Shape::Sphere(Sphere::new(c, r)),
                material: 0,
                light: None,
            });
        }
        // A twin of sphere 0: every ray that meets one meets both at the same root, and the
        // lower index must win.
        prims.push(prims[0]);
        let lanes = SphereLanes::new(&prims);
        assert_eq!(lanes.len_groups(), 12usize.div_ceil(LANES));
        // Batches of every length around the group size, each ray with its own t_max.
        let mut batch = RayBatch::default();
        for len in [0, 1, 7, 8, 9, 17, 300] {
            batch.clear();
            let rays: Vec<(Ray, f64)> = (0..len)
                .map(|_| {
                    let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 12.0;
                    let d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
                    let t_max = if rng.next_f64() < 0.3 {
                        rng.next_f64() * 6.0
                    } else {
                        f64::INFINITY
                    };
                    (Ray::new(o - 6.0, d), t_max)
                })
                .collect();
            for (ray, t_max) in &rays {
                batch.push(ray, *t_max);
            }
            lanes.closest_batch(&mut batch);
            assert_eq!(batch.len(), len);
            for (i, (ray, t_max)) in rays.iter().enumerate() {
                let scalar = crate::accel::flat::intersect(&prims, ray, *t_max);
                let want = scalar.map_or((*t_max, u32::MAX), |h| (h.t, h.prim));
                assert_eq!(
                    (batch.t[i].to_bits(), batch.prim[i]),
                    (want.0.to_bits(), want.1)
                );
                assert_eq!(batch.ray(i).o, ray.o);
            }
            // Every copy this CPU can run gives the same bits.
            let (t, prim) = (batch.t.clone(), batch.prim.clone());
            lanes.closest_batch_portable(&mut batch);
            assert_eq!((&t, &prim), (&batch.t, &batch.prim));
            #[cfg(target_arch = "x86_64")]
            if has_v3() {
                // SAFETY: checked just above.
                unsafe { lanes.closest_batch_avx2(&mut batch) };
                assert_eq!((&t, &prim), (&batch.t, &batch.prim));
            }
            #[cfg(target_arch = "x86_64")]
            if has_avx512f() {
                // SAFETY: checked just above.
                unsafe { lanes.closest_batch_avx512(&mut batch) };
                assert_eq!((&t, &prim), (&batch.t, &batch.prim));
            }
        }
        // 9 spheres: one group of eight and one tested alone.
        let nine = SphereLanes::new(&prims[..9]);
        assert_eq!((nine.len_groups(), nine.tail.len()), (1, 1));
        for _ in 0..20_000 {
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 12.0 - 6.0;
            let d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            let ray = Ray::new(o, d);
            let t_max = if rng.next_f64() < 0.2 {
                3.0
            } else {
                f64::INFINITY
            };
            let scalar = crate::accel::flat::intersect(&prims, &ray, t_max).map(|h| (h.t, h.prim));
            assert_eq!(lanes.intersect(&ray, t_max), scalar);
            let scalar9 =
                crate::accel::flat::intersect(&prims[..9], &ray, t_max).map(|h| (h.t, h.prim));
            assert_eq!(nine.intersect(&ray, t_max), scalar9);
            assert_eq!(lanes.intersect_portable(&ray, t_max), scalar);
            #[cfg(target_arch = "x86_64")]
            if has_v3() {
                // SAFETY: checked just above.
                assert_eq!(unsafe { lanes.intersect_avx2(&ray, t_max) }, scalar);
            }
        }
    }
}
