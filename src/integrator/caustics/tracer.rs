//! The light tracer: its set-up for a scene, and the light paths of a pass, traced by chunk,
//! splatted to the camera and their ends kept for the joins.

use super::emitters::{emission, emission_point, sphere_region, Emitter, MAX_TARGETS};
use super::reservoir::Reservoir;
use super::vertices::{large_passes, merge};
use super::{
    encode_unit, CausticVertex, LightSide, PassSplats, Region, JOIN_ATTEMPT, RESERVOIR_SALT,
    ROW_WINDOW, SALT, VERTICES_PER_PATH,
};
use crate::camera::Camera;
use crate::cpu::{v3_copy, ShadingCode};
use crate::geometry::{spawn_origin, Hit, Sphere};
use crate::light::Light;
use crate::math::{luminance, DVec3, Ray};
use crate::sampling::Rng;
use crate::scene::Scene;
use crate::settings::{Caustics, IntegratorKind, RenderSettings};
use rayon::prelude::*;

/// Light paths per pixel and pass. Error per second is flat from 0.025 to 0.05; 0.035 sits in
/// it with less time per path (benches/HISTORY.md#light-paths-per-pixel).
pub const LIGHT_PATHS_PER_PIXEL: f64 = 0.035;

/// Paths per parallel task (and per random-stream block).
const CHUNK: u64 = 2048;

#[derive(Clone, Debug)]
pub struct CausticTracer {
    pub(super) emitters: Vec<Emitter>,
    /// Per light index: its emitter (and so its region), if the tracer starts paths there.
    pub(super) emitter_of: Vec<Option<usize>>,
    pub(super) targets: Vec<Sphere>,
    camera: Camera,
    width: u32,
    height: u32,
    light_paths: u64,
    /// [`CausticTracer::large_passes`], fixed with `light_paths` and read at every camera
    /// vertex, where recomputing it cost (benches/HISTORY.md#caustic-join-bounds).
    large: bool,
    /// Pixel area on the image plane at distance 1, times the light paths per pass.
    pixel_norm: f64,
    /// Fraction of the pilot's light paths that reached the camera.
    pilot_rate: f64,
    /// Whether camera vertices are joined to the light paths' ends (`caustics = "light"`).
    pub connect: bool,
    /// Why `caustics = "light"` was asked for but the joins are off, for the summary.
    no_joins_why: Option<&'static str>,
    /// Connections worth less than this (radiance) play roulette for their shadow ray.
    pub connect_threshold: f64,
}

