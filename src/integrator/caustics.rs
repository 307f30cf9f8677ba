//! Light-traced caustics for the `path` integrator: the paths camera -> diffuse -> one or more
//! mirror/glass bounces -> light, a caustic seen directly. Camera paths find them only when a
//! BSDF-sampled direction happens to reach the light through the specular chain, which for a
//! small light is rare and bright: fireflies, most of the remaining error on `cornell` and nearly
//! all of it on `cornell-small-light`. Traced from the light instead (emit towards the specular
//! spheres, follow the specular chain, connect the first diffuse hit to the camera) every path
//! contributes (pbrt's light tracer, the t = 1 strategy of BDPT).
//!
//! The two estimators split path space, so nothing is counted twice and nothing is lost: the
//! light tracer covers exactly the paths whose light vertex is in an emitter's [`Region`], left
//! outwards, reach a diffuse surface through at least one specular bounce and are seen directly
//! from the camera, and those that go on from that first diffuse vertex y with one bounce through
//! one or more specular bounces to a diffuse x seen directly (a caustic of a caustic: on
//! `cornell`, the floor's caustic seen through the glass ball from the ceiling and the walls,
//! fireflies of 27 that were a halo of error around the lamp); the camera paths skip precisely
//! those ([`CausticTracer::covers`] at the light, `PathState::caustic_end` for the shape) and keep
//! everything else. The tracer's emission directions are drawn only towards the scene's specular
//! spheres, which is complete because every path it must cover starts by hitting one; so it is
//! used only when all delta materials sit on spheres (a mirror mesh turns it off, as does a depth
//! limit, which the split would have to count against).
//!
//! Where a caustic is seen after a bounce the camera paths and joins share it by MIS: camera
//! vertices join one of the pass's light-path ends, the first diffuse hit y (light -> chain ->
//! y -> x) or the second one x' (light -> chain -> y -> chain -> x' -> x: on `cornell-small-light`
//! the floor's caustic through the glass ball again, seen after a bounce, 97% of its squared
//! error as fireflies of 900 before these joins). A pass keeps at most
//! [`VERTICES_PER_PATH`] ends per light path, a uniform sample per chunk, and a join picks among
//! all the ends left, kept or not, with equal probability. A camera vertex attempts its join
//! with probability [`JOIN_ATTEMPT`] and plays a roulette on the join's worth (both divided out).
//!
//! Each pass traces [`LIGHT_PATHS_PER_PIXEL`] x pixels light paths with their own random streams
//! and adds the splats landing in a pixel to that pixel's camera sample of the same pass: every
//! pass stays one independent, unbiased sample per pixel, so the film's means, variances and
//! half-buffer error estimates stay valid. Splats are gathered per chunk of paths and sorted by
//! pixel, so the sum is the same bit for bit whatever the thread count.

use crate::camera::Camera;
use crate::cpu::{v3_copy, ShadingCode};
use crate::geometry::{spawn_origin, Hit, Sphere};
use crate::light::{sphere::on_cap, Light};
use crate::math::{luminance, DVec3, Frame, Ray};
use crate::sampling::{warp, Rng, Sampler, SamplerKind};
use crate::scene::Scene;
use crate::settings::{Caustics, IntegratorKind, RenderSettings};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Light paths per pixel and pass. Error per second is flat from 0.025 to 0.05; 0.035 sits in
/// it with less time per path (benches/HISTORY.md#light-paths-per-pixel).
pub const LIGHT_PATHS_PER_PIXEL: f64 = 0.035;

/// The largest f64 below 1.
const ONE_BELOW: f64 = 1.0 - f64::EPSILON / 2.0;

/// Paths per parallel task (and per random-stream block).
const CHUNK: u64 = 2048;

/// At most this many specular spheres are aimed at; beyond, the per-path cone set costs too much
/// and the tracer stays off.
const MAX_TARGETS: usize = 16;

/// Salt separating the light paths' random streams from the camera paths'.
const SALT: u64 = 0x6c69_6768_7470_6174;

/// Salt of the reservoirs' streams, which choose the vertices kept.
const RESERVOIR_SALT: u64 = 0x7265_7365_7276_6f69;
/// Keeps the rows' join windows ([`CausticPass::for_row`]) apart from both.
const WINDOW_SALT: u64 = 0x7769_6e64_6f77_7321;

/// See [`CausticTracer::large_passes`].
const LARGE_PASS_BYTES: f64 = 1024.0 * 1024.0;

/// Light paths of the pilot run that decides whether the tracer is worth having.
const PILOT_PATHS: u64 = 4096;

/// The pilot must see at least this fraction of its paths reach the camera: a light mostly
/// hidden from the scene (a huge sphere behind a wall it does not cross) would otherwise start
/// nearly all its paths where they can never arrive, and its few arrivals would be fireflies.
const PILOT_MIN_HIT_RATE: f64 = 0.01;

/// Camera paths of the pilot that sets the connections' roulette threshold.
const PILOT_CAMERA_PATHS: u64 = 4096;

/// A connection to a caustic vertex whose unoccluded value is below this share of the image's
/// mean luminance traces its shadow ray with probability value / threshold (and is divided by
/// it). What the joins cost is the attempts (picking an end, its bound), and a higher threshold
/// ends more of them at the first bound; 1.0 had the best error x time
/// (benches/HISTORY.md#join-roulette-threshold).
const CONNECT_ROULETTE_SHARE: f64 = 1.0;

