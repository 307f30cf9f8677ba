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
//! which camera paths found only as rare fireflies, a halo of error around the lamp); the camera
//! paths skip precisely
//! those ([`CausticTracer::covers`] at the light, `PathState::caustic_end` for the shape) and keep
//! everything else. The tracer's emission directions are drawn only towards the scene's specular
//! spheres, which is complete because every path it must cover starts by hitting one; so it is
//! used only when all delta materials sit on spheres (a mirror mesh turns it off, as does a depth
//! limit, which the split would have to count against).
//!
//! Where a caustic is seen after a bounce the camera paths and joins share it by MIS: camera
//! vertices join one of the pass's light-path ends, the first diffuse hit y (light -> chain ->
//! y -> x) or the second one x' (light -> chain -> y -> chain -> x' -> x: on `cornell-small-light`
//! the floor's caustic through the glass ball again, seen after a bounce, fireflies that held
//! nearly all of its squared error before these joins; benches/HISTORY.md#caustic-joins). A pass
//! keeps at most
//! [`VERTICES_PER_PATH`] ends per light path, a uniform sample per chunk, and a join picks among
//! all the ends left, kept or not, with equal probability. A camera vertex attempts its join
//! with probability [`JOIN_ATTEMPT`] and plays a roulette on the join's worth (both divided out).
//!
//! Each pass traces [`LIGHT_PATHS_PER_PIXEL`] x pixels light paths with their own random streams
//! and adds the splats landing in a pixel to that pixel's camera sample of the same pass: every
//! pass stays one independent, unbiased sample per pixel, so the film's means, variances and
//! half-buffer error estimates stay valid. Splats are gathered per chunk of paths and sorted by
//! pixel, so the sum is the same bit for bit whatever the thread count.
//!
//! One job per file: `emitters` (where and in which direction light paths start, and which
//! emission the camera paths leave to them), `encoding` (unit vectors in 32 bits), `vertices` (a
//! pass's splats and light-path ends), `reservoir` (the uniform sample of ends a chunk keeps),
//! `joins` (which end a camera vertex joins), `tracer` (the light paths), `pilot` (the fixed-seed
//! runs that decide whether the tracer pays and set the joins' roulette) and `mis` (the ratio of
//! path densities the joins are weighed by).

mod emitters;
mod encoding;
mod joins;
mod mis;
mod pilot;
mod reservoir;
mod tracer;
mod vertices;

pub use emitters::Region;
pub use encoding::{decode_unit, encode_unit};
pub use joins::{CausticPass, JOIN_ATTEMPT, ROW_WINDOW};
pub use mis::connection_ratio;
pub(crate) use mis::LightSide;
pub use tracer::{CausticTracer, LIGHT_PATHS_PER_PIXEL};
pub use vertices::{CausticVertex, PassSplats, Splat, VertexGroup, VERTICES_PER_PATH};

/// Salt separating the light paths' random streams from the camera paths'.
const SALT: u64 = 0x6c69_6768_7470_6174;

/// Salt of the reservoirs' streams, which choose the vertices kept.
const RESERVOIR_SALT: u64 = 0x7265_7365_7276_6f69;
/// Keeps the rows' join windows ([`CausticPass::for_row`]) apart from both.
const WINDOW_SALT: u64 = 0x7769_6e64_6f77_7321;
