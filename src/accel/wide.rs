//! Four-wide BVH nodes with f32 boxes, and the traversal over them.
//!
//! The binary SAH tree of [`super::bvh`] is collapsed into nodes of up to four children (Embree's
//! BVH4): each node holds its children's boxes as f32 lanes, one SSE register per box plane, so
//! one node visit tests four boxes with a handful of instructions, in half the bytes per box of
//! the f64 nodes. Children are visited nearest first; the rest wait on a stack with their entry
//! distance, and are skipped when popped if a hit nearer than that has been found meanwhile.
//!
//! Exactness: the leaves hold the same shapes, tested in f64 as before, so only the box test
//! changed, and a box test may accept too much but must never reject a box holding a hit. The
//! f32 boxes are rounded outward (each plane one ulp beyond the f32 nearest to the f64 plane), so
//! they contain the padded f64 boxes. The f32 test ([`RayF32`], [`test_f32`]) is conservative in
//! exact arithmetic: it computes a lower bound of the entry distance and an upper bound of the
//! exit distance; the bound is derived at [`RayF32`]. Rays the f32 test cannot bound (a
//! direction component of 0, or coordinates beyond +-1e30) take the f64 slab test of the binary
//! tree ([`slab`]) on the same f32 boxes instead.

use crate::geometry::triangle::gamma;
use crate::geometry::Aabb;
use crate::math::{DVec3, Ray};
use std::mem::MaybeUninit;
use std::ops::Range;

/// Children per node: one SSE register of f32.
pub(super) const WIDTH: usize = 4;
/// Child slot that holds nothing (its box is empty, so no ray enters it).
const EMPTY: u32 = u32::MAX;
/// Traversal stack: a node visit pushes at most WIDTH - 1 entries, and the wide tree is no
/// deeper than the binary one, whose depth stays below `max_depth` (see `super::bvh`).
const fn stack_size(max_depth: usize) -> usize {
    (WIDTH - 1) * max_depth + 1
}
const STACK: usize = stack_size(super::bvh::MAX_DEPTH);
// Two cache lines a node.
const _: () = assert!(std::mem::size_of::<WideNode>() == 128);

/// A node: its children's boxes, plane by plane, and what each child is.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct WideNode {
    /// Rows min x, min y, min z, max x, max y, max z; lane j is child j. f32, rounded outward.
    planes: [[f32; WIDTH]; 6],
    /// Interior child: its node index. Leaf child: its first index into `order`/`shapes`.
    /// Empty slot: [`EMPTY`].
    child: [u32; WIDTH],
    /// Leaf child: its primitive count (1..=MAX_LEAF); interior child or empty slot: 0.
    count: [u8; WIDTH],
}

impl WideNode {
    const NONE: WideNode = WideNode {
        planes: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
        count: [0; WIDTH],
    };

    /// Child `j`'s box, in f64 (exactly the f32 planes).
    pub(super) fn child_box(&self, j: usize) -> Aabb {
        let p = |r: usize| self.planes[r][j] as f64;
        Aabb {
            min: DVec3::new(p(0), p(1), p(2)),
            max: DVec3::new(p(3), p(4), p(5)),
        }
    }

    /// Child `j`: None for an empty slot, else (index, count) with count 0 for a node.
    pub(super) fn child(&self, j: usize) -> Option<(u32, u8)> {
        (self.child[j] != EMPTY).then_some((self.child[j], self.count[j]))
    }

    /// Children held (for the cost probe). Inlined so that where the count goes unused it is
    /// not computed: out of line, it was a third of a query's time.
    #[inline(always)]
    fn slots(&self) -> u64 {
        self.child.map(|c| (c != EMPTY) as u64).iter().sum()
    }
}

/// `b`'s planes as the rows of [`WideNode::planes`], rounded outward: each one f32 step beyond
/// the f32 nearest the f64 plane (the cast is within half an ulp, so one step is beyond it).
fn outward(b: &Aabb) -> [f32; 6] {
    let below = |x: f64| (x as f32).next_down();
    let above = |x: f64| (x as f32).next_up();
    [
        below(b.min.x),
        below(b.min.y),
        below(b.min.z),
        above(b.max.x),
        above(b.max.y),
        above(b.max.z),
    ]
}