/// The chance a camera vertex attempts its join at all; an attempt that goes ahead plays the
/// roulette above against `JOIN_ATTEMPT` x the threshold and is divided by `JOIN_ATTEMPT` too.
/// A join worth w is then traced with probability min(JOIN_ATTEMPT, w / threshold): for the
/// joins worth less than JOIN_ATTEMPT x the threshold, nearly all of them, the same chance and
/// weight as without it, while four attempts in five now end before an end is picked, loaded
/// and bounded; only the few worth more are traced less often (and weigh more). Set by error x
/// time on cornell and cornell-small-light (benches/HISTORY.md#join-attempt).
pub const JOIN_ATTEMPT: f64 = 0.2;

/// Where on an emitter the light tracer starts paths (it covers emission from there, outwards).
#[derive(Clone, Copy, Debug)]
pub enum Region {
    /// All of a sphere, left outwards.
    Sphere,
    /// A sphere's cap n . axis >= 1 - h (n the outward normal), left outwards: the part of a
    /// light cut by another sphere's surface that lies on the specular objects' side.
    Cap { axis: DVec3, h: f64 },
    /// A triangle: its front face, or both faces of a two-sided emitter.
    Triangle { two_sided: bool },
}

#[derive(Clone, Copy, Debug)]
struct Emitter {
    light: usize,
    region: Region,
    /// Probability of starting a path here.
    pmf: f64,
    /// The region's area: the start point's density is 1 / area. A two-sided triangle's is its
    /// area once, not twice: its points are drawn once and its directions cover both faces.
    area: f64,
}

/// A splat: pixel index and the value added to that pixel's sample of the pass.
pub type Splat = (u32, [f32; 3]);

/// Where a light path's specular chain ended on a diffuse surface (y): what a camera vertex x
/// needs to connect to it (light -> specular -> y -> x -> camera, a caustic seen after a bounce)
/// and to weigh that connection by MIS against the camera path that reaches the light from x
/// through y and the same chain. Single precision where only a weight or a colour depends on it.
#[derive(Clone, Copy, Debug)]
pub struct CausticVertex {
    /// The position, as an array: a `DVec3` is padded to 32 bytes.
    pub p: [f64; 3],
    /// The unit normal, octahedron-encoded ([`encode_unit`]).
    pub n: u32,
    /// Unit direction from y back along the light path (towards the last specular vertex),
    /// octahedron-encoded.
    pub wo: u32,
    /// The light path's weight arriving at y (flux over pdfs, f at y excluded).
    pub alpha: [f32; 3],
    pub err: f32,
    pub material: u32,
    /// The light side of [`connection_ratio`]: the start's density (emitter pmf x area pdf x
    /// direction pdf) over cos at the light, times the chain's cosine factor.
    pub p_light: f32,
}

/// A unit vector in 32 bits: the octahedral map (Meyer et al. 2010) quantised to 16 bits per
/// coordinate, within 1e-4 radians. Keeps a vertex at 56 bytes (see [`VERTICES_PER_PATH`] for
/// the pass's budget).
pub fn encode_unit(v: DVec3) -> u32 {
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    let (mut x, mut y) = (v.x / l1, v.y / l1);
    if v.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * ox.signum();
        y = (1.0 - ox.abs()) * oy.signum();
    }
    let q = |c: f64| (((c.clamp(-1.0, 1.0) + 1.0) * 0.5 * 65535.0).round()) as u32;
    q(x) | (q(y) << 16)
}

