//! Bounding volume hierarchy: binned SAH build (Wald 2007, pbrt-v4's `BVHAggregate` with
//! buckets) into a binary, depth-first node array, collapsed into four-wide nodes with f32 boxes
//! ([`super::wide`], which also holds the traversal); the closest-hit and any-hit queries (and
//! the cost probe) run that traversal with their own leaf test.
//!
//! Results are exactly those of the flat scan ([`super::flat`]): the same shapes are tested with
//! the same arithmetic, box tests are conservative (boxes padded, f32 boxes rounded outward, the
//! f32 test's distances bounded for its rounding), and when two primitives are hit at exactly the
//! same distance the lower index wins, as it does in the flat scan's in-order loop.

use super::wide::{self, BinaryNode, WideNode};
use crate::geometry::{Aabb, Hit};
use crate::geometry::{Primitive, Shape};
use crate::math::{DVec3, Ray};
use crate::progress::{tick, Progress};
use rayon::prelude::*;
use std::ops::Range;
use std::time::{Duration, Instant};

/// SAH buckets per split (pbrt uses 12; more buy little).
const BUCKETS: usize = 16;
/// A leaf never holds more primitives than this, unless they cannot be separated at all.
const MAX_LEAF: usize = 4;
/// Cost of a traversal step (a box test) relative to one primitive test: 1 gives fewer, fuller
/// leaves than pbrt's 1/2 and renders torus-knot faster (benches/HISTORY.md#bvh-traversal-cost).
const TRAVERSAL_COST: f64 = 1.0;
/// Below this depth splits follow the SAH; deeper, the median split by count guarantees that
/// the tree (and the traversal stack) stays shallow even for adversarial inputs.
const SAH_DEPTH: usize = 48;
/// Subtrees of at least this many primitives, in the top [`PARALLEL_DEPTH`] levels, build their
/// second child on another thread, into its own node array that is copied in after the first
/// child's: the same decisions in the same order, so the same tree as one thread builds, bit
/// for bit. The depth bound keeps the copying to a few passes over the nodes (2^4 tasks are
/// plenty for rayon to balance).
const PARALLEL_MIN: usize = 16 * 1024;
const PARALLEL_DEPTH: usize = 4;
/// Bound on the binary tree's depth (so on the wide tree's): SAH splits for SAH_DEPTH levels,
/// then halving splits, at most 32 more for u32 indices.
pub(super) const MAX_DEPTH: usize = 96;

/// A node of the binary tree the build makes (and [`wide::collapse`] turns into wide nodes).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    /// The box's corners as arrays (as `DVec3`s, padded to 32 bytes, they took more memory).
    corners: [[f64; 3]; 2],
    /// Leaf: first index into `order`. Interior: index of the second child (the first child is
    /// the next node).
    offset: u32,
    /// Leaf: number of primitives (> 0). Interior: 0.
    count: u32,
}

impl BinaryNode for Node {
    fn bounds(&self) -> Aabb {
        Aabb {
            min: DVec3::from_array(self.corners[0]),
            max: DVec3::from_array(self.corners[1]),
        }
    }

    fn leaf(&self) -> Option<(u32, u32)> {
        (self.count > 0).then_some((self.offset, self.count))
    }

    fn second(&self) -> usize {
        self.offset as usize
    }
}

#[derive(Clone, Debug)]
pub struct Bvh {
    /// The four-wide tree; the binary one it was collapsed from is dropped after the build.
    nodes: Vec<WideNode>,
    /// Primitive indices; each leaf owns a contiguous range.
    order: Vec<u32>,
    /// The primitives' shapes in `order`: a leaf's shapes sit next to each other in memory
    /// instead of scattered over the scene's primitive array (fewer cache misses).
    shapes: Vec<Shape>,
    pub build_time: Duration,
}

#[derive(Clone, Copy)]
struct BuildPrim {
    bounds: Aabb,
    centroid: DVec3,
    index: u32,
}

