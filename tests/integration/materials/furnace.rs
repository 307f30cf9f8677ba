//! White furnace of the microfacet distributions: a conductor without Fresnel (reflectance 1)
//! in a uniform environment of radiance 1 returns its directional albedo
//!
//!   A(mu) = int D(h) G1(o, h) G1(i, h) / (4 mu) d(omega_i)
//!         = int D(h) G1(o, h) G1(i, h) (o . h) / mu d(omega_h)   (d omega_i = 4 (o . h) d omega_h),
//!
//! which is below 1 by what Smith's masking loses (the rays a microsurface would reflect into
//! itself). Here A is integrated numerically from the formulas of Walter et al. 2007 (GGX and
//! Beckmann D, Smith's G1; Beckmann's G1 is the rational fit Walter gives, the one Mitsuba and
//! ptui use) written out in this file, not by calling ptui's microfacet code. Two furnaces use
//! it: the mean of `sample`'s weights at one `wo`, and a rendered sphere, where each pixel sees
//! the albedo at its own cos(theta_o) (a convex sphere reflects each ray once).

use super::{beckmann, conductor, dir, ggx};
use crate::common::{load_str, render};
use ptui::analysis::stats::bonferroni_z;
use ptui::geometry::Normals;
use ptui::material::{ConductorFresnel, Distribution};
use ptui::math::DVec3;
use ptui::sampling::{Rng, SamplerKind};
use ptui::settings::SettingsOverrides;
use std::f64::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Ndf {
    Ggx,
    Beckmann,
    /// Beckmann with its exact Smith G1 (through erf) instead of the fit: only to measure
    /// what the fit changes.
    BeckmannExact,
}

impl Ndf {
    fn distribution(self, alpha: f64) -> Distribution {
        match self {
            Ndf::Ggx => ggx(alpha, alpha),
            _ => beckmann(alpha, alpha),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Ndf::Ggx => "ggx",
            _ => "beckmann",
        }
    }
}

/// D(h) for a normal at cos_h to the surface's: GGX, Walter's eq. 33, and Beckmann, eq. 25.
fn ndf(kind: Ndf, alpha: f64, cos_h: f64) -> f64 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let c2 = cos_h * cos_h;
    let (a2, tan2) = (alpha * alpha, (1.0 - c2) / c2);
    match kind {
        Ndf::Ggx => a2 / (PI * c2 * c2 * (a2 + tan2).powi(2)),
        _ => (-tan2 / a2).exp() / (PI * a2 * c2 * c2),
    }
}

/// Smith's G1 of direction `v` over microfacet `h`: zero where v sees the facet's back; GGX by
/// Walter's eq. 34, Beckmann by the rational fit of his eq. 27 (or exactly, eq. 26's erf form).
fn smith_g1(kind: Ndf, alpha: f64, v: DVec3, h: DVec3) -> f64 {
    if v.dot(h) * v.z <= 0.0 {
        return 0.0;
    }
    let tan2 = (1.0 - v.z * v.z).max(0.0) / (v.z * v.z);
    if tan2 == 0.0 {
        return 1.0;
    }
    let a = 1.0 / (alpha * tan2.sqrt());
    match kind {
        Ndf::Ggx => 2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt()),
        Ndf::Beckmann if a >= 1.6 => 1.0,
        Ndf::Beckmann => (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a),
        Ndf::BeckmannExact => {
            let lambda = 0.5 * (statrs::function::erf::erf(a) - 1.0)
                + (-a * a).exp() / (2.0 * a * PI.sqrt());
            1.0 / (1.0 + lambda)
        }
    }
}

/// Quadrature nodes: in the distribution's core, its tail, and azimuth.
#[derive(Clone, Copy, Debug)]
struct Nodes {
    core: usize,
    tail: usize,
    phi: usize,
}

impl Nodes {
    fn doubled(self) -> Self {
        Nodes {
            core: 2 * self.core,
            tail: 2 * self.tail,
            phi: 2 * self.phi,
        }
    }
}