/// `x` rounded down to an f32.
fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x {
        f.next_down()
    } else {
        f
    }
}

/// What the collapse reads of a binary node.
pub(super) trait BinaryNode {
    fn bounds(&self) -> Aabb;
    /// Leaf: (first, count). Interior: None.
    fn leaf(&self) -> Option<(u32, u32)>;
    /// Interior: index of the second child (the first is the next node).
    fn second(&self) -> usize;
}

/// Collapse a binary tree (depth-first, first child next to its parent) into four-wide nodes:
/// a node takes its binary node's two children and keeps opening the interior child of largest
/// area until it has four (Wald et al. 2008), so the tree keeps the SAH's splits. Nodes come
/// out depth-first as well.
pub(super) fn collapse<N: BinaryNode>(bin: &[N]) -> Vec<WideNode> {
    let mut out = Vec::with_capacity(bin.len() / 3 + 1);
    if !bin.is_empty() {
        emit(bin, 0, &mut out);
    }
    out
}

fn emit<N: BinaryNode>(bin: &[N], root: usize, out: &mut Vec<WideNode>) -> u32 {
    let mut kids = [0usize; WIDTH];
    let mut n = 1;
    kids[0] = root;
    if bin[root].leaf().is_none() {
        kids[0] = root + 1;
        kids[1] = bin[root].second();
        n = 2;
        while n < WIDTH {
            let open = (0..n)
                .filter(|&i| bin[kids[i]].leaf().is_none())
                .max_by(|&a, &b| {
                    let area = |i: usize| bin[kids[i]].bounds().half_area();
                    area(a).total_cmp(&area(b))
                });
            let Some(i) = open else { break };
            let k = kids[i];
            kids.copy_within(i + 1..n, i + 2);
            kids[i] = k + 1;
            kids[i + 1] = bin[k].second();
            n += 1;
        }
    }
    let index = out.len();
    out.push(WideNode::NONE);
    for (j, &k) in kids[..n].iter().enumerate() {
        let planes = outward(&bin[k].bounds());
        let (child, count) = match bin[k].leaf() {
            Some((first, count)) => (first, count as u8),
            None => (emit(bin, k, out), 0),
        };
        let node = &mut out[index];
        for (row, p) in planes.into_iter().enumerate() {
            node.planes[row][j] = p;
        }
        node.child[j] = child;
        node.count[j] = count;
    }
    index as u32
}

/// Relative slack (eight unit roundoffs of f32) of what is rounded to f32 per query: the inverse
/// direction is scaled by 1 -+ 2^-21, the origin and the bound moved outward by 2^-21 of their
/// size, so rounding to nearest lands on the safe side.
const SHRINK: f64 = 1.0 / (1u64 << 21) as f64;
/// Coordinates and inverse-direction magnitudes the f32 test takes (inverse directions at least
/// 1 / LIMIT): their f32 copies stay finite and normal.
const LIMIT: f64 = 1e30;
/// Added to the exit distance before comparing: covers a product's absolute rounding error
/// when it falls into the subnormal range (at most 2^-150), where relative bounds do not hold.
/// The smallest normal f32, not 2^-148: a subnormal operand costs a microcode assist on every
/// node (it doubled the time of a one-primitive query).
const SLACK: f32 = f32::MIN_POSITIVE;