/// Bounds grown by a relative margin, so a hit that rounding puts a hair outside the exact
/// bounds of its shape (a grazing sphere root, say) is still inside its box. The margin is far
/// above the shapes' rounding errors (tens of ulps) and far below any visible size.
fn padded(b: Aabb) -> Aabb {
    let scale = b.min.abs().max(b.max.abs()).max_element() + (b.max - b.min).max_element();
    let pad = DVec3::splat(scale * 1e-12);
    Aabb {
        min: b.min - pad,
        max: b.max + pad,
    }
}

impl Bvh {
    pub fn build(prims: &[Primitive]) -> Bvh {
        Self::build_with(prims, None)
    }

    /// [`Self::build`], counting the primitives placed in leaves into `progress` (whose stage
    /// the caller starts with the primitive count as its total).
    pub fn build_with(prims: &[Primitive], progress: Option<&Progress>) -> Bvh {
        Self::build_split(prims, progress, PARALLEL_MIN)
    }

    /// The build, with subtrees of `parallel_min` primitives or more built on two threads.
    fn build_split(prims: &[Primitive], progress: Option<&Progress>, parallel_min: usize) -> Bvh {
        let started = Instant::now();
        let mut build: Vec<BuildPrim> = prims
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let bounds = padded(p.shape.bounds());
                BuildPrim {
                    bounds,
                    centroid: bounds.centroid(),
                    index: i as u32,
                }
            })
            .collect();
        // At most 2n - 1 nodes (every leaf holds a primitive): reserved, never reallocated;
        // pages the tree does not reach are never touched.
        let mut nodes = Vec::with_capacity(2 * prims.len());
        if !build.is_empty() {
            let ctx = BuildCtx {
                progress,
                parallel_min,
            };
            build_node(&mut build, 0, 0, &mut nodes, &ctx);
        }
        let nodes = wide::collapse(&nodes);
        let order: Vec<u32> = build.par_iter().map(|b| b.index).collect();
        let shapes = order.par_iter().map(|&i| prims[i as usize].shape).collect();
        Bvh {
            nodes,
            order,
            shapes,
            build_time: started.elapsed(),
        }
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes the tree holds: nodes, the leaf order and the shapes copied into leaf order.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
            + self.order.len() * std::mem::size_of::<u32>()
            + self.shapes.len() * std::mem::size_of::<Shape>()
    }

    /// Measured cost of closest-hit queries for `rays`, in units of one primitive test: the
    /// mean over the rays of (boxes tested x TRAVERSAL_COST + primitives tested), counted by
    /// running the real traversal. The flat scan costs exactly the primitive count, so
    /// comparing the two says whether the boxes separate anything *for rays like these*.
    pub fn probe_cost(&self, rays: &[Ray]) -> f64 {
        if rays.is_empty() {
            return 0.0;
        }
        let (mut boxes, mut tests) = (0u64, 0u64);
        for ray in rays {
            boxes += self.traverse::<true>(ray, f64::INFINITY, |range, best| {
                for shape in &self.shapes[range] {
                    tests += 1;
                    if let Some(t) = shape.intersect(ray, *best) {
                        *best = t;
                    }
                }
                false
            });
        }
        (boxes as f64 * TRAVERSAL_COST + tests as f64) / rays.len() as f64
    }

    /// Closest hit in (0, t_max).
    #[inline]
    pub fn intersect(&self, prims: &[Primitive], ray: &Ray, t_max: f64) -> Option<Hit> {
        self.closest(ray, t_max)
            .map(|(t, i)| prims[i as usize].shape.hit(ray, t, i))
    }

    /// Distance and index of the closest hit in (0, t_max), without the hit record (which
    /// recomputes the winning test and reads the scene's primitive: 12-22% of a query,
    /// benches/HISTORY.md#the-hit-record-and-the-walk-alone).
    #[inline]
    pub fn closest(&self, ray: &Ray, t_max: f64) -> Option<(f64, u32)> {
        let mut best = t_max;
        let mut best_index = u32::MAX;
        self.traverse::<true>(ray, t_max, |range, bound| {
            for (&i, shape) in self.order[range.clone()].iter().zip(&self.shapes[range]) {
                // Allow t == bound so an equal-distance hit of a lower index wins.
                if let Some(t) = shape.intersect(ray, bound.next_up()) {
                    let found = best_index != u32::MAX;
                    if t < *bound || (found && t == *bound && i < best_index) {
                        *bound = t;
                        best = t;
                        best_index = i;
                    }
                }
            }
            false
        });
        (best_index != u32::MAX).then_some((best, best_index))
    }

    /// Whether anything is hit in (0, t_max); stops at the first hit found.
    #[inline]
    pub fn any_hit(&self, ray: &Ray, t_max: f64) -> bool {
        let mut hit = false;
        self.traverse::<false>(ray, t_max, |range, _| {
            hit = self.shapes[range]
                .iter()
                .any(|s| s.intersect(ray, t_max).is_some());
            hit
        });
        hit
    }

    #[inline(always)]
    fn traverse<const ORDERED: bool>(
        &self,
        ray: &Ray,
        t_max: f64,
        leaf: impl FnMut(Range<usize>, &mut f64) -> bool,
    ) -> u64 {
        wide::traverse::<ORDERED>(&self.nodes, ray, t_max, leaf)
    }

    /// Check the structure: every primitive in exactly one leaf, each primitive's box inside its
    /// leaf's, each node's children's boxes inside the box its parent keeps for it, every node
    /// reached once. For tests; returns what is wrong.
    pub fn check(&self, prims: &[Primitive]) -> Result<(), String> {
        let mut seen = vec![0u32; prims.len()];
        if prims.is_empty() {
            return if self.nodes.is_empty() {
                Ok(())
            } else {
                Err("nodes without primitives".into())
            };
        }
        let mut stack = vec![(0usize, None::<Aabb>)];
        let mut visited = 0usize;
        while let Some((i, parent)) = stack.pop() {
            let n = self
                .nodes
                .get(i)
                .ok_or_else(|| format!("node index {i} out of range"))?;
            visited += 1;
            for j in 0..wide::WIDTH {
                let Some((child, count)) = n.child(j) else {
                    continue;
                };
                let b = n.child_box(j);
                if let Some(p) = parent {
                    if !p.contains(&b) {
                        return Err(format!("child {j} of node {i} is not inside its parent"));
                    }
                }
                if count == 0 {
                    stack.push((child as usize, Some(b)));
                    continue;
                }
                let range = child as usize..child as usize + count as usize;
                let leaf = self
                    .order
                    .get(range)
                    .ok_or_else(|| format!("leaf {j} of node {i}: range out of order array"))?;
                for &p in leaf {
                    let slot = seen
                        .get_mut(p as usize)
                        .ok_or_else(|| format!("node {i} holds unknown primitive {p}"))?;
                    *slot += 1;
                    if !b.contains(&prims[p as usize].shape.bounds()) {
                        return Err(format!("primitive {p} sticks out of its leaf in node {i}"));
                    }
                }
            }
        }
        if visited != self.nodes.len() {
            return Err(format!("{} nodes, {visited} reachable", self.nodes.len()));
        }
        match seen.iter().position(|&c| c != 1) {
            Some(p) => Err(format!("primitive {p} is in {} leaves", seen[p])),
            None => Ok(()),
        }
    }
}

