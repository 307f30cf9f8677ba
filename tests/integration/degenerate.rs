//! Degenerate geometry, exactly: rays tangent to a sphere (the discriminant is exactly zero),
//! rays a relative 1e-12 inside and outside the silhouette, and light sampling from points on
//! every axis (so the cone's frame is built around normals exactly along +-x, +-y, +-z).

use ptui::geometry::{spawn_origin, Sphere};
use ptui::light::sphere::SphereLight;
use ptui::math::{DVec3, Ray};
use ptui::sampling::Rng;

/// (centre, radius): unit, far away, huge, tiny and far, tiny.
const SPHERES: &[([f64; 3], f64)] = &[
    ([0.0, 0.0, 0.0], 1.0),
    ([1e6, -1e6, 1e6], 1.0),
    ([50.0, 1e5, 81.6], 1e5),
    ([1e4, 1e4, -1e4], 1e-3),
    ([0.0, 0.0, 0.0], 1e-12),
];

#[test]
fn rays_through_the_silhouette() {
    for &(c, r) in SPHERES {
        let s = Sphere::new(DVec3::from_array(c), r);
        // Along +z at an x offset of exactly r from the centre (exact when c.x + r is).
        for (x_rel, expect_hit) in [(1.0 - 1e-12, true), (1.0 + 1e-12, false), (1.0, false)] {
            let o = s.center + DVec3::new(r * x_rel, 0.0, -10.0 * r);
            let ray = Ray::new(o, DVec3::Z);
            let t = s.intersect(&ray, f64::INFINITY);
            if x_rel == 1.0 {
                // Exactly tangent: a grazing hit or a miss are both right; it must be finite.
                if let Some(t) = t {
                    let hit = s.hit(&ray, t, 0);
                    assert!(hit.p.is_finite() && hit.n.is_finite(), "{c:?} {r}");
                    assert!((hit.n.length() - 1.0).abs() < 1e-12);
                    // A mirror bounce off the grazing hit leaves the surface: no second hit.
                    let wo = -ray.d;
                    let wi = hit.n * (2.0 * wo.dot(hit.n)) - wo;
                    let o2 = spawn_origin(hit.p, hit.n, hit.err, wi);
                    let again = s.intersect(&Ray::new(o2, wi), f64::INFINITY);
                    assert!(again.is_none(), "{c:?} {r}: re-hit at {again:?}");
                    // Passing straight on (index-matched glass): rounding may put d a hair
                    // inside (d.n = -2e-16 for r = 1e5); the ray then crosses a sliver of the
                    // sphere and leaves it, finite, on the outward side.
                    let o3 = spawn_origin(hit.p, hit.n, hit.err, ray.d);
                    if let Some(t3) = s.intersect(&Ray::new(o3, ray.d), f64::INFINITY) {
                        let exit = s.hit(&Ray::new(o3, ray.d), t3, 0);
                        assert!(t3 > 0.0 && t3.is_finite() && exit.n.dot(ray.d) >= 0.0);
                    }
                }
                continue;
            }
            // 1e-12 relative is resolvable only where r is not swamped by |c| (err ~ 1e-16 |c|).
            if r * 1e-12 < 1e-15 * (s.center.abs().max_element() + r) {
                continue;
            }
            assert_eq!(t.is_some(), expect_hit, "centre {c:?} r {r} x {x_rel}");
        }
    }
}

#[test]
fn light_sampling_from_every_axis() {
    let mut rng = Rng::new(1);
    for &(c, r) in SPHERES {
        let sphere = Sphere::new(DVec3::from_array(c), r);
        let light = SphereLight::new(0, sphere, DVec3::ONE);
        for axis in ptui::math::SIGNED_AXES {
            // A point 3 radii out along the axis: the cone's axis is exactly -axis.
            let p = sphere.center + axis * (3.0 * r);
            for _ in 0..1000 {
                let ls = light
                    .sample(p, p, (rng.next_f64(), rng.next_f64()))
                    .expect("a light in view can be sampled");
                assert!(ls.wi.is_finite() && ls.pdf.is_finite() && ls.pdf > 0.0);
                assert!((ls.wi.length() - 1.0).abs() < 1e-12);
                assert!(
                    sphere
                        .intersect(&Ray::new(p, ls.wi), f64::INFINITY)
                        .is_some(),
                    "sample from {p:?} along {:?} misses the light",
                    ls.wi
                );
            }
        }
    }
}