/// A ray prepared for the f32 box test.
///
/// Why the test is conservative. Per axis with direction d > 0, the near plane is the box's min
/// `lo` and the far plane its max `hi` (for d < 0 the two swap and the signs below flip; the
/// argument is the same). The exact entry distance along the axis is (lo - o) / d; we compute
/// `tn = fl(fl(lo - on) * in)` with `on` >= o an f32 and `in` <= |1/d| (1 - 6u),
/// u = 2^-24 the unit roundoff. If lo - on > 0, each of the two roundings adds at most a
/// factor (1 + u), so tn <= (lo - o) |1/d| (1 - 6u)(1 + u)^2 < (lo - o) / d; if lo - on <= 0,
/// tn <= 0. So tn <= max(0, exact), and `near = max(0, tn_x, tn_y, tn_z)` is at most the exact
/// entry distance (clamped at 0, as the f64 test does). Likewise the exit distance is computed
/// with an f32 <= o and `if_` >= |1/d| (1 + 6u): whenever the exact exit is >= 0 (which it
/// is when the ray meets the box at t >= 0), tf >= it, since fl(x) >= x (1 - u) for x > 0. The
/// bound (the current closest hit) is rounded up to f32. Hence near <= far whenever the exact
/// ray meets the f32 box within [0, bound]. Outside the normal range: a subtraction whose
/// result is subnormal is exact, a product that is adds at most 2^-150 and rounds to at most
/// 2^-126, so comparing with the exit distance plus [`SLACK`] = 2^-126 covers it;
/// overflow rounds to an infinity of the right sign, which keeps each inequality. No NaN can
/// arise: the origin and inverse direction are finite and nonzero (else the ray takes the f64
/// test), an empty slot's planes are infinities of the sign that makes it rejected.
///
/// The inverse direction: `1/d` in f64 is within 2^-53 of the exact one; scaling by
/// 1 - 2^-21 = 1 - 8u and casting to f32 (relative error <= u) keeps it below |1/d| (1 - 6u).
#[derive(Clone, Copy, Debug)]
pub(super) struct RayF32 {
    /// Per axis: the origin as rounded for the near plane's distance, and for the far plane's.
    o_near: [f32; 3],
    o_far: [f32; 3],
    /// Per axis: the inverse direction shrunk in magnitude (near), and grown (far).
    inv_near: [f32; 3],
    inv_far: [f32; 3],
    /// Per axis: the row of [`WideNode::planes`] holding the near plane, and the far plane.
    near_row: [usize; 3],
    far_row: [usize; 3],
}

impl RayF32 {
    /// None when the f32 test cannot bound this ray (see [`LIMIT`]). Branch-free but for that
    /// check: it runs once per query, and for small scenes it was a third of the query.
    #[inline]
    pub(super) fn new(ray: &Ray) -> Option<Self> {
        let inv = ray.d.recip();
        let (o, a) = (ray.o, inv.abs());
        // Negated comparisons so NaN falls back too.
        if !(o.abs().max_element() <= LIMIT
            && a.max_element() <= LIMIT
            && a.min_element() >= 1.0 / LIMIT)
        {
            return None;
        }
        // The origin moved outward before rounding to nearest: by 2^-21 relative (beyond the
        // cast's 2^-24) and 2^-126 absolute (beyond its absolute error where the f32 is
        // subnormal), so `up` >= o >= `down`; one ulp or two more than needed, no branches.
        let pad = o.abs() * SHRINK + f32::MIN_POSITIVE as f64;
        let (up, down) = ((o + pad).to_array(), (o - pad).to_array());
        let inv = inv.to_array();
        let mut r = RayF32 {
            o_near: [0.0; 3],
            o_far: [0.0; 3],
            inv_near: [0.0; 3],
            inv_far: [0.0; 3],
            near_row: [0; 3],
            far_row: [0; 3],
        };
        for k in 0..3 {
            let pos = inv[k] > 0.0;
            r.o_near[k] = (if pos { up[k] } else { down[k] }) as f32;
            r.o_far[k] = (if pos { down[k] } else { up[k] }) as f32;
            r.inv_near[k] = (inv[k] * (1.0 - SHRINK)) as f32;
            r.inv_far[k] = (inv[k] * (1.0 + SHRINK)) as f32;
            r.near_row[k] = k + 3 * (!pos as usize);
            r.far_row[k] = k + 3 * (pos as usize);
        }
        Some(r)
    }
}

/// The four lanes of f32 the box test computes with: SSE on x86-64 (part of the base ISA, so
/// the default build has it), plain arrays elsewhere.
#[cfg(target_arch = "x86_64")]
mod lanes4 {
    // SAFETY (every `unsafe` here): the intrinsics need SSE (and SSE2), which every x86-64
    // CPU has and every build for the target enables; loads and stores are unaligned.
    use std::arch::x86_64::*;

    #[derive(Clone, Copy)]
    pub struct F4(__m128);