impl CausticTracer {
    /// The tracer for `scene` under `settings`, or why there is none.
    pub fn new(scene: &Scene, settings: &RenderSettings) -> Result<Self, String> {
        if settings.caustics == Caustics::Path {
            return Err("path-traced (caustics = \"path\")".into());
        }
        if settings.integrator != IntegratorKind::Path {
            return Err(format!(
                "not light-traced ({} integrator)",
                settings.integrator.name()
            ));
        }
        if settings.max_depth.is_some() {
            return Err("path-traced (a depth limit is set)".into());
        }
        if settings.strategy != crate::settings::Strategy::Mis {
            // Its joins are weighed against the camera paths by MIS.
            return Err(format!(
                "path-traced (strategy {}, not mis)",
                settings.strategy.name()
            ));
        }
        let lens = scene
            .camera
            .with_lens_settings(settings.aperture, settings.focus_distance);
        if lens.has_lens() {
            // Its splats are projected through a pinhole; through a lens a light vertex reaches
            // a disc of pixels, which the joins do not sample.
            return Err("path-traced (a thin-lens camera)".into());
        }
        if scene.environment.is_some() {
            // Light paths start on emitters; one from the map would start on a disc at
            // infinity, which the tracer does not sample.
            return Err("path-traced (an environment map)".into());
        }
        if scene.lights.is_empty() {
            return Err("none (no emitters)".into());
        }
        if scene.textures.is_some() {
            // Its vertices' BSDFs would need the textures looked up at each light-path end.
            return Err("path-traced (the scene has textures)".into());
        }
        if let Some(m) = scene.materials.iter().find(|m| !m.kind.is_smallpt()) {
            // Its splats and joins assume diffuse, mirror and smooth glass vertices: a glossy
            // one has neither a bounded BSDF for the joins' roulette nor a delta chain's
            // bookkeeping. Glossy paths stay with the camera paths, which handle them by MIS.
            return Err(format!(
                "path-traced (the light tracer handles diffuse, mirror and glass; the scene \
                 has {})",
                m.kind.describe()
            ));
        }
        let mut targets = Vec::new();
        for p in scene.prims.iter() {
            if !scene.materials[p.material as usize].is_delta() {
                continue;
            }
            match p.shape.as_sphere() {
                Some(s) => targets.push(*s),
                None => return Err("path-traced (a mirror or glass object is not a sphere)".into()),
            }
        }
        if targets.is_empty() {
            return Err("none (no mirror or glass objects)".into());
        }
        if targets.len() > MAX_TARGETS {
            return Err(format!(
                "path-traced ({} mirror/glass spheres, more than {MAX_TARGETS})",
                targets.len()
            ));
        }
        let mut emitters = Vec::new();
        let mut emitter_of = vec![None; scene.lights.len()];
        for (i, light) in scene.lights.lights.iter().enumerate() {
            let (region, area, sides) = match light {
                Light::Sphere(l) => {
                    let (region, area) = sphere_region(l, &targets);
                    (region, area, 1.0)
                }
                Light::Triangle(l) => (
                    Region::Triangle {
                        two_sided: l.two_sided,
                    },
                    l.triangle.area(),
                    l.sides(),
                ),
            };
            let power = sides * area * luminance(emission(light)).max(0.0);
            if power > 0.0 && power.is_finite() {
                emitter_of[i] = Some(emitters.len());
                emitters.push(Emitter {
                    light: i,
                    region,
                    pmf: power,
                    area,
                });
            }
        }
        let total: f64 = emitters.iter().map(|e| e.pmf).sum();
        if emitters.is_empty() || !(total > 0.0 && total.is_finite()) {
            return Err("none (no emitter with finite power)".into());
        }
        for e in &mut emitters {
            e.pmf /= total;
        }
        let (w, h) = (settings.width, settings.height);
        let pixels = w as f64 * h as f64;
        let light_paths = ((pixels * LIGHT_PATHS_PER_PIXEL).ceil() as u64).max(1);
        let tan = scene.camera.tan_half_vfov;
        let pixel_area = (2.0 * tan / h as f64).powi(2);
        let tracer = CausticTracer {
            emitters,
            emitter_of,
            targets,
            camera: scene.camera,
            width: w,
            height: h,
            light_paths,
            large: large_passes(light_paths),
            pixel_norm: pixel_area * light_paths as f64,
            pilot_rate: 0.0,
            // Joins would need y's shading normal in the stored vertex: scenes with vertex
            // normals keep the light paths' direct splats only.
            connect: settings.caustics == Caustics::Light && !scene.has_shading_normals(),
            no_joins_why: (settings.caustics == Caustics::Light && scene.has_shading_normals())
                .then_some(
                    "the scene has smooth meshes, whose shading normals the light-path ends do \
                     not keep",
                ),
            connect_threshold: 0.0,
        };
        let (pilot_rate, connect_threshold) = tracer.pilot(scene, settings)?;
        Ok(CausticTracer {
            pilot_rate,
            connect_threshold,
            ..tracer
        })
    }