fn bounds_of(prims: &[BuildPrim]) -> (Aabb, Aabb) {
    prims.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), p| {
        (b.union(p.bounds), c.grow(p.centroid))
    })
}

/// What every level of a build shares.
struct BuildCtx<'a> {
    progress: Option<&'a Progress>,
    parallel_min: usize,
}

/// Build the subtree over `prims` (which sit at `first` in the final order); returns its index.
fn build_node(
    prims: &mut [BuildPrim],
    first: usize,
    depth: usize,
    nodes: &mut Vec<Node>,
    ctx: &BuildCtx,
) -> usize {
    let progress = ctx.progress;
    let (bounds, centroids) = bounds_of(prims);
    let index = nodes.len();
    nodes.push(Node {
        corners: [bounds.min.to_array(), bounds.max.to_array()],
        offset: first as u32,
        count: prims.len() as u32,
    });
    let n = prims.len();
    if n == 1 {
        tick(progress, 1);
        return index;
    }
    let extent = centroids.max - centroids.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    if extent[axis].is_nan() || extent[axis] <= 0.0 {
        // All centroids coincide: no split can separate them by position.
        if n <= MAX_LEAF {
            tick(progress, n as u64);
            return index;
        }
        return split_at(prims, first, depth, nodes, index, n / 2, ctx);
    }
    if depth >= SAH_DEPTH {
        prims.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        return split_at(prims, first, depth, nodes, index, n / 2, ctx);
    }

    // Bin centroids along the axis and sweep for the cheapest bucket boundary.
    let lo = centroids.min[axis];
    let scale = BUCKETS as f64 / extent[axis];
    let bucket_of = |p: &BuildPrim| (((p.centroid[axis] - lo) * scale) as usize).min(BUCKETS - 1);
    let mut count = [0usize; BUCKETS];
    let mut bbox = [Aabb::EMPTY; BUCKETS];
    for p in prims.iter() {
        let b = bucket_of(p);
        count[b] += 1;
        bbox[b] = bbox[b].union(p.bounds);
    }
    // cost[i]: split after bucket i.
    let mut cost = [0.0f64; BUCKETS - 1];
    let (mut acc_b, mut acc_n) = (Aabb::EMPTY, 0usize);
    for i in 0..BUCKETS - 1 {
        acc_b = acc_b.union(bbox[i]);
        acc_n += count[i];
        cost[i] = acc_n as f64 * acc_b.half_area();
    }
    let (mut acc_b, mut acc_n) = (Aabb::EMPTY, 0usize);
    for i in (1..BUCKETS).rev() {
        acc_b = acc_b.union(bbox[i]);
        acc_n += count[i];
        cost[i - 1] += acc_n as f64 * acc_b.half_area();
    }
    let (best, best_cost) = cost.iter().enumerate().fold(
        (0, f64::INFINITY),
        |(bi, bc), (i, &c)| {
            if c < bc {
                (i, c)
            } else {
                (bi, bc)
            }
        },
    );
    let area = bounds.half_area();
    let split_cost = TRAVERSAL_COST + if area > 0.0 { best_cost / area } else { 0.0 };
    if n <= MAX_LEAF && n as f64 <= split_cost {
        tick(progress, n as u64);
        return index;
    }
    let mid = partition(prims, |p| bucket_of(p) <= best);
    let mid = if mid == 0 || mid == n {
        // Every centroid fell on one side (possible only through rounding): split by count.
        prims.select_nth_unstable_by(n / 2, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
        n / 2
    } else {
        mid
    };
    split_at(prims, first, depth, nodes, index, mid, ctx)
}

#[allow(clippy::too_many_arguments)]
fn split_at(
    prims: &mut [BuildPrim],
    first: usize,
    depth: usize,
    nodes: &mut Vec<Node>,
    index: usize,
    mid: usize,
    ctx: &BuildCtx,
) -> usize {
    let parallel = prims.len() >= ctx.parallel_min && depth < PARALLEL_DEPTH;
    let (left, right) = prims.split_at_mut(mid);
    let second = if parallel {
        let ((), r) = rayon::join(
            || {
                build_node(left, first, depth + 1, nodes, ctx);
            },
            || {
                let mut own = Vec::with_capacity(2 * right.len());
                build_node(right, first + mid, depth + 1, &mut own, ctx);
                own
            },
        );
        let second = nodes.len();
        splice(nodes, r);
        second
    } else {
        build_node(left, first, depth + 1, nodes, ctx);
        build_node(right, first + mid, depth + 1, nodes, ctx)
    };
    nodes[index].offset = second as u32;
    nodes[index].count = 0;
    index
}

/// Append a subtree built into its own array: its interior nodes' child indices were relative
/// to that array's start (leaves index `order`, which does not move).
fn splice(nodes: &mut Vec<Node>, subtree: Vec<Node>) {
    let base = nodes.len() as u32;
    let start = nodes.len();
    nodes.extend_from_slice(&subtree);
    for n in &mut nodes[start..] {
        if n.count == 0 {
            n.offset += base;
        }
    }
}

/// In-place partition: elements satisfying `pred` first; returns how many.
fn partition(prims: &mut [BuildPrim], pred: impl Fn(&BuildPrim) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..prims.len() {
        if pred(&prims[i]) {
            prims.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bench::random_prims;
    use crate::accel::flat;
    use crate::sampling::{warp, Rng};

    /// Rays aimed at the primitives' vertices and edges (nudged by an ulp or two), where a box
    /// test that rejects a hair too much would lose the hit; a tenth axis-parallel (the f64 test),
    /// a tenth from far away. The wide tree must find what the flat scan finds, bit for bit.
    #[test]
    fn grazing_rays_find_what_the_flat_scan_finds() {
        let mut rng = Rng::new(11);
        for (n, seed) in [(2usize, 1u64), (17, 2), (300, 3), (5000, 4)] {
            let prims = random_prims(n, seed);
            let bvh = Bvh::build(&prims);
            bvh.check(&prims).unwrap();
            for i in 0..4000 {
                let target = match &prims[rng.next_u64() as usize % n].shape {
                    Shape::Triangle(t) => {
                        let p = t.p();
                        let (a, b) = (p[i % 3], p[(i + 1) % 3]);
                        let w = if i % 2 == 0 { 0.0 } else { rng.next_f64() };
                        a + (b - a) * w
                    }
                    Shape::Sphere(s) => {
                        let b = s.bounds();
                        b.centroid() + (b.max - b.centroid()) * rng.next_f64()
                    }
                };
                let nudge = |x: f64, rng: &mut Rng| match rng.next_u64() % 3 {
                    0 => x.next_up(),
                    1 => x.next_down(),
                    _ => x,
                };
                let target = DVec3::new(
                    nudge(target.x, &mut rng),
                    nudge(target.y, &mut rng),
                    nudge(target.z, &mut rng),
                );
                let d = if i % 10 == 0 {
                    [DVec3::X, -DVec3::Y, DVec3::Z][i % 3]
                } else {
                    warp::uniform_sphere((rng.next_f64(), rng.next_f64()))
                };
                let dist = if i % 10 == 5 {
                    1e4
                } else {
                    2.0 * rng.next_f64()
                };
                let ray = Ray::new(target - d * dist, d);
                let t_max = if i % 4 == 0 {
                    dist * (1.0 + 1e-9)
                } else {
                    f64::INFINITY
                };
                let key = |h: Option<Hit>| h.map(|h| (h.prim, h.t.to_bits()));
                assert_eq!(
                    key(flat::intersect(&prims, &ray, t_max)),
                    key(bvh.intersect(&prims, &ray, t_max)),
                    "n {n} ray {ray:?} t_max {t_max}"
                );
                assert_eq!(flat::any_hit(&prims, &ray, t_max), bvh.any_hit(&ray, t_max));
            }
        }
    }

    #[test]
    fn the_parallel_build_is_the_one_thread_build_node_for_node() {
        let prims = random_prims(5000, 7);
        let one = Bvh::build_split(&prims, None, usize::MAX);
        let split = Bvh::build_split(&prims, None, 64);
        assert!(one.nodes.len() > 1000);
        assert_eq!(one.nodes, split.nodes);
        assert_eq!(one.order, split.order);
        split.check(&prims).unwrap();
    }

    #[test]
    fn the_build_counts_every_primitive_into_its_progress() {
        let prims = random_prims(3000, 8);
        let progress = Progress::default();
        progress.start("BVH", prims.len() as u64);
        Bvh::build_split(&prims, Some(&progress), 64);
        assert_eq!(progress.snapshot().2, prims.len() as u64);
    }
}