/// The inverse of [`encode_unit`], normalised.
pub fn decode_unit(e: u32) -> DVec3 {
    let d = |q: u32| (q & 0xffff) as f64 / 65535.0 * 2.0 - 1.0;
    let (x, y) = (d(e), d(e >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    DVec3::new(x, y, z).normalize()
}

impl CausticVertex {
    pub fn normal(&self) -> DVec3 {
        decode_unit(self.n)
    }

    pub fn wo(&self) -> DVec3 {
        decode_unit(self.wo)
    }

    pub fn alpha(&self) -> DVec3 {
        DVec3::from_array(self.alpha.map(f64::from))
    }
}

/// At most this many caustic vertices are kept per light path of a chunk (a path leaves up to
/// two: its first diffuse hit and the second one after a specular chain). A join picks one
/// vertex of the pass with probability 1 / (vertices left) whether or not they were all kept
/// (see [`CausticPass::pick_index`]), so the cap costs nothing in expectation; it bounds the pass's
/// state: 0.035 light paths per pixel x (2 splats x 16 bytes + 0.66 x 56 bytes) = 2.41 bytes per
/// pixel, 59.41 with the film (56) and the adaptive map (1); 61.82 on images whose passes are not
/// large, where the next pass is traced beside this one's rows (`Renderer::run_pass`). Measured
/// on cornell (1.32 vertices per light path before the cap) in the README.
pub const VERTICES_PER_PATH: f64 = 0.66;

/// The caustic vertices one chunk of light paths left: how many (`seen`) and where its kept
/// uniform sample of them starts in [`PassSplats::vertices`] (`kept` of them).
#[derive(Clone, Copy, Debug, Default)]
pub struct VertexGroup {
    pub seen: u64,
    /// Vertices the chunks before this one left: where its run starts among all the pass's.
    pub before: u64,
    pub start: u32,
    pub kept: u32,
}

/// One pass's splats, sorted by pixel, its kept caustic vertices by chunk, and the rays traced
/// for them.
#[derive(Debug, Default)]
pub struct PassSplats {
    pub splats: Vec<Splat>,
    pub vertices: Vec<CausticVertex>,
    pub groups: Vec<VertexGroup>,
    pub rays: u64,
    pub paths: u64,
}

impl PassSplats {
    /// The splats of pixels `start..end`.
    pub fn range(&self, start: u32, end: u32) -> &[Splat] {
        let a = self.splats.partition_point(|s| s.0 < start);
        let b = self.splats.partition_point(|s| s.0 < end);
        &self.splats[a..b]
    }

    /// What the camera paths of this pass take from it.
    pub fn pass<'a>(&'a self, tracer: &'a CausticTracer) -> CausticPass<'a> {
        let seen = self.groups.iter().map(|g| g.seen).sum();
        CausticPass {
            tracer,
            vertices: &self.vertices,
            groups: &self.groups,
            seen,
            light_paths: self.paths,
            window: (0.0, seen as f64),
            first: 0,
        }
    }
}

/// A uniform sample of at most `cap` of the vertices offered (Vitter's algorithm R), drawn with
/// its own random stream so the light paths keep theirs.
struct Reservoir {
    kept: Vec<CausticVertex>,
    seen: u64,
    cap: usize,
    rng: Rng,
}

impl Reservoir {
    fn new(cap: usize, rng: Rng) -> Self {
        Reservoir {
            kept: Vec::new(),
            seen: 0,
            cap,
            rng,
        }
    }

    /// `out`'s vertices: this reservoir's sample, as one group.
    fn close(self, out: &mut PassSplats) {
        out.groups = vec![VertexGroup {
            seen: self.seen,
            before: 0,
            start: 0,
            kept: self.kept.len() as u32,
        }];
        out.vertices = self.kept;
    }

    fn offer(&mut self, v: CausticVertex) {
        self.seen += 1;
        if self.kept.len() < self.cap {
            self.kept.push(v);
        } else {
            let j = (self.rng.next_f64() * self.seen as f64) as usize;
            if j < self.cap {
                self.kept[j] = v;
            }
        }
    }
}

/// What the camera paths of one pass use from the tracer: which caustics it splats, and its
/// caustic vertices to connect to.
#[derive(Clone, Copy, Debug)]
pub struct CausticPass<'a> {
    pub tracer: &'a CausticTracer,
    /// The kept vertices, by chunk ([`VertexGroup`]).
    pub vertices: &'a [CausticVertex],
    pub groups: &'a [VertexGroup],
    /// Vertices the pass's light paths left, kept or not.
    pub seen: u64,
    /// Light paths traced this pass (those that left no vertex included).
    pub light_paths: u64,
    /// The run of vertices left that `pick_index` draws from, as its start and length in units of
    /// vertices left (all of them, or a row's window: see [`CausticPass::for_row`]).
    window: (f64, f64),
    /// The chunk holding the window's start.
    first: usize,
}

/// The most vertices left a row's joins pick among (about 2.5k kept ones, 140 KB): picked among
/// all of a pass's, one per camera vertex and each at random, the joins missed the caches on
/// nearly every pick (a 1280x960 pass leaves 160k, 5 MB; 3840x2160 1.1M, 37 MB). Measured at
/// 1280x960, 4 passes: windows of 16k, 4k and 1k took 5.93, 5.33 and 5.19 s (medians of 3); 4k
/// keeps each vertex's uses in a row few (about 5 at 3840 pixels a row).
pub const ROW_WINDOW: u64 = 4_096;

impl CausticPass<'_> {
    /// This pass for the camera paths of image row `row`: on large passes
    /// ([`CausticTracer::large_passes`]) that left more than [`ROW_WINDOW`] vertices, its joins
    /// pick among a run of that many, starting at a uniformly
    /// random place (wrapping round), drawn per pass and row. Each vertex left is still picked
    /// with probability 1 / `seen` (a uniform start plus any offset, modulo the total, is
    /// uniform), so the joins stay unbiased given the pass's light paths, and each vertex is
    /// used as often as before, only by random rows' pixels instead of random pixels. The row's
    /// picks stay within a hundred-odd kilobytes. Checked by the chi-square test below and, on
    /// a whole render, by `tests/reference.rs`.
    pub fn for_row(self, seed: u64, pass: u32, row: u32) -> Self {
        if !self.tracer.large_passes() || self.seen <= ROW_WINDOW {
            return self;
        }
        let mut rng = Rng::for_sample(seed ^ SALT ^ WINDOW_SALT, row as u64, pass as u64);
        self.windowed(rng.next_f64(), ROW_WINDOW)
    }

    /// This pass picking among `len` of its vertices left, from `start` x `seen` on, wrapping
    /// round (`start` in [0, 1)).
    fn windowed(self, start: f64, len: u64) -> Self {
        let seen = self.seen as f64;
        let start = (start * seen).min(seen);
        let first = self
            .groups
            .partition_point(|g| (g.before + g.seen) as f64 <= start)
            .min(self.groups.len().saturating_sub(1));
        CausticPass {
            window: (start, len as f64),
            first,
            ..self
        }
    }

    /// One of the pass's vertices for the number `u`, as its index in `vertices`, each with
    /// probability 1 / `seen` over the reservoirs' draws: a chunk by its share of the vertices
    /// left, then one of its kept ones uniformly (kept with probability kept / seen, so
    /// kept / seen x seen_chunk / seen x 1 / kept = 1 / seen). Returns it and what is left of
    /// `u`, uniform again.
    #[inline]
    pub fn pick_index(&self, u: f64) -> Option<(u32, f64)> {
        let (start, len) = self.window;
        let seen = self.seen as f64;
        let mut x = start + u * len;
        let mut i = self.first;
        // Exact for x in [seen, 2 seen).
        if x >= seen {
            x -= seen;
            i = 0;
        }
        // The chunk whose run of vertices holds x: a window spans a few chunks from `first`.
        // The last one also takes what rounding leaves past the end.
        let last = self.groups.len().checked_sub(1)?;
        while i < last
            && self
                .groups
                .get(i)
                .is_some_and(|g| (g.before + g.seen) as f64 <= x)
        {
            i += 1;
        }
        let g = self.groups.get(i)?;
        if g.kept == 0 {
            return None;
        }
        // Exact (x >= before, both whole below 2^53 or x's own bits): the same number as
        // subtracting the runs before one by one.
        let x = x - g.before as f64;
        let seen = g.seen as f64;
        let f = (x / seen).clamp(0.0, 1.0) * g.kept as f64;
        let k = (f as u32).min(g.kept - 1);
        Some((g.start + k, (f - k as f64).clamp(0.0, 1.0)))
    }

    /// A camera vertex's join for uniform `u`: none with probability 1 - [`JOIN_ATTEMPT`], else
    /// [`CausticPass::pick_index`] of `u` stretched back to uniform.
    #[inline]
    pub fn attempt(&self, u: f64) -> Option<(u32, f64)> {
        let p = JOIN_ATTEMPT;
        if u >= p {
            return None;
        }
        self.pick_index((u / p).min(ONE_BELOW))
    }

    /// Start loading vertex `k` into the cache: camera paths pick the vertex their next vertex
    /// joins a ray ahead, and the load runs while the row's batch of rays is traced.
    #[inline]
    pub fn prefetch(&self, k: u32) {
        if let Some(v) = self.vertices.get(k as usize) {
            prefetch(v);
        }
    }
}