    /// One line for summaries.
    pub fn describe(&self) -> String {
        let joins = if self.connect {
            // Large passes change how the joins pick their ends (see `large_passes`).
            let windows = if self.large_passes() {
                format!(", picked from windows of {ROW_WINDOW} ends per row")
            } else {
                String::new()
            };
            format!(
                "their ends joined to camera vertices by MIS, each join traced with \
                 probability min({}, worth / {:.3}){windows}",
                JOIN_ATTEMPT, self.connect_threshold
            )
        } else if let Some(why) = self.no_joins_why {
            format!("seen directly only: no joins to camera vertices, as {why}")
        } else {
            "seen directly only (caustics = \"light-direct\")".to_string()
        };
        format!(
            "light-traced ({} paths per pass towards {} mirror/glass sphere(s); {:.0}% of a \
             pilot's paths reached the camera; {joins})",
            self.light_paths,
            self.targets.len(),
            100.0 * self.pilot_rate,
        )
    }

    /// Trace this pass's light paths on the current rayon pool.
    pub fn trace_pass(&self, scene: &Scene, seed: u64, pass: u32) -> PassSplats {
        let chunks = self.light_paths.div_ceil(CHUNK);
        let parts: Vec<PassSplats> = (0..chunks)
            .into_par_iter()
            .map(|c| self.chunk(scene, seed, pass, c))
            .collect();
        merge(parts)
    }

    /// [`CausticTracer::trace_pass`] on the calling thread alone (the same splats and ends):
    /// for a thread that traces a pass's light paths between its bands of rows, while the
    /// others, busy with theirs, would take none of its chunks anyway.
    pub fn trace_pass_here(&self, scene: &Scene, seed: u64, pass: u32) -> PassSplats {
        let chunks = self.light_paths.div_ceil(CHUNK);
        merge(
            (0..chunks)
                .map(|c| self.chunk(scene, seed, pass, c))
                .collect(),
        )
    }

    #[inline]
    fn chunk(&self, scene: &Scene, seed: u64, pass: u32, c: u64) -> PassSplats {
        match ShadingCode::detect() {
            // SAFETY: `ShadingCode::detect` found every feature the copy is compiled for.
            #[cfg(target_arch = "x86_64")]
            ShadingCode::V3 => unsafe { self.trace_chunk_v3(scene, seed, pass, c) },
            _ => self.trace_chunk(scene, seed, pass, c),
        }
    }

    /// Chunk `c` of pass `pass`'s light paths.
    #[inline(always)]
    fn trace_chunk(&self, scene: &Scene, seed: u64, pass: u32, c: u64) -> PassSplats {
        let mut out = PassSplats::default();
        let end = ((c + 1) * CHUNK).min(self.light_paths);
        // At least one: a chunk whose ends were all dropped could never be picked, and
        // its share of the joins would be lost (a last chunk of one path, a tiny image).
        let cap = ((end - c * CHUNK) as f64 * VERTICES_PER_PATH) as usize;
        let mut reservoir = Reservoir::new(
            cap.max(1),
            Rng::for_sample(seed ^ SALT ^ RESERVOIR_SALT, c, pass as u64),
        );
        for i in c * CHUNK..end {
            let mut rng = Rng::for_sample(seed ^ SALT, i, pass as u64);
            self.trace(scene, &mut rng, &mut out, &mut reservoir);
            out.paths += 1;
        }
        reservoir.close(&mut out);
        out
    }

    v3_copy! {
        /// [`CausticTracer::trace_chunk`] compiled for x86-64-v3 ([`ShadingCode`]).
        unsafe fn trace_chunk_v3(
            &self,
            scene: &Scene,
            seed: u64,
            pass: u32,
            c: u64,
        ) -> PassSplats {
            self.trace_chunk(scene, seed, pass, c)
        }
    }

    /// Whether a pass's kept light-path ends outgrow the core's cache (more than 1 MiB at
    /// [`VERTICES_PER_PATH`]: images of more than ~280k pixels). Camera paths then pick the end
    /// each vertex joins a ray ahead and prefetch it; on smaller passes the ends stay cached and
    /// the picks are made at the vertex, as the draw order of the smaller images always was.
    #[inline]
    pub fn large_passes(&self) -> bool {
        self.large
    }