/// The nodes [`albedo`] uses.
const NODES: Nodes = Nodes {
    core: 256,
    tail: 384,
    phi: 64,
};
/// What [`albedo`]'s quadrature is good to (tested by `the_albedo_integral_converges`): the
/// integrand has a kink where reflections reach the horizon (G1 of a grazing direction falls
/// linearly to 0), which holds Simpson's rule to second order there, so its error is about 4/3
/// of what doubling the nodes changes. Well below the furnaces' standard errors (1e-3 to 1e-4)
/// except where every weight is 1 (Beckmann's short tail at normal incidence), where the
/// integral is exact to 1e-7.
const QUADRATURE_ERROR: f64 = 1e-4;
/// Where the core ends: tan(theta_h) = CORE alpha.
const CORE: f64 = 3.0;

/// Composite Simpson's rule for the integral of `g` over [a, b] on `n` (even) intervals.
fn simpson(a: f64, b: f64, n: usize, g: impl Fn(f64) -> f64) -> f64 {
    let h = (b - a) / n as f64;
    let inner: f64 = (1..n)
        .map(|k| g(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 })
        .sum();
    (g(a) + inner + g(b)) * h / 3.0
}

/// The integral of `f(h)` D(h) cos(h) over the hemisphere of microfacet normals, by Simpson's
/// rule in theta and the midpoint rule in phi, in two parts. The core, tan(theta_h) < 8 alpha, in v with tan(theta_h) = alpha tan(v):
/// that puts the nodes where D is, whatever alpha, and makes D cos(h) d(omega) a smooth density
/// in v (sin(2 v) / 4 for GGX). The tail, uniform in ln(theta_h): D falls there as a power of
/// theta_h, and the masking of reflections that graze the surface changes over a few alpha of
/// theta_h, which the core's variable would sample too sparsely (an error of 1e-4 at alpha
/// 0.05). `f` is even in phi (the view lies in
/// the xz plane), so phi runs over [0, pi] only.
fn integrate_ndf(kind: Ndf, alpha: f64, nodes: Nodes, f: impl Fn(DVec3) -> f64) -> f64 {
    // The integral over phi of the ring at theta, times d(theta)/d(variable).
    let ring = |theta: f64, dtheta: f64| {
        let (sin_t, cos_t) = theta.sin_cos();
        let weight = ndf(kind, alpha, cos_t) * cos_t * sin_t * dtheta;
        let mut sum = 0.0;
        for b in 0..nodes.phi {
            let phi = PI * (b as f64 + 0.5) / nodes.phi as f64;
            sum += f(DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
        }
        weight * sum * 2.0 * PI / nodes.phi as f64
    };
    let core = simpson(0.0, CORE.atan(), nodes.core, |v| {
        let dtheta_dv = alpha / (v.cos().powi(2) + (alpha * v.sin()).powi(2));
        ring((alpha * v.tan()).atan(), dtheta_dv)
    });
    let tail = simpson(
        (CORE * alpha).atan().ln(),
        (0.5 * PI).ln(),
        nodes.tail,
        |w| {
            let theta = w.exp();
            ring(theta, theta)
        },
    );
    core + tail
}

/// The directional albedo A(mu) of a Fresnel-free microfacet reflector (module docs).
fn albedo(kind: Ndf, alpha: f64, mu: f64, nodes: Nodes) -> f64 {
    let o = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    integrate_ndf(kind, alpha, nodes, |h| {
        let oh = o.dot(h);
        let i = h * (2.0 * oh) - o;
        if oh <= 0.0 || i.z <= 0.0 {
            return 0.0;
        }
        smith_g1(kind, alpha, o, h) * smith_g1(kind, alpha, i, h) * oh / (mu * h.z)
    })
}

/// The reference is only as good as its quadrature: D integrates to 1 over the projected
/// hemisphere (which also checks the D formulas against their normalisation), the albedo
/// changes by less than 7.5e-5 when the nodes are doubled, it tends to 1 where masking
/// vanishes (normal incidence on a nearly smooth surface), and the rendered furnace's table of
/// it interpolates to within 1e-4 halfway between its nodes.
#[test]
fn the_albedo_integral_converges() {
    for kind in [Ndf::Ggx, Ndf::Beckmann] {
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            let norm = integrate_ndf(kind, alpha, NODES, |_| 1.0);
            assert!(
                (norm - 1.0).abs() < QUADRATURE_ERROR,
                "{kind:?} {alpha}: {norm}"
            );
            for mu in [1.0, 0.5, 0.1, 0.01] {
                let a = albedo(kind, alpha, mu, NODES);
                let fine = albedo(kind, alpha, mu, NODES.doubled());
                assert!(
                    (a - fine).abs() < 0.75 * QUADRATURE_ERROR,
                    "{kind:?} {alpha} {mu}: {a} vs {fine}"
                );
            }
        }
        let a = albedo(kind, 1e-3, 1.0, NODES);
        assert!((a - 1.0).abs() < QUADRATURE_ERROR, "{kind:?}: {a}");
        for alpha in [0.05, 1.0] {
            let table = Table::new(kind, alpha);
            for k in [1, 3, 10, 30, Table::K - 2] {
                let s = (k as f64 + 0.5) / Table::K as f64;
                let (got, want) = (table.at(s * s), albedo(kind, alpha, s * s, NODES));
                assert!(
                    (got - want).abs() < QUADRATURE_ERROR,
                    "{kind:?} {alpha} table at {}: {got} vs {want}",
                    s * s
                );
            }
        }
    }
}