/// Ask the cache for the lines `v` spans: a hint, it never faults and changes no result.
#[inline]
fn prefetch<T>(v: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let first = (v as *const T).cast::<i8>();
        let last = first.wrapping_add(std::mem::size_of::<T>().saturating_sub(1));
        // SAFETY: a prefetch reads nothing into the program's state and does not fault,
        // whatever the address; SSE is part of every x86_64 target.
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(first);
            _mm_prefetch::<_MM_HINT_T0>(last);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = v;
}

/// Whether passes of `light_paths` light paths keep more ends than the core's cache holds
/// (see [`CausticTracer::large_passes`]).
fn large_passes(light_paths: u64) -> bool {
    light_paths as f64 * VERTICES_PER_PATH * std::mem::size_of::<CausticVertex>() as f64
        > LARGE_PASS_BYTES
}

#[derive(Clone, Debug)]
pub struct CausticTracer {
    emitters: Vec<Emitter>,
    /// Per light index: its emitter (and so its region), if the tracer starts paths there.
    emitter_of: Vec<Option<usize>>,
    targets: Vec<Sphere>,
    camera: Camera,
    width: u32,
    height: u32,
    light_paths: u64,
    /// [`CausticTracer::large_passes`], fixed with `light_paths` and read at every camera
    /// vertex (recomputing it there was 0.6% of a cornell render's instructions).
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
        if scene.lights.is_empty() {
            return Err("none (no emitters)".into());
        }
        let mut targets = Vec::new();
        for p in &scene.prims {
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
        // A fixed-seed pilot, before any sample is taken: the choice does not depend on the
        // render's random numbers, so either way the estimate stays unbiased.
        let mut pilot = PassSplats::default();
        let mut reached = 0u64;
        let mut unused = Reservoir::new(0, Rng::new(SALT));
        for i in 0..PILOT_PATHS {
            let mut rng = Rng::for_sample(SALT, i, u64::MAX);
            let before = pilot.splats.len();
            tracer.trace(scene, &mut rng, &mut pilot, &mut unused);
            // A path splats once or twice (first and second diffuse hit): count paths.
            reached += u64::from(pilot.splats.len() > before);
        }
        let rate = reached as f64 / PILOT_PATHS as f64;
        if rate < PILOT_MIN_HIT_RATE {
            return Err(format!(
                "path-traced (only {:.2}% of {PILOT_PATHS} pilot light paths reach the camera \
                 through a mirror or glass sphere)",
                100.0 * rate
            ));
        }
        let connect_threshold = if tracer.connect {
            CONNECT_ROULETTE_SHARE * pilot_mean_luminance(scene, settings)
        } else {
            0.0
        };
        Ok(CausticTracer {
            pilot_rate: rate,
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

    /// Whether emission of light `light`, hit where its outward normal is `n` by a ray along `d`, is
    /// the tracer's: the camera path reached it from a diffuse first hit through at least one
    /// specular bounce (the caller checks that), so it must not count it again.
    #[inline]
    pub fn covers(&self, light: u32, n: DVec3, d: DVec3) -> bool {
        match self.emitter(light).map(|e| e.region) {
            None => false,
            Some(Region::Triangle { two_sided }) => two_sided || d.dot(n) < 0.0,
            Some(Region::Sphere) => d.dot(n) < 0.0,
            Some(Region::Cap { axis, h }) => d.dot(n) < 0.0 && on_cap(n, axis, h),
        }
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

    /// The emitter on light `light`, if the tracer starts paths there.
    fn emitter(&self, light: u32) -> Option<&Emitter> {
        let i = self.emitter_of.get(light as usize).copied().flatten()?;
        self.emitters.get(i)
    }

    fn pick_emitter(&self, u: f64) -> &Emitter {
        let mut acc = 0.0;
        for e in &self.emitters {
            acc += e.pmf;
            if u < acc {
                return e;
            }
        }
        &self.emitters[self.emitters.len() - 1]
    }

    /// One light path: emit towards a specular sphere, follow the specular chain, splat the
    /// first diffuse hit y seen by the camera; then bounce once off y, and if that reaches another
    /// diffuse hit x through one or more specular bounces, splat x too (a caustic of a caustic:
    /// cornell's floor caustic seen through the glass ball from the ceiling and walls).
    #[inline(always)]
    fn trace(&self, scene: &Scene, rng: &mut Rng, out: &mut PassSplats, kept: &mut Reservoir) {
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
            let Some(q) = super::roulette_survival(throughput, bounces, rng.next_f64()) else {
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

    /// The cones from `y` towards the target spheres: (axis, 1 - cos) each (1 - cos = 2 from
    /// inside a target, where every direction reaches it), and their total solid angle.
    fn cones(&self, y: DVec3) -> ([(DVec3, f64); MAX_TARGETS], f64) {
        let mut cones = [(DVec3::ZERO, 0.0f64); MAX_TARGETS];
        let mut total = 0.0;
        for (slot, s) in cones.iter_mut().zip(&self.targets) {
            let to = s.center - y;
            let d2 = to.length_squared();
            let r2 = s.radius * s.radius;
            let one_minus_cos = if d2 <= r2 {
                2.0
            } else {
                warp::cone_one_minus_cos(r2 / d2)
            };
            *slot = (to / d2.sqrt(), one_minus_cos);
            total += 2.0 * PI * one_minus_cos;
        }
        (cones, total)
    }

    /// How many of `cones` hold the unit direction `w`.
    fn holding(cones: &[(DVec3, f64)], w: DVec3) -> usize {
        cones
            .iter()
            .filter(|(a, omc)| *omc >= 2.0 || 0.5 * (w - *a).length_squared() <= *omc)
            .count()
    }

    /// A direction from `y` uniform over the union of the cones towards the target spheres,
    /// counted with multiplicity: choose a cone in proportion to its solid angle, sample it, and
    /// the pdf is (number of cones holding the direction) / (sum of solid angles).
    #[inline(always)]
    fn emission_direction(&self, y: DVec3, u: (f64, f64, f64)) -> Option<(DVec3, f64)> {
        let (cones, total) = self.cones(y);
        let cones = &cones[..self.targets.len()];
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut pick = u.0 * total;
        let mut chosen = cones.len() - 1;
        for (k, c) in cones.iter().enumerate() {
            let omega = 2.0 * PI * c.1;
            if pick < omega {
                chosen = k;
                break;
            }
            pick -= omega;
        }
        let (axis, omc) = cones[chosen];
        let w = if omc >= 2.0 {
            warp::uniform_sphere((u.1, u.2))
        } else {
            Frame::from_normal(axis).to_world(warp::uniform_cone((u.1, u.2), omc))
        };
        let holding = Self::holding(cones, w).max(1);
        Some((w, holding as f64 / total))
    }

    /// The density with which a light path starts at `z` on light `light` and leaves along `w`
    /// (emitter pmf x area pdf x direction pdf), as [`CausticVertex::p_light`] records it; 0
    /// where the tracer does not start paths. Only for points the tracer covers.
    pub fn light_pdf(&self, light: u32, z: DVec3, w: DVec3) -> f64 {
        let Some(e) = self.emitter(light) else {
            return 0.0;
        };
        let (cones, total) = self.cones(z);
        if !(total > 0.0 && total.is_finite()) {
            return 0.0;
        }
        let holding = Self::holding(&cones[..self.targets.len()], w);
        e.pmf / e.area * (holding as f64 / total)
    }
}

/// The chunks' splats, sorted by pixel, and their kept vertices, grouped by chunk.
fn merge(parts: Vec<PassSplats>) -> PassSplats {
    let mut all = PassSplats::default();
    for p in parts {
        all.splats.extend(p.splats);
        for g in p.groups {
            let before = all.groups.last().map_or(0, |l| l.before + l.seen);
            all.groups.push(VertexGroup {
                start: all.vertices.len() as u32,
                before,
                ..g
            });
        }
        all.vertices.extend(p.vertices);
        all.rays += p.rays;
        all.paths += p.paths;
    }
    // Stable: splats of one pixel keep the order of their paths, so sums are reproducible.
    all.splats.sort_by_key(|s| s.0);
    all
}

/// The light side of [`connection_ratio`] along a light path: the start's density, the cosine
/// products of the specular chains, and at the first diffuse vertex y the turn towards the
/// chain to the second one.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightSide {
    /// The start's density (emitter pmf x area pdf x direction pdf); after y, times what the
    /// first chain and y contribute.
    p: f64,
    cos0: f64,
    /// Product over the current chain's specular vertices of cos(arrival) / cos(departure), as
    /// seen from the light.
    chain_cos: f64,
    past_y: bool,
}

impl LightSide {
    pub(crate) fn new(p_start: f64, cos0: f64) -> Self {
        LightSide {
            p: p_start,
            cos0,
            chain_cos: 1.0,
            past_y: false,
        }
    }

    /// A specular bounce, its cosines on the light's way in and out.
    pub(crate) fn specular(&mut self, cos_arrival: f64, cos_departure: f64) {
        self.chain_cos *= cos_arrival / cos_departure;
    }

    /// Whether the path has left its first diffuse vertex y.
    pub(crate) fn past_y(&self) -> bool {
        self.past_y
    }

    /// The ratio's light side for a join to the diffuse vertex the path has reached.
    pub(crate) fn here(&self) -> f64 {
        if self.past_y {
            self.p * self.chain_cos
        } else {
            self.p * self.chain_cos / self.cos0
        }
    }

    /// Leaving y along a direction sampled with `pdf` (`reverse` the other way, as a camera
    /// path samples it): the join to the next diffuse vertex is weighed against the camera path
    /// that samples y's bounce towards the light's chain, so the light side takes y's forward
    /// over reverse pdf and the cosines of the two chains at y; the next chain starts its own
    /// cosine product.
    pub(crate) fn leave_y(&mut self, cos_in: f64, pdf: f64, reverse: f64, cos_out: f64) {
        let turn = cos_in * pdf / (reverse * cos_out);
        self.p *= self.chain_cos / self.cos0 * turn;
        self.chain_cos = 1.0;
        self.past_y = true;
    }
}

/// The same holds for the light path's second diffuse vertex x' (light -> chain -> y -> chain' ->
/// x'), joined to a camera vertex x: the camera path samples x', then x' towards the chain', then
/// y towards the light's chain, where the light path sampled y's bounce the other way. With
/// everything not at y as above, the light side gains y's forward over reverse pdf and the
/// cosines of the two chains at y ([`LightSide::leave_y`]), and K' of the chain': the camera
/// side has the same form, with x' in y's place (`path::Chains`).
///
/// The ratio p_connect / p_camera of the densities with which the two strategies produce the
/// path camera .. x -> y -> specular chain s_1 .. s_k -> light z: the light tracer's (its start,
/// the chain, then x joined to y) over the camera path's (x's BSDF towards y, y's BSDF along the
/// chain, landing on the light). In area measure the chain's segment lengths and Fresnel
/// choices appear in both and cancel, as does x's prefix; what is left is
///
///   r = p_start cos_y_in K / (pdf_x (cos_y_x / d_xy^2) pdf_y cos_z),
///
/// with cos_y_in the angle at y of the chain's last segment, cos_z that at the light of its
/// first, and K the product over specular vertices of cos(arrival) / cos(departure) seen from
/// the light (1 for a mirror; for a pass through a glass sphere the two interfaces cancel).
/// The light side's factors are `p_light` (p_start K / cos_z, [`CausticVertex::p_light`]); the
/// camera side's are `camera` (pdf_x cos_y_x / d_xy^2 pdf_y / cos_y_in, over K). Russian
/// roulette is left out of both, which keeps the weights summing to 1 (all MIS needs).
#[inline]
pub fn connection_ratio(p_light: f64, camera: f64) -> f64 {
    if camera > 0.0 {
        p_light / camera
    } else {
        f64::INFINITY
    }
}

/// Mean luminance of the image, from fixed-seed camera paths through random pixels (the path
/// integrator without the tracer): the scale of the connections' roulette threshold, fixed
/// before any sample is taken so the render's passes stay independent. 0 if not finite.
fn pilot_mean_luminance(scene: &Scene, settings: &RenderSettings) -> f64 {
    let mut sum = 0.0;
    for i in 0..PILOT_CAMERA_PATHS {
        let mut rng = Rng::for_sample(SALT ^ 1, i, u64::MAX);
        let fx = rng.next_f64() * settings.width as f64;
        let fy = rng.next_f64() * settings.height as f64;
        let ray = scene.camera.ray(settings.width, settings.height, fx, fy);
        let mut sampler = Sampler::new(SamplerKind::Independent, SALT, i, u64::MAX);
        sum += luminance(super::path::radiance(
            scene,
            ray,
            &mut sampler,
            u32::MAX,
            None,
        ));
    }
    let mean = sum / PILOT_CAMERA_PATHS as f64;
    if mean.is_finite() && mean > 0.0 {
        mean
    } else {
        0.0
    }
}

fn emission(light: &Light) -> DVec3 {
    match light {
        Light::Sphere(l) => l.emission,
        Light::Triangle(l) => l.emission,
    }
}

/// The region of a sphere light the tracer starts from, and its area: the smallest cap left by
/// a cutting sphere with every target on the cap's side, else the whole sphere.
fn sphere_region(l: &crate::light::sphere::SphereLight, targets: &[Sphere]) -> (Region, f64) {
    let r2 = l.sphere.radius * l.sphere.radius;
    let mut best = (Region::Sphere, 4.0 * PI * r2);
    for clip in l.clips() {
        let inside: Vec<bool> = targets
            .iter()
            .map(|t| (t.center - clip.center).length_squared() < clip.radius2)
            .collect();
        let (axis, h) = if inside.iter().all(|&b| b) {
            (clip.axis, clip.h_in)
        } else if inside.iter().all(|&b| !b) {
            (-clip.axis, clip.h_out)
        } else {
            continue;
        };
        let area = 2.0 * PI * r2 * h;
        if area < best.1 {
            best = (Region::Cap { axis, h }, area);
        }
    }
    best
}

/// A point on the emitter's region, uniform by area: (point, outward normal, error bound, area
/// pdf, emitted radiance).
#[inline(always)]
fn emission_point(
    light: &Light,
    region: Region,
    u: (f64, f64),
) -> Option<(DVec3, DVec3, f64, f64, DVec3)> {
    match (light, region) {
        (Light::Sphere(l), Region::Sphere | Region::Cap { .. }) => {
            let s = &l.sphere;
            let r2 = s.radius * s.radius;
            let (n, area) = match region {
                Region::Cap { axis, h, .. } => (
                    Frame::from_normal(axis).to_world(warp::uniform_cone(u, h)),
                    2.0 * PI * r2 * h,
                ),
                _ => (warp::uniform_sphere(u), 4.0 * PI * r2),
            };
            let err = s.error_bound();
            Some((s.center + n * s.radius, n, err, 1.0 / area, l.emission))
        }
        (Light::Triangle(l), _) => {
            let (b1, b2) = warp::uniform_triangle(u);
            let y = l.triangle.point(b1, b2);
            let n = l.triangle.normal()?;
            let max = l
                .triangle
                .p()
                .iter()
                .map(|p| p.abs().max_element())
                .fold(0.0, f64::max);
            let err = crate::geometry::triangle::gamma(7.0) * 3.0 * max;
            Some((y, n, err, 1.0 / l.triangle.area(), l.emission))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unit vectors survive the 32-bit encoding within 1e-4 radians, the axes and the
    /// octahedron's folded lower half included, and a vertex stays at 56 bytes.
    #[test]
    fn unit_vectors_round_trip_and_vertices_stay_small() {
        let mut rng = Rng::new(5);
        let mut worst = 0.0f64;
        for i in 0..100_000 {
            let v = match crate::math::SIGNED_AXES.get(i) {
                Some(a) => *a,
                None => warp::uniform_sphere((rng.next_f64(), rng.next_f64())),
            };
            let back = decode_unit(encode_unit(v));
            worst = worst.max(v.to_glam().angle_between(back.to_glam()));
        }
        assert!(worst < 1e-4, "worst angle {worst:e}");
        assert_eq!(std::mem::size_of::<CausticVertex>(), 56);
    }

    /// A join picks each vertex the light paths left with probability 1 / seen, whether its
    /// chunk kept it or not: chunks that keep all, some or none of theirs (the last has no
    /// vertex). Pearson's chi-square over the vertices, normal approximation, 5 sigma.
    #[test]
    fn kept_vertices_are_picked_uniformly_over_all_left() {
        let tracer = dummy_tracer();
        let mut rng = Rng::new(11);
        let (seen, counts) = pick_counts(220_000, |t| {
            let all = reservoir_pass(t);
            let pass = all.pass(&tracer);
            let (k, rest) = pass.pick_index(rng.next_f64()).expect("a vertex");
            (pass.seen, pass.vertices[k as usize].material, rest)
        });
        assert_uniform(seen, &counts, 1);
    }

    /// A row's window (here 7 of the 24 vertices left, starting anywhere, wrapping round)
    /// keeps every vertex left at probability 1 / seen, and the number left over for the
    /// roulette uniform: chi-square over (vertex, half of that number). Fails if the window
    /// does not wrap round (picks past the end) or starts only where a chunk does (z 9347).
    #[test]
    fn windowed_picks_stay_uniform_over_all_left() {
        let tracer = dummy_tracer();
        let mut rng = Rng::new(12);
        let (seen, counts) = pick_counts(300_000, |t| {
            let all = reservoir_pass(t);
            let pass = all.pass(&tracer).windowed(rng.next_f64(), 7);
            let (k, rest) = pass.pick_index(rng.next_f64()).expect("a vertex");
            (pass.seen, pass.vertices[k as usize].material, rest)
        });
        assert_uniform(seen, &counts, 2);
    }

    /// A camera vertex attempts its join with probability [`JOIN_ATTEMPT`], and an attempt that goes
    /// ahead still picks every vertex left with probability 1 / seen and leaves a uniform number
    /// for the roulette: chi-square over (vertex, half of that number), and the draws it took
    /// to see the trials' attempts against their negative binomial law, 5 sigma each.
    #[test]
    fn attempts_go_ahead_at_their_rate_and_pick_uniformly() {
        let tracer = dummy_tracer();
        let p = JOIN_ATTEMPT;
        assert!(p > 0.0 && p < 1.0);
        let mut rng = Rng::new(13);
        let trials = 200_000u64;
        let mut draws = 0u64;
        let (seen, counts) = pick_counts(trials, |t| {
            let all = reservoir_pass(t);
            let pass = all.pass(&tracer);
            loop {
                draws += 1;
                if let Some((k, rest)) = pass.attempt(rng.next_f64()) {
                    break (pass.seen, pass.vertices[k as usize].material, rest);
                }
            }
        });
        assert_uniform(seen, &counts, 2);
        let n = trials as f64;
        let z = (draws as f64 - n / p) / ((n * (1.0 - p)).sqrt() / p);
        assert!(
            z.abs() < 5.0,
            "{draws} draws for {trials} attempts (z {z:.2})"
        );
    }

    /// 24 vertices left by 5 chunks whose reservoirs keep all, some or none of them (drawn
    /// anew for each trial `t`); each vertex's number rides in its material field.
    fn reservoir_pass(t: u64) -> PassSplats {
        let sizes = [(7u64, 4usize), (3, 3), (12, 5), (2, 1), (0, 2)];
        let mut next = 0u32;
        let parts = sizes
            .iter()
            .enumerate()
            .map(|(c, &(n, cap))| {
                let mut r = Reservoir::new(cap, Rng::for_sample(3, c as u64, t));
                for _ in 0..n {
                    r.offer(CausticVertex {
                        p: [0.0; 3],
                        n: 0,
                        wo: 0,
                        alpha: [1.0; 3],
                        err: 0.0,
                        material: next,
                        p_light: 1.0,
                    });
                    next += 1;
                }
                let mut out = PassSplats::default();
                r.close(&mut out);
                out
            })
            .collect();
        merge(parts)
    }

    /// Counts of (vertex, which half of the number left over) over `trials` picks, and the
    /// vertices left.
    fn pick_counts(
        trials: u64,
        mut pick: impl FnMut(u64) -> (u64, u32, f64),
    ) -> (u64, Vec<[u64; 2]>) {
        let mut counts = Vec::new();
        let mut seen_all = 0;
        for t in 0..trials {
            let (seen, v, rest) = pick(t);
            assert_eq!(seen, 24);
            assert!((0.0..=1.0).contains(&rest), "{rest}");
            counts.resize(seen as usize, [0u64; 2]);
            counts[v as usize][usize::from(rest >= 0.5)] += 1;
            seen_all = seen;
        }
        (seen_all, counts)
    }

    /// Pearson's chi-square against the uniform distribution over the vertices (`halves` = 1)
    /// or over vertex x half of the number left (2); normal approximation, 5 sigma.
    fn assert_uniform(seen: u64, counts: &[[u64; 2]], halves: usize) {
        let cells: Vec<u64> = if halves == 1 {
            counts.iter().map(|c| c[0] + c[1]).collect()
        } else {
            counts.iter().flatten().copied().collect()
        };
        let trials: u64 = cells.iter().sum();
        assert_eq!(cells.len() as u64, seen * halves as u64);
        let expected = trials as f64 / cells.len() as f64;
        let chi2: f64 = cells
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        let dof = (cells.len() - 1) as f64;
        let z = (chi2 - dof) / (2.0 * dof).sqrt();
        assert!(z < 5.0, "chi2 {chi2:.1} on {dof} dof (z {z:.2}): {cells:?}");
    }

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

    /// The density the camera paths weigh a light they find against the joins with
    /// ([`CausticTracer::light_pdf`]) is the one the light paths start with (emitter pmf x area
    /// pdf x direction pdf, as `trace` records it), for sphere lights, one-sided quads and
    /// two-sided ones. Two-sided quads once counted their area twice in the first but not the
    /// second, so the MIS weights of a caustic seen after a bounce summed to up to 4/3.
    #[test]
    fn the_camera_side_light_density_is_the_one_light_paths_start_with() {
        let quad = |sides: &str| {
            format!(
                "[[quad]]\ncorner = [-1, 4, -1]\nedge1 = [2, 0, 0]\nedge2 = [0, 0, 2]\n\
                 emission = 5\n{sides}\n[[sphere]]\nmaterial = \"glass\"\ncenter = [0, 1, 0]\n\
                 radius = 1\n[[sphere]]\ncenter = [0, -1e4, 0]\nradius = 1e4\n\
                 [camera]\nposition = [0, 2, 8]\nlook_at = [0, 0, 0]\n"
            )
        };
        let sources = [
            quad(""),
            quad("two_sided = true"),
            quad("").replace(
                "[[quad]]\ncorner = [-1, 4, -1]\nedge1 = [2, 0, 0]\nedge2 = [0, 0, 2]",
                "[[sphere]]\ncenter = [0, 5, 0]\nradius = 0.5",
            ),
        ];
        for src in sources {
            let scene = crate::scene::load_str(&src, "t.toml").expect("scene");
            let mut settings = RenderSettings::merged(&[&scene.render]);
            (settings.width, settings.height) = (32, 24);
            let tracer = CausticTracer::new(&scene, &settings).expect("a tracer");
            let mut rng = Rng::new(9);
            let mut checked = 0;
            for _ in 0..2000 {
                let e = *tracer.pick_emitter(rng.next_f64());
                let light = &scene.lights.lights[e.light];
                let u = (rng.next_f64(), rng.next_f64());
                let (y0, _, _, area_pdf, _) = emission_point(light, e.region, u).expect("point");
                let u3 = (rng.next_f64(), rng.next_f64(), rng.next_f64());
                let Some((w, dir_pdf)) = tracer.emission_direction(y0, u3) else {
                    continue;
                };
                let start = e.pmf * area_pdf * dir_pdf;
                let camera_side = tracer.light_pdf(e.light as u32, y0, w);
                assert!(
                    (camera_side - start).abs() <= 1e-9 * start,
                    "{src}: light_pdf {camera_side:e} vs start {start:e}"
                );
                checked += 1;
            }
            assert!(checked > 1000);
        }
    }

    fn dummy_tracer() -> CausticTracer {
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
}