    /// One light path: emit towards a specular sphere, follow the specular chain, splat the
    /// first diffuse hit y seen by the camera; then bounce once off y, and if that reaches another
    /// diffuse hit x through one or more specular bounces, splat x too (a caustic of a caustic:
    /// cornell's floor caustic seen through the glass ball from the ceiling and walls).
    #[inline(always)]
    pub(super) fn trace(
        &self,
        scene: &Scene,
        rng: &mut Rng,
        out: &mut PassSplats,
        kept: &mut Reservoir,
    ) {
        let e = *self.pick_emitter(rng.next_f64());
        let light = &scene.lights.lights[e.light];
        let u = (rng.next_f64(), rng.next_f64());
        let Some((y0, n0, err0, area_pdf, le)) = emission_point(light, e.region, u) else {
            return;
        };
        let Some((w, dir_pdf)) =
            self.emission_direction(y0, (rng.next_f64(), rng.next_f64(), rng.next_f64()))
        else {
            return;
        };
        let cos0 = w.dot(n0);
        let cos0 = match e.region {
            Region::Triangle { two_sided: true } => cos0.abs(),
            // Sphere regions and one-sided triangles cover emission from their front alone.
            _ => cos0,
        };
        if cos0 <= 0.0 {
            return;
        }
        let mut beta = le * (cos0 / (e.pmf * area_pdf * dir_pdf));
        if !beta.is_finite() {
            return;
        }
        let mut side = LightSide::new(e.pmf * area_pdf * dir_pdf, cos0);
        let mut ray = Ray::new(spawn_origin(y0, n0, err0, w), w);
        let mut bounces = 0u32;
        // Specular bounces since the light or the diffuse vertex y.
        let mut run = 0u32;
        let mut throughput = DVec3::ONE;
        loop {
            out.rays += 1;
            let Some(hit) = scene.intersect(&ray, f64::INFINITY) else {
                return;
            };
            let m = scene.material(&hit);
            let wo = -ray.d;
            if !m.is_delta() {
                if run == 0 {
                    return;
                }
                self.splat(scene, &hit, wo, beta, out);
                if self.connect {
                    let vertex = CausticVertex {
                        p: hit.p.to_array(),
                        n: encode_unit(hit.n),
                        wo: encode_unit(wo),
                        alpha: beta.as_vec3().to_array(),
                        err: hit.err as f32,
                        material: scene.prims[hit.prim as usize].material,
                        p_light: side.here() as f32,
                    };
                    if vertex.alpha.iter().all(|a| a.is_finite())
                        && vertex.p_light.is_finite()
                        && vertex.p_light > 0.0
                    {
                        kept.offer(vertex);
                    }
                }
                // The second diffuse vertex ends the path; the first bounces once more.
                if side.past_y() {
                    return;
                }
            }
            let nn = hit.normals();
            // Light carries importance: at a shading normal, the adjoint BSDF's sample.
            let Some(bs) =
                m.sample_adjoint(wo, nn, rng.next_f64(), (rng.next_f64(), rng.next_f64()))
            else {
                return;
            };
            let (cos_in, cos_out) = (hit.n.dot(wo).abs(), hit.n.dot(bs.wi).abs());
            if m.is_delta() {
                side.specular(cos_in, cos_out);
                run += 1;
            } else {
                side.leave_y(cos_in, bs.pdf, m.eval(bs.wi, wo, nn).pdf, cos_out);
                run = 0;
            }
            // Light carries importance, for which radiance's compression across a refraction
            // (in `weight`) does not apply: `eta_scale` undoes it.
            let weight = bs.weight * bs.eta_scale;
            beta *= weight;
            throughput *= weight;
            bounces += 1;
            // Roulette on the dimensionless throughput, not on beta, which carries the light's
            // flux and so the scene's scale (at 1e-3 it would end nearly every path).
            let Some(q) = crate::integrator::roulette_survival(throughput, bounces, rng.next_f64())
            else {
                return;
            };
            throughput /= q;
            beta /= q;
            ray = Ray::new(spawn_origin(hit.p, hit.n, hit.err, bs.wi), bs.wi);
        }
    }