/// The albedo as the mean weight of `sample` at one `wo`, against [`albedo`]: every weight
/// (G1(wi), 0 for a rejected draw) counts, so a weight without G1, a sampler that draws normals
/// not in proportion to D G1(wo) |wo.h| / cos_o, or a G1 of the wrong form moves the mean. The
/// tolerance is the weights' own standard error (Bonferroni over the 40 cases at 1e-3) and the
/// integral's.
#[test]
fn mean_sample_weight_is_the_albedo() {
    let cases = 40;
    let z_limit = bonferroni_z(1e-3, cases);
    let n = 40_000;
    let mut rng = Rng::new(0xf0a);
    let mut worst: f64 = 0.0;
    for kind in [Ndf::Ggx, Ndf::Beckmann] {
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            let m = conductor(Some(kind.distribution(alpha)), ConductorFresnel::None);
            for mu in [1.0, 0.7, 0.3, 0.1, 0.02] {
                let wo = dir(mu, 0.0, false);
                let (mut sum, mut sum2) = (0.0, 0.0);
                for _ in 0..n {
                    let u = (rng.next_f64(), rng.next_f64());
                    let w = m
                        .sample(wo, Normals::flat(DVec3::Z), rng.next_f64(), u)
                        .map_or(0.0, |s| s.weight.x);
                    sum += w;
                    sum2 += w * w;
                }
                let mean = sum / n as f64;
                let se = ((sum2 / n as f64 - mean * mean) / (n - 1) as f64).sqrt();
                let want = albedo(kind, alpha, mu, NODES);
                // At normal incidence on Beckmann's short tail every weight is exactly 1.
                let z = (mean - want) / (se * se + QUADRATURE_ERROR * QUADRATURE_ERROR).sqrt();
                eprintln!(
                    "{kind:?} alpha {alpha} mu {mu}: mean weight {mean:.5} +- {se:.5}, \
                     integral {want:.5}, z {z:.2}"
                );
                worst = worst.max(z.abs());
                assert!(z.abs() < z_limit, "{kind:?} {alpha} {mu}: z = {z:.2}");
            }
        }
    }
    eprintln!("worst |z| {worst:.2} (limit {z_limit:.2})");
}

/// What Beckmann's rational G1 (under 0.35% from the exact one, Walter's claim) moves the
/// albedo by: printed, and bounded by the claim compounded over the two G1s.
#[test]
fn beckmanns_fitted_masking_is_close_to_the_exact_one() {
    let mut worst: f64 = 0.0;
    for alpha in [0.05, 0.2, 0.5, 1.0] {
        for mu in [1.0, 0.5, 0.1, 0.02] {
            let fit = albedo(Ndf::Beckmann, alpha, mu, NODES);
            let exact = albedo(Ndf::BeckmannExact, alpha, mu, NODES);
            worst = worst.max((fit / exact - 1.0).abs());
        }
    }
    eprintln!("Beckmann albedo, fitted G1 against exact: largest relative difference {worst:.2e}");
    assert!(worst < 2.0 * 0.0035, "{worst}");
}

/// A table of A(mu) at mu = (k / K)^2 (dense at grazing angles, where A changes fastest),
/// read by cubic (Catmull-Rom) interpolation in sqrt(mu).
struct Table(Vec<f64>);

