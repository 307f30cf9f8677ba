//! The BVH against the flat scan: the same closest hit (primitive and distance, bit for bit) and
//! the same any-hit answer for random rays over random scenes, and its structural invariants.
//! The renderer's flat scan (spheres in lanes) is held to the same reference.

use proptest::prelude::*;
use ptui::accel::{bench, flat, flat::FlatScan, Bvh};
use ptui::geometry::{Primitive, Shape};
use ptui::geometry::{Sphere, Triangle};
use ptui::math::{DVec3, Ray};
use ptui::sampling::{warp, Rng};

/// Random primitives plus the stiff cases: exact duplicates (equal distances, where the lower
/// index must win), a huge smallpt-style wall sphere, and a degenerate triangle.
fn scene(n: usize, seed: u64, extras: bool) -> Vec<Primitive> {
    let mut prims = bench::random_prims(n, seed);
    if extras {
        let dup: Vec<Primitive> = prims.iter().step_by(3).copied().collect();
        prims.extend(dup);
        let prim = |shape| Primitive {
            shape,
            material: 0,
            light: None,
        };
        prims.push(prim(Shape::Sphere(Sphere::new(
            DVec3::new(0.5, -1e5, 0.5),
            1e5 - 0.05,
        ))));
        prims.push(prim(Shape::Triangle(Triangle::new(
            DVec3::ZERO,
            DVec3::ONE,
            DVec3::ONE * 2.0,
        ))));
        // Rotate so duplicates are not all at the end.
        let k = (seed as usize) % prims.len();
        prims.rotate_left(k);
    }
    prims
}

fn rays(count: usize, seed: u64) -> Vec<(Ray, f64)> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| {
            // Origins inside and outside the unit cube; axis-aligned directions now and then.
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 3.0 - DVec3::ONE;
            let mut d = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
            if rng.next_f64() < 0.1 {
                d = [DVec3::X, -DVec3::Y, DVec3::Z][(rng.next_u64() % 3) as usize];
            }
            let t_max = if rng.next_f64() < 0.5 {
                f64::INFINITY
            } else {
                rng.next_f64() * 2.0
            };
            (Ray::new(o, d), t_max)
        })
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn bvh_matches_flat_scan(n in 1usize..400, seed in any::<u64>(), extras in any::<bool>()) {
        let prims = scene(n, seed, extras);
        let bvh = Bvh::build(&prims);
        let lanes = FlatScan::new(&prims);
        prop_assert_eq!(bvh.check(&prims), Ok(()));
        for (ray, t_max) in rays(300, seed ^ 1) {
            let key = |h: Option<ptui::geometry::Hit>| h.map(|h| (h.prim, h.t.to_bits()));
            let a = key(flat::intersect(&prims, &ray, t_max));
            prop_assert_eq!(a, key(bvh.intersect(&prims, &ray, t_max)));
            prop_assert_eq!(a, key(lanes.intersect(&prims, &ray, t_max)));
            prop_assert_eq!(
                flat::any_hit(&prims, &ray, t_max),
                bvh.any_hit(&ray, t_max)
            );
        }
    }
}

#[test]
fn invariants_hold_for_large_and_degenerate_inputs() {
    // Many primitives, and many sharing one centroid (no positional split possible).
    let mut prims = bench::random_prims(20_000, 9);
    let same = Primitive {
        shape: Shape::Sphere(Sphere::new(DVec3::splat(0.5), 0.01)),
        material: 0,
        light: None,
    };
    prims.extend(std::iter::repeat_n(same, 100));
    let bvh = Bvh::build(&prims);
    assert_eq!(bvh.check(&prims), Ok(()));
    assert!(bvh.probe_cost(&bench::random_rays(100, 1)) < prims.len() as f64);
    // Empty and single-primitive scenes.
    assert_eq!(Bvh::build(&[]).check(&[]), Ok(()));
    let one = &prims[..1];
    assert_eq!(Bvh::build(one).check(one), Ok(()));
}