    impl F4 {
        #[inline(always)]
        pub fn splat(x: f32) -> F4 {
            F4(unsafe { _mm_set1_ps(x) })
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> F4 {
            F4(unsafe { _mm_loadu_ps(a.as_ptr()) })
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            let mut a = [0.0f32; 4];
            unsafe { _mm_storeu_ps(a.as_mut_ptr(), self.0) };
            a
        }
        #[inline(always)]
        pub fn sub(self, b: F4) -> F4 {
            F4(unsafe { _mm_sub_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn mul(self, b: F4) -> F4 {
            F4(unsafe { _mm_mul_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn add(self, b: F4) -> F4 {
            F4(unsafe { _mm_add_ps(self.0, b.0) })
        }
        /// Lane-wise min/max; no NaN reaches them (see `RayF32`).
        #[inline(always)]
        pub fn min(self, b: F4) -> F4 {
            F4(unsafe { _mm_min_ps(self.0, b.0) })
        }
        #[inline(always)]
        pub fn max(self, b: F4) -> F4 {
            F4(unsafe { _mm_max_ps(self.0, b.0) })
        }
        /// Bit j set where lane j of self <= lane j of b.
        #[inline(always)]
        pub fn le_mask(self, b: F4) -> u32 {
            (unsafe { _mm_movemask_ps(_mm_cmple_ps(self.0, b.0)) }) as u32
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
mod lanes4 {
    #[derive(Clone, Copy)]
    pub struct F4([f32; 4]);

    impl F4 {
        #[inline(always)]
        pub fn splat(x: f32) -> F4 {
            F4([x; 4])
        }
        #[inline(always)]
        pub fn load(a: &[f32; 4]) -> F4 {
            F4(*a)
        }
        #[inline(always)]
        pub fn to_array(self) -> [f32; 4] {
            self.0
        }
        #[inline(always)]
        fn zip(self, b: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
            F4(std::array::from_fn(|i| f(self.0[i], b.0[i])))
        }
        #[inline(always)]
        pub fn sub(self, b: F4) -> F4 {
            self.zip(b, |x, y| x - y)
        }
        #[inline(always)]
        pub fn mul(self, b: F4) -> F4 {
            self.zip(b, |x, y| x * y)
        }
        #[inline(always)]
        pub fn add(self, b: F4) -> F4 {
            self.zip(b, |x, y| x + y)
        }
        #[inline(always)]
        pub fn min(self, b: F4) -> F4 {
            self.zip(b, |x, y| if x < y { x } else { y })
        }
        #[inline(always)]
        pub fn max(self, b: F4) -> F4 {
            self.zip(b, |x, y| if x > y { x } else { y })
        }
        #[inline(always)]
        pub fn le_mask(self, b: F4) -> u32 {
            (0..4).fold(0, |m, i| m | (((self.0[i] <= b.0[i]) as u32) << i))
        }
    }
}

use lanes4::F4;

/// The f32 test of a node's four boxes for t in [0, bound]: bit j of the mask set if child j
/// may be hit, and lane j a lower bound of its entry distance. `bound` is the f64 bound rounded
/// up ([`Fast::set_bound`]).
#[inline(always)]
pub(super) fn test_f32(n: &WideNode, r: &RayF32, bound: f32) -> (u32, [f32; WIDTH]) {
    let axis = |k: usize| {
        let near = F4::load(&n.planes[r.near_row[k]])
            .sub(F4::splat(r.o_near[k]))
            .mul(F4::splat(r.inv_near[k]));
        let far = F4::load(&n.planes[r.far_row[k]])
            .sub(F4::splat(r.o_far[k]))
            .mul(F4::splat(r.inv_far[k]));
        (near, far)
    };
    let (nx, fx) = axis(0);
    let (ny, fy) = axis(1);
    let (nz, fz) = axis(2);
    let near = nx.max(ny).max(nz.max(F4::splat(0.0)));
    let far = fx.min(fy).min(fz.min(F4::splat(bound)));
    (near.le_mask(far.add(F4::splat(SLACK))), near.to_array())
}

/// The binary tree's f64 slab test for t in [0, t_max], returning the entry distance: the far
/// distance is widened by its rounding bound (pbrt-v4's 1 + 2 gamma(3)), so a ray grazing the box
/// is never rejected wrongly.
#[inline]
pub(super) fn slab(b: &Aabb, o: DVec3, inv: DVec3, t_max: f64) -> Option<f64> {
    let t0 = (b.min - o) * inv;
    let t1 = (b.max - o) * inv;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element() * (1.0 + 2.0 * gamma(3.0));
    (near <= far && near <= t_max).then_some(near)
}

/// A node test and its view of the bound.
trait NodeTest {
    /// The bound fell to `bound` (a closer hit).
    fn set_bound(&mut self, bound: f64);
    /// Whether an entry distance from [`Self::test`] lies beyond the bound.
    fn beyond(&self, near: f32) -> bool;
    /// Mask of children that may be hit, and lower bounds of their entry distances.
    fn test(&self, n: &WideNode) -> (u32, [f32; WIDTH]);
}

struct Fast {
    ray: RayF32,
    /// The bound rounded up, and that plus [`SLACK`] (for popped entries).
    bound: f32,
    cull: f32,
}

impl Fast {
    fn new(ray: RayF32, bound: f64) -> Fast {
        let mut f = Fast {
            ray,
            bound: 0.0,
            cull: 0.0,
        };
        f.set_bound(bound);
        f
    }
}

impl NodeTest for Fast {
    #[inline(always)]
    fn set_bound(&mut self, bound: f64) {
        // Rounded up without branches (it runs after every leaf): moved up by 2^-21 relative
        // and 2^-126 absolute, beyond the cast's rounding. (A negative bound admits no hit;
        // then any bound will do.)
        self.bound = (bound * (1.0 + SHRINK) + f32::MIN_POSITIVE as f64) as f32;
        self.cull = self.bound + SLACK;
    }
    #[inline(always)]
    fn beyond(&self, near: f32) -> bool {
        near > self.cull
    }
    #[inline(always)]
    fn test(&self, n: &WideNode) -> (u32, [f32; WIDTH]) {
        test_f32(n, &self.ray, self.bound)
    }
}

/// The f64 test, one child at a time, for rays the f32 test cannot take.
struct Exact {
    o: DVec3,
    inv: DVec3,
    bound: f64,
}

impl NodeTest for Exact {
    fn set_bound(&mut self, bound: f64) {
        self.bound = bound;
    }
    fn beyond(&self, near: f32) -> bool {
        near as f64 > self.bound
    }
    fn test(&self, n: &WideNode) -> (u32, [f32; WIDTH]) {
        let mut mask = 0;
        let mut near = [0.0; WIDTH];
        for (j, lane) in near.iter_mut().enumerate() {
            if n.child[j] == EMPTY {
                continue;
            }
            if let Some(t) = slab(&n.child_box(j), self.o, self.inv, self.bound) {
                mask |= 1 << j;
                *lane = round_down(t);
            }
        }
        (mask, near)
    }
}

/// Ask for both cache lines of a child node as soon as its box is hit: the nearest is loaded
/// right after this node's sort and push, the others when popped, and a node load missing the
/// cache was a third of a query's time on large meshes (benches/HISTORY.md#node-prefetch).
#[inline(always)]
fn prefetch(n: &WideNode) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint: it never faults, and the address is a node's.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let p = (n as *const WideNode).cast::<i8>();
        _mm_prefetch(p, _MM_HINT_T0);
        _mm_prefetch(p.add(64), _MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = n;
}

/// A child waiting to be visited, with a lower bound of its entry distance.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u32,
    near: f32,
}

/// The one traversal behind every query: a depth-first walk over the children whose boxes the
/// ray meets within the bound (t_max to start with). Each leaf's range of `order`/`shapes` goes
/// to `leaf`, which may lower the bound (closest hit) and returns true to end the walk (any
/// hit). `ORDERED` visits a node's children nearest first and skips popped ones beyond the
/// bound (closest hit); unordered, in slot order. Returns the number of child boxes tested (for
/// the cost probe; unused, it compiles away).
#[inline(always)]
pub(super) fn traverse<const ORDERED: bool>(
    nodes: &[WideNode],
    ray: &Ray,
    t_max: f64,
    leaf: impl FnMut(Range<usize>, &mut f64) -> bool,
) -> u64 {
    if nodes.is_empty() {
        return 0;
    }
    match RayF32::new(ray) {
        Some(r) => walk::<ORDERED, _, _>(nodes, Fast::new(r, t_max), t_max, leaf),
        None => walk_exact::<ORDERED, _>(nodes, ray, t_max, leaf),
    }
}

/// The walk with the f64 test: rare (axis-parallel rays), so kept out of line.
#[cold]
#[inline(never)]
fn walk_exact<const ORDERED: bool, F: FnMut(Range<usize>, &mut f64) -> bool>(
    nodes: &[WideNode],
    ray: &Ray,
    t_max: f64,
    leaf: F,
) -> u64 {
    let test = Exact {
        o: ray.o,
        inv: ray.d.recip(),
        bound: t_max,
    };
    walk::<ORDERED, _, _>(nodes, test, t_max, leaf)
}

#[inline(always)]
fn walk<const ORDERED: bool, T: NodeTest, F: FnMut(Range<usize>, &mut f64) -> bool>(
    nodes: &[WideNode],
    mut test: T,
    t_max: f64,
    mut leaf: F,
) -> u64 {
    let mut bound = t_max;
    let mut boxes = 0u64;
    let mut stack = [const { MaybeUninit::<Entry>::uninit() }; STACK];
    let mut sp = 0usize;
    let mut node = 0usize;
    loop {
        let n = &nodes[node];
        boxes += n.slots();
        let (mask, near) = test.test(n);
        let mut next = None;
        if mask != 0 {
            let mut hits = [Entry {
                child: 0,
                count: 0,
                near: 0.0,
            }; WIDTH];
            let mut k = 0;
            let mut m = mask;
            while m != 0 {
                let j = m.trailing_zeros() as usize;
                m &= m - 1;
                hits[k] = Entry {
                    child: n.child[j],
                    count: n.count[j] as u32,
                    near: near[j],
                };
                if hits[k].count == 0 {
                    prefetch(&nodes[hits[k].child as usize]);
                }
                k += 1;
            }
            if ORDERED {
                // Insertion sort of at most four.
                for i in 1..k {
                    let mut p = i;
                    while p > 0 && hits[p - 1].near > hits[p].near {
                        hits.swap(p - 1, p);
                        p -= 1;
                    }
                }
            }
            // The farther ones wait, the farthest deepest.
            for e in hits[1..k].iter().rev() {
                stack[sp].write(*e);
                sp += 1;
            }
            next = Some(hits[0]);
        }
        // Go to the next node, running the leaves met on the way.
        loop {
            let e = match next.take() {
                Some(e) => e,
                None => {
                    if sp == 0 {
                        return boxes;
                    }
                    sp -= 1;
                    // SAFETY: every slot below the pointer was written by a push above.
                    let e = unsafe { stack[sp].assume_init() };
                    if ORDERED && test.beyond(e.near) {
                        continue;
                    }
                    e
                }
            };
            if e.count == 0 {
                node = e.child as usize;
                break;
            }
            let first = e.child as usize;
            if leaf(first..first + e.count as usize, &mut bound) {
                return boxes;
            }
            test.set_bound(bound);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{warp, Rng};

    /// `b` rounded outward as a node holds it, in f64.
    fn rounded(b: &Aabb) -> Aabb {
        node_of(b).child_box(0)
    }

    /// A node whose four slots all hold `b` rounded outward.
    fn node_of(b: &Aabb) -> WideNode {
        let mut n = WideNode::NONE;
        for (row, v) in outward(b).into_iter().enumerate() {
            n.planes[row] = [v; WIDTH];
        }
        n.child = [0; WIDTH];
        n
    }

    /// Nudge `x` by up to `k` ulps either way.
    fn jiggle(x: f64, k: u64, rng: &mut Rng) -> f64 {
        let steps = (rng.next_u64() % (2 * k + 1)) as i64 - k as i64;
        let mut y = x;
        for _ in 0..steps.unsigned_abs() {
            y = if steps > 0 {
                y.next_up()
            } else {
                y.next_down()
            };
        }
        y
    }

    /// Random boxes at scales from 1e-6 to 1e4 and offsets up to 1e5, and rays grazing them:
    /// aimed at a point on a face, edge or corner (nudged by a few ulps), from near and far,
    /// in directions from random to nearly parallel to a face, with bounds just around the
    /// entry distance. Whenever the f64 test of the binary tree accepts the f64 box, the f32
    /// test must accept its rounded box; and it must accept whenever an exactly computed point
    /// of the ray at t in [0, bound] lies in the f64 box.
    #[test]
    fn the_f32_test_never_rejects_what_the_f64_test_accepts() {
        let mut rng = Rng::new(2026);
        let mut accepted = 0u64;
        let trials = 400_000;
        for i in 0..trials {
            let scale = 10f64.powf(-6.0 + 10.0 * rng.next_f64());
            let offset = 10f64.powf(-2.0 + 7.0 * rng.next_f64()) * (rng.next_f64() - 0.5);
            let c = DVec3::new(
                offset * rng.next_f64(),
                offset * rng.next_f64(),
                offset * rng.next_f64(),
            );
            let half = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * scale;
            // Now and then a flat box (a triangle in an axis plane).
            let half = if i % 7 == 0 {
                DVec3::new(half.x, 0.0, half.z)
            } else {
                half
            };
            let b = Aabb {
                min: c - half,
                max: c + half,
            };
            // A target on the box's boundary: each axis at min, max or inside.
            let pick = |lo: f64, hi: f64, rng: &mut Rng| match rng.next_u64() % 3 {
                0 => lo,
                1 => hi,
                _ => lo + (hi - lo) * rng.next_f64(),
            };
            let target = DVec3::new(
                jiggle(pick(b.min.x, b.max.x, &mut rng), 4, &mut rng),
                jiggle(pick(b.min.y, b.max.y, &mut rng), 4, &mut rng),
                jiggle(pick(b.min.z, b.max.z, &mut rng), 4, &mut rng),
            );
            let mut d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            if i % 3 == 0 {
                // Nearly parallel to a face.
                let k = (rng.next_u64() % 3) as usize;
                let mut a = d.to_array();
                a[k] *= 10f64.powf(-12.0 * rng.next_f64());
                d = DVec3::from_array(a).normalize();
            }
            let dist = scale * 10f64.powf(-3.0 + 6.0 * rng.next_f64());
            let o = if i % 11 == 0 {
                target // starts on the boundary
            } else {
                target - d * dist
            };
            let ray = Ray::new(o, d);
            let inv = d.recip();
            let bound = match rng.next_u64() % 4 {
                0 => f64::INFINITY,
                1 => dist * (1.0 + 1e-7 * (rng.next_f64() - 0.5)),
                2 => jiggle(dist, 8, &mut rng),
                _ => dist * 2.0 * rng.next_f64(),
            };
            let Some(r) = RayF32::new(&ray) else {
                continue;
            };
            let (mask, near) = Fast::new(r, bound).test(&node_of(&b));
            let f64_accepts = slab(&b, o, inv, bound).is_some();
            // An exactly rounded point inside the box at a t within the bound.
            let t = dist.min(bound);
            let p = ray.at(t);
            let inside = (b.min.cmple(p) & p.cmple(b.max)).all() && t >= 0.0;
            if f64_accepts || inside {
                accepted += 1;
                assert_eq!(
                    mask, 0b1111,
                    "false rejection: box {b:?} ray {ray:?} bound {bound} near {near:?}"
                );
                // The entry bound is below the f64 entry distance (up to f32 rounding).
                if let Some(t64) = slab(&rounded(&b), o, inv, bound) {
                    assert!(near[0] as f64 <= t64 * (1.0 + 1e-6) + 1e-30);
                }
            }
        }
        // The cases are mostly the hard ones: most are accepted.
        assert!(accepted > trials as u64 / 4, "{accepted} of {trials}");
    }

    #[test]
    fn rays_the_f32_test_cannot_bound_are_sent_to_the_f64_test() {
        let o = DVec3::splat(0.5);
        assert!(RayF32::new(&Ray::new(o, DVec3::X)).is_none());
        assert!(RayF32::new(&Ray::new(DVec3::splat(1e31), DVec3::ONE.normalize())).is_none());
        assert!(RayF32::new(&Ray::new(o, DVec3::splat(f64::NAN))).is_none());
        assert!(RayF32::new(&Ray::new(o, DVec3::ONE.normalize())).is_some());
    }

    #[test]
    fn an_empty_slot_is_never_entered() {
        let mut rng = Rng::new(5);
        let n = WideNode::NONE;
        for _ in 0..1000 {
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 10.0 - 5.0;
            let d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            if let Some(r) = RayF32::new(&Ray::new(o, d)) {
                assert_eq!(test_f32(&n, &r, f32::INFINITY).0, 0);
            }
        }
    }
}