impl Table {
    const K: usize = 48;

    fn new(kind: Ndf, alpha: f64) -> Self {
        Table(
            (0..=Self::K)
                .map(|k| {
                    let s = k as f64 / Self::K as f64;
                    albedo(kind, alpha, (s * s).max(1e-9), NODES)
                })
                .collect(),
        )
    }

    fn at(&self, mu: f64) -> f64 {
        let x = mu.clamp(0.0, 1.0).sqrt() * Self::K as f64;
        let i = (x as usize).min(Self::K - 1);
        let t = x - i as f64;
        let p = |j: isize| self.0[(i as isize + j).clamp(0, Self::K as isize) as usize];
        let (p0, p1, p2, p3) = (p(-1), p(0), p(1), p(2));
        p1 + 0.5
            * t
            * (p2 - p0
                + t * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + t * (3.0 * (p1 - p2) + p3 - p0)))
    }
}

/// What a pixel of the furnace render should read, and whether the sphere covers all of it:
/// the albedo (or the environment's 1 where the footprint misses the sphere) averaged over the
/// pixel's square, on an n x n grid (8, or 64 across the silhouette, where coverage changes),
/// and the cos(theta_o) at the pixel's centre.
fn expected_pixel(
    scene: &ptui::scene::Scene,
    table: &Table,
    x: u32,
    y: u32,
    size: u32,
) -> (f64, bool, f64) {
    // The unit sphere at the origin, |o + t d|^2 = 1: the cosine at the hit, None for a miss.
    let cos_at = |fx: f64, fy: f64| {
        let r = scene.camera.ray(size, size, fx, fy);
        let half_b = r.o.dot(r.d);
        let disc = half_b * half_b - (r.o.dot(r.o) - 1.0);
        (disc >= 0.0).then(|| -r.d.dot((r.o + r.d * (-half_b - disc.sqrt())).normalize()))
    };
    let grid = |n: u32| {
        let mut sum = 0.0;
        for a in 0..n {
            for b in 0..n {
                let fx = x as f64 + (a as f64 + 0.5) / n as f64;
                let fy = y as f64 + (b as f64 + 0.5) / n as f64;
                sum += cos_at(fx, fy).map_or(1.0, |mu| table.at(mu));
            }
        }
        sum / (n * n) as f64
    };
    let centre = cos_at(x as f64 + 0.5, y as f64 + 0.5).unwrap_or(0.0);
    // The silhouette is a circle about the image's centre (the camera looks at the sphere's
    // centre from 4 radii) of radius (size / 2) tan(asin(1 / 4)) / tan(vfov / 2) pixels: which
    // pixels it crosses follows from their corners' distances to the centre.
    let radius = 0.5 * size as f64 * 0.25f64.asin().tan() / scene.camera.tan_half_vfov;
    let c = 0.5 * size as f64;
    let (dx, dy) = (x as f64 - c, y as f64 - c);
    // The nearest and farthest offsets from the centre over [d, d + 1].
    let near = |d: f64| {
        if d > 0.0 {
            d
        } else if d + 1.0 < 0.0 {
            d + 1.0
        } else {
            0.0
        }
    };
    let far = |d: f64| d.abs().max((d + 1.0).abs());
    let min_r = near(dx).hypot(near(dy));
    let max_r = far(dx).hypot(far(dy));
    if max_r < radius {
        (grid(8), true, centre)
    } else if min_r > radius {
        (1.0, false, centre)
    } else {
        (grid(64), false, centre)
    }
}

/// The groups of pixels the rendered furnace is tested on: the silhouette (pixels the sphere
/// covers only in part), then the covered ones by cos(theta_o) at their centre.
const GROUPS: [&str; 5] = ["rim", "cos < 0.4", "cos < 0.7", "cos < 0.9", "cos >= 0.9"];

fn group(covered: bool, mu: f64) -> usize {
    match (covered, mu) {
        (false, _) => 0,
        (_, m) if m < 0.4 => 1,
        (_, m) if m < 0.7 => 2,
        (_, m) if m < 0.9 => 3,
        _ => 4,
    }
}