    /// Connect a diffuse hit to the camera and record its contribution to the pixel it lands in:
    /// beta f cos_y We / pdf_camera = beta f cos_y / (A_pixel cos^3 theta_c dist^2), over the
    /// light paths of the pass (the box-filtered pixel is 1 / A_pixel times the integral of
    /// the radiance over its footprint on the image plane at distance 1).
    #[inline(always)]
    fn splat(&self, scene: &Scene, hit: &Hit, wo: DVec3, beta: DVec3, out: &mut PassSplats) {
        let cam = &self.camera;
        let to_cam = cam.position - hit.p;
        let dist2 = to_cam.length_squared();
        let dist = dist2.sqrt();
        if dist.is_nan() || dist <= cam.near {
            return;
        }
        let d = -to_cam / dist;
        let Some((fx, fy)) = cam.raster(self.width, self.height, d) else {
            return;
        };
        let cos_c = d.dot(cam.forward);
        let wi = -d;
        // Importance transport: at a shading normal, the adjoint BSDF (f cos as ever on flat
        // surfaces).
        let f_cos = scene.material(hit).eval_adjoint(wo, wi, hit.normals());
        if f_cos.max_element() <= 0.0 {
            return;
        }
        // Visible if nothing lies between the hit and where camera rays start (`near`).
        let o = spawn_origin(hit.p, hit.n, hit.err, wi);
        let start = cam.position + d * cam.near;
        let seg = start - o;
        let len = seg.length();
        out.rays += 1;
        if scene.intersect(&Ray::new(o, seg / len), len).is_some() {
            return;
        }
        let v = beta * f_cos / (self.pixel_norm * cos_c * cos_c * cos_c * dist2);
        if !v.is_finite() {
            return;
        }
        let pixel = fy as u32 * self.width + fx as u32;
        out.splats.push((pixel, v.as_vec3().to_array()));
    }
}

/// A tracer with no emitter and no target, for the joins' tests.
#[cfg(test)]
pub(super) fn dummy_tracer() -> CausticTracer {
    CausticTracer {
        emitters: Vec::new(),
        emitter_of: Vec::new(),
        targets: Vec::new(),
        camera: crate::scene::load("cornell").expect("built-in").camera,
        width: 1,
        height: 1,
        light_paths: 1,
        large: false,
        pixel_norm: 1.0,
        pilot_rate: 0.0,
        connect: true,
        no_joins_why: None,
        connect_threshold: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The light tracer's x86-64-v3 copy leaves the same splats and ends, bit for bit, as the
    /// portable one (where this CPU can run it).
    #[test]
    fn the_fast_copy_of_a_chunk_matches_the_portable_one() {
        #[cfg(target_arch = "x86_64")]
        if ShadingCode::detect() == ShadingCode::V3 {
            for name in ["cornell", "cornell-small-light"] {
                let scene = crate::scene::load(name).expect("built-in scene");
                let mut settings = RenderSettings::merged(&[&scene.render]);
                (settings.width, settings.height) = (64, 48);
                let tracer = CausticTracer::new(&scene, &settings).expect("a tracer");
                for (pass, c) in [(0, 0), (3, 0)] {
                    let portable = tracer.trace_chunk(&scene, 9, pass, c);
                    // SAFETY: the CPU has the features (checked above).
                    let fast = unsafe { tracer.trace_chunk_v3(&scene, 9, pass, c) };
                    assert!(portable.paths > 0 && !portable.splats.is_empty());
                    assert_eq!(
                        format!("{portable:?}"),
                        format!("{fast:?}"),
                        "{name} {pass}"
                    );
                }
            }
        }
    }
}
