//! What a pass of light paths leaves: its splats, and the caustic vertices (light-path ends) its
//! chunks kept, grouped by chunk.

use crate::math::DVec3;

use super::decode_unit;

/// See [`CausticTracer::large_passes`](super::CausticTracer::large_passes).
const LARGE_PASS_BYTES: f64 = 1024.0 * 1024.0;

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
    /// The unit normal, octahedron-encoded ([`encode_unit`](super::encode_unit)).
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
    ///
    /// [`connection_ratio`]: super::connection_ratio
    pub p_light: f32,
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
/// on cornell: benches/HISTORY.md#kept-light-path-ends.
///
/// [`CausticPass::pick_index`]: super::CausticPass::pick_index
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
}

/// Whether passes of `light_paths` light paths keep more ends than the core's cache holds
/// (see [`CausticTracer::large_passes`](super::CausticTracer::large_passes)).
pub(super) fn large_passes(light_paths: u64) -> bool {
    light_paths as f64 * VERTICES_PER_PATH * std::mem::size_of::<CausticVertex>() as f64
        > LARGE_PASS_BYTES
}

/// The chunks' splats, sorted by pixel, and their kept vertices, grouped by chunk.
pub(super) fn merge(parts: Vec<PassSplats>) -> PassSplats {
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