/// The rendered furnace: a Fresnel-free rough conductor sphere filling most of a 24 x 24 image
/// under `[environment] color = 1`. The pixels are compared with their expected values in
/// groups (`GROUPS`): each group's mean difference against its standard error, the sum of its
/// pixels' variances of the mean. Not pixel by pixel: a low alpha's GGX tail reflects 0.25% of
/// the rays below the horizon, a rare zero most pixels' 256 samples miss, so single pixels'
/// variance estimates are too often near zero for a z-test, while a group's thousands of
/// samples see them. At 256 spp a group's standard error is 1e-3 to 5e-3 of its mean (0 where
/// every weight is 1), enough for a masking term of the wrong form (GGX's G1 without its
/// square root, Beckmann's fit off by 4%); `deep_rendered_furnace` takes it to 1e-4.
fn rendered_furnace(kind: Ndf, alpha: f64, spp: u32) {
    let size = 24;
    let scene = load_str(&format!(
        r#"
        [camera]
        position = [0, 0, 4]
        direction = [0, 0, -1]
        vfov = 32
        [render]
        width = {size}
        height = {size}
        spp = {spp}
        [environment]
        color = 1
        [[sphere]]
        center = [0, 0, 0]
        radius = 1
        material = "conductor"
        alpha = {alpha}
        distribution = "{}"
        "#,
        kind.name()
    ));
    let r = render(
        scene.clone(),
        &SettingsOverrides {
            sampler: Some(SamplerKind::Independent),
            adaptive: Some(false),
            ..Default::default()
        },
    );
    assert_eq!(r.stats().invalid, 0);
    let film = r.film();
    let table = Table::new(kind, alpha);
    // (sum of rendered, sum of expected, sum of variances of the mean, pixels)
    let mut groups = [(0.0, 0.0, 0.0, 0usize); GROUPS.len()];
    for y in 0..size {
        for x in 0..size {
            let i = (y * size + x) as usize;
            let (want, covered, mu) = expected_pixel(&scene, &table, x, y, size);
            let (m, v) = (film.mean(i).x, film.variance_of_mean(i).x);
            if want == 1.0 && !covered {
                assert_eq!(m, 1.0, "pixel ({x}, {y}) sees only the environment");
                continue;
            }
            let g = &mut groups[group(covered, mu)];
            *g = (g.0 + m, g.1 + want, g.2 + v, g.3 + 1);
        }
    }
    let limit = bonferroni_z(1e-3, 8 * GROUPS.len());
    let mut report = Vec::new();
    for (name, (rendered, want, var, n)) in GROUPS.iter().zip(groups) {
        assert!(n >= 16, "{kind:?} {alpha}: {n} pixels in {name}");
        let n = n as f64;
        // Where every weight is 1 (Beckmann's short tail) the variance is 0 and the bound on
        // the integral's error is all the tolerance there is.
        let z = (rendered - want) / (var + (n * QUADRATURE_ERROR).powi(2)).sqrt();
        report.push(format!(
            "{name}: {:.5}/{:.5} +- {:.1e} (z {z:.2})",
            rendered / n,
            want / n,
            var.sqrt() / n
        ));
        assert!(
            z.abs() < limit,
            "{kind:?} alpha {alpha}, {name}: rendered {:.5} vs integral {:.5}, z {z:.2}",
            rendered / n,
            want / n
        );
    }
    eprintln!("{kind:?} alpha {alpha}: {}", report.join("; "));
}

#[test]
fn rendered_furnace_ggx() {
    for alpha in [0.05, 0.2, 0.5, 1.0] {
        rendered_furnace(Ndf::Ggx, alpha, 256);
    }
}

#[test]
fn rendered_furnace_beckmann() {
    for alpha in [0.05, 0.2, 0.5, 1.0] {
        rendered_furnace(Ndf::Beckmann, alpha, 256);
    }
}

/// At 8192 samples per pixel the groups' standard errors reach 5e-5 to 5e-4: Beckmann's
/// fitted masking taken for the sampling density (0.1% to 0.3% off at oblique views) failed
/// here with z = -5.9 at alpha 0.5.
#[test]
#[ignore = "deep: the rendered furnaces at 8192 samples per pixel (15 s)"]
fn deep_rendered_furnace() {
    for kind in [Ndf::Ggx, Ndf::Beckmann] {
        for alpha in [0.05, 0.2, 0.5, 1.0] {
            rendered_furnace(kind, alpha, 8192);
        }
    }
}
