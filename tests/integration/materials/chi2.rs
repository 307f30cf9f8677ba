//! Chi-square goodness of fit of each microfacet material's `sample` against its own
//! `eval(...).pdf`, after Mitsuba's `chi2.py` and its `test_rough_*.py`: the directions `sample`
//! draws are binned, and the counts compared with the pdf integrated over each bin. A sampler
//! and a pdf that disagree anywhere (a missing G1, a wrong Jacobian, a Fresnel term at the wrong
//! cosine choosing the lobe, a stretch along the wrong axis) fail it.
//!
//! A lobe of alpha 0.01 is a hundredth of a radian wide, far narrower than any bin on the whole
//! sphere, and seen at cos 0.05 it is twenty times narrower still across the plane of
//! incidence. So each direction is binned by the microfacet normal that scatters `wo` into it
//! (the half vector, generalised for refraction: one to one on each side of the surface), in
//! polar coordinates about the shading normal with the angle warped logarithmically,
//! x = ln(1 + theta / s) / ln(1 + theta_max / s), s about alpha. There every lobe is round and
//! the bins resolve its core and its tails alike; the expected counts are eval's pdf times the
//! Jacobian |d omega_i / d omega_m|, integrated over each bin. Besides the bins: the draws
//! `sample` rejects (expected 1 minus the pdf's integral, which tests the pdf's normalisation)
//! and those of a delta lobe (expected its discrete probability, computed here from the
//! Fresnel equations).

use super::{beckmann, conductor, dir, ggx, gold, plastic, rough_glass};
use ptui::analysis::stats;
use ptui::geometry::Normals;
use ptui::material::fresnel;
use ptui::material::{ConductorFresnel, Distribution, Material};
use ptui::math::{DVec3, Frame};
use ptui::sampling::Rng;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Bins along the warped angle from the shading normal, and around it.
const RADIAL: usize = 16;
const AZIMUTH: usize = 24;
const SAMPLES: usize = 100_000;
/// Family-wise significance over every case of this file, default and deep tiers together
/// (Sidak-corrected per case with [`CASES`]).
const ALPHA: f64 = 0.01;
const CASES: f64 = 140.0;
/// How finely a bin's integral is taken: `nodes` x `nodes` midpoint nodes per cell, and
/// `edge_grid` + 1 points a side on which a cell is judged to hold an edge of the pdf's support.
#[derive(Clone, Copy)]
struct Grid {
    edge_grid: usize,
    nodes: usize,
}

/// The usual grid; bins the support enters between its points are looked at again on 8 times
/// the points, and bins expecting more than [`HEAVY`] samples on twice the nodes (the midpoint
/// rule's error is a share of a bin's mass: at 12 nodes, 1e-4 of the total for a rough
/// plastic's lobes, which the rejected draws, expected 1 - integral, would feel).
const GRID: Grid = Grid {
    edge_grid: 4,
    nodes: 12,
};
const HEAVY: f64 = 500.0;
/// How many times a cell holding an edge of the support is split: down to 1/16 of a bin, the
/// edge resolved to 1/192 of the bin's width.
const SPLITS: u32 = 4;

/// Warped polar coordinates about `center`.
struct Polar {
    center: DVec3,
    e1: DVec3,
    e2: DVec3,
    scale: f64,
    /// ln(1 + max_theta / scale).
    span: f64,
}

impl Polar {
    /// Polar coordinates about `center` out to `max_theta` (pi: the whole sphere).
    fn new(center: DVec3, scale: f64, max_theta: f64) -> Self {
        // Gram-Schmidt, independent of `Frame::from_normal`.
        let helper = if center.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let e1 = (helper - center * helper.dot(center)).normalize();
        Polar {
            center,
            e1,
            e2: center.cross(e1),
            scale,
            span: (1.0 + max_theta / scale).ln(),
        }
    }

    fn bin(&self, w: DVec3) -> usize {
        // The angle from the cross product: accurate in the lobe's core.
        let theta = w.cross(self.center).length().atan2(w.dot(self.center));
        let x = (1.0 + theta / self.scale).ln() / self.span;
        let i = ((x * RADIAL as f64) as usize).min(RADIAL - 1);
        let phi = w.dot(self.e2).atan2(w.dot(self.e1)).rem_euclid(TAU);
        let j = ((phi / TAU * AZIMUTH as f64) as usize).min(AZIMUTH - 1);
        i * AZIMUTH + j
    }

    /// The direction at (x, phi) and the solid angle per unit x and phi there:
    /// sin(theta) d(theta)/dx = sin(theta) span (theta + scale).
    fn at(&self, x: f64, phi: f64) -> (DVec3, f64) {
        let theta = self.scale * (x * self.span).exp_m1();
        let (s, c) = theta.sin_cos();
        let w = self.center * c + (self.e1 * phi.cos() + self.e2 * phi.sin()) * s;
        (w, s.abs() * self.span * (theta + self.scale))
    }

    /// The integral of `pdf` over bin `b`.
    fn integrate(&self, b: usize, pdf: &dyn Fn(DVec3) -> f64, grid: Grid) -> f64 {
        let (i, j) = (b / AZIMUTH, b % AZIMUTH);
        let (dx, dphi) = (1.0 / RADIAL as f64, TAU / AZIMUTH as f64);
        let x = (i as f64 * dx, (i + 1) as f64 * dx);
        let phi = (j as f64 * dphi, (j + 1) as f64 * dphi);
        self.integrate_cell(x, phi, pdf, grid, SPLITS)
    }

    /// The midpoint rule on the grid's nodes where `pdf` is zero nowhere or everywhere
    /// in the cell (judged on a grid that includes its edges); where it drops to zero inside
    /// (the horizon, a side of the surface), a sharp edge would cost that rule up to a twelfth of
    /// the cell's mass, so the cell is split in four, `splits` times over.
    fn integrate_cell(
        &self,
        x: (f64, f64),
        phi: (f64, f64),
        pdf: &dyn Fn(DVec3) -> f64,
        grid: Grid,
        splits: u32,
    ) -> f64 {
        let Grid { edge_grid, nodes } = grid;
        let lerp = |r: (f64, f64), t: f64| r.0 + (r.1 - r.0) * t;
        let mut zeros = 0;
        for a in 0..=edge_grid {
            for c in 0..=edge_grid {
                let t = (a as f64 / edge_grid as f64, c as f64 / edge_grid as f64);
                let (w, _) = self.at(lerp(x, t.0), lerp(phi, t.1));
                zeros += (pdf(w) == 0.0) as usize;
            }
        }
        let all = (edge_grid + 1) * (edge_grid + 1);
        if zeros == all {
            return 0.0;
        }
        if zeros > 0 && splits > 0 {
            let (xm, pm) = (lerp(x, 0.5), lerp(phi, 0.5));
            return [(x.0, xm), (xm, x.1)]
                .iter()
                .flat_map(|&xs| [(xs, (phi.0, pm)), (xs, (pm, phi.1))])
                .map(|(xs, ps)| self.integrate_cell(xs, ps, pdf, grid, splits - 1))
                .sum();
        }
        let n = nodes;
        let mut sum = 0.0;
        for a in 0..n {
            for c in 0..n {
                let t = ((a as f64 + 0.5) / n as f64, (c as f64 + 0.5) / n as f64);
                let (w, jac) = self.at(lerp(x, t.0), lerp(phi, t.1));
                sum += pdf(w) * jac;
            }
        }
        sum * (x.1 - x.0) * (phi.1 - phi.0) / (n * n) as f64
    }
}

/// One configuration: a material seen from `wo` at a surface with normals `nn`.
struct Case {
    name: String,
    m: Material,
    wo: DVec3,
    nn: Normals,
    /// The lobes' width in microfacet normals, for the bins: about alpha.
    scale: f64,
    /// The probability of the delta lobe (smooth plastic's coat) and its direction.
    delta: Option<(f64, DVec3)>,
    /// The index on the far side of the surface over `wo`'s, for a material that refracts.
    eta: Option<f64>,
}

/// How directions on one side of the surface map to microfacet normals: the (generalised) half
/// vector m of wo and wi, and back, with |d omega_i / d omega_m|, the Jacobian that turns a
/// density over wi into one over m (Walter et al. 2007, eqs. 14 and 17, written here, not
/// taken from ptui).
#[derive(Clone, Copy)]
enum Side {
    /// wi on wo's side: m = (wo + wi) / |wo + wi|, d omega_i = 4 |wo.m| d omega_m.
    Reflect,
    /// wi across: m along wo + eta wi, eta the index on wi's side over wo's, turned to `up`'s
    /// side (m and -m are the same facet); d omega_i = (wo.m + eta wi.m)^2 / (eta^2 |wi.m|)
    /// d omega_m.
    Refract { eta: f64, up: DVec3 },
}

impl Side {
    fn half_vector(self, wo: DVec3, wi: DVec3) -> DVec3 {
        match self {
            Side::Reflect => (wo + wi).normalize(),
            Side::Refract { eta, up } => {
                let m = (wo + wi * eta).normalize();
                m * m.dot(up).signum()
            }
        }
    }

    /// The direction facet `m` scatters `wo` into on this side and the Jacobian there, or None
    /// where no direction maps to `m` (a facet wo sees from behind for reflection; total
    /// internal reflection, or `m` on the other side of `up`, for refraction).
    fn scattered(self, wo: DVec3, m: DVec3) -> Option<(DVec3, f64)> {
        match self {
            Side::Reflect => {
                let c = wo.dot(m);
                (c > 0.0).then(|| (m * (2.0 * c) - wo, 4.0 * c))
            }
            Side::Refract { eta, up } => {
                if m.dot(up) <= 0.0 {
                    return None;
                }
                // Snell at the facet turned to wo.
                let mm = m * wo.dot(m).signum();
                let c = wo.dot(mm);
                let sin2_t = (1.0 - c * c) / (eta * eta);
                if sin2_t >= 1.0 {
                    return None;
                }
                let wi = -wo / eta + mm * (c / eta - (1.0 - sin2_t).sqrt());
                let jacobian =
                    (wo.dot(m) + eta * wi.dot(m)).powi(2) / (eta * eta * wi.dot(m).abs());
                Some((wi, jacobian))
            }
        }
    }
}

/// Bins of the microfacet normals of each side of the surface (polar about the shading normal,
/// warped with alpha), then the delta lobe's, then the rejected draws'. The map from directions
/// to normals is one to one on each side, so the samples' normals must follow eval's pdf times
/// the Jacobian there; binned by normal, the lobe of alpha 0.01 at cos 0.05, which in directions
/// is 2 alpha wide along the plane of incidence and 2 alpha cos wide across it, is round.
fn run(case: &Case) -> f64 {
    let Case { m, wo, nn, .. } = case;
    let name = &case.name;
    let towards_wo = nn.s * wo.dot(nn.g).signum();
    let sides = [
        (Side::Reflect, Polar::new(towards_wo, case.scale, PI)),
        (
            Side::Refract {
                eta: case.eta.unwrap_or(1.5),
                up: nn.s,
            },
            // Refracting normals are turned to `up`: a hemisphere, whose rim (where a facet
            // at right angles to the surface still refracts) is the bins' outer edge.
            Polar::new(nn.s, case.scale, FRAC_PI_2),
        ),
    ];
    let cells = RADIAL * AZIMUTH;
    let (delta_bin, rejected_bin) = (2 * cells, 2 * cells + 1);
    let side_of = |w: DVec3| (w.dot(nn.g) * wo.dot(nn.g) <= 0.0) as usize;
    let mut counts = vec![0.0; 2 * cells + 2];
    let seed = name
        .bytes()
        .fold(0xc412u64, |h, b| h.rotate_left(5) ^ b as u64);
    let mut rng = Rng::new(seed);
    for _ in 0..SAMPLES {
        let u_lobe = rng.next_f64();
        let u = (rng.next_f64(), rng.next_f64());
        let Some(s) = m.sample(*wo, *nn, u_lobe, u) else {
            counts[rejected_bin] += 1.0;
            continue;
        };
        assert!(
            (s.wi.length() - 1.0).abs() < 1e-9 && s.weight.is_finite(),
            "{name}: {s:?}"
        );
        if s.delta {
            let (_, wi) = case
                .delta
                .unwrap_or_else(|| panic!("{name}: a delta sample"));
            assert!(
                (s.wi - wi).length() < 1e-12,
                "{name}: delta along {:?}",
                s.wi
            );
            counts[delta_bin] += 1.0;
        } else {
            let side = side_of(s.wi);
            let (map, polar) = &sides[side];
            counts[side * cells + polar.bin(map.half_vector(*wo, s.wi))] += 1.0;
        }
    }
    let mut expected = vec![0.0; 2 * cells + 2];
    // An opaque material has no refraction side: any sample there lands where nothing is
    // expected.
    let lit_sides = if case.eta.is_some() { 2 } else { 1 };
    for (side, (map, polar)) in sides.iter().enumerate().take(lit_sides) {
        let density = |h: DVec3| match map.scattered(*wo, h) {
            Some((wi, jacobian)) if side_of(wi) == side => m.eval(*wo, wi, *nn).pdf * jacobian,
            _ => 0.0,
        };
        for b in 0..cells {
            let mut p = polar.integrate(b, &density, GRID);
            if p == 0.0 && counts[side * cells + b] > 0.0 {
                let closer = Grid {
                    edge_grid: 8 * GRID.edge_grid,
                    ..GRID
                };
                p = polar.integrate(b, &density, closer);
            } else if p * SAMPLES as f64 > HEAVY {
                let finer = Grid {
                    nodes: 2 * GRID.nodes,
                    ..GRID
                };
                p = polar.integrate(b, &density, finer);
            }
            expected[side * cells + b] = p;
        }
    }
    let total: f64 = expected.iter().sum();
    let p_delta = case.delta.map_or(0.0, |d| d.0);
    assert!(
        total + p_delta <= 1.0 + 2e-3,
        "{name}: the pdf integrates to {total} (+ delta {p_delta})"
    );
    expected[delta_bin] = p_delta;
    expected[rejected_bin] = 1.0 - total - p_delta;
    let mut expected: Vec<f64> = expected.iter().map(|p| p * SAMPLES as f64).collect();
    if expected[rejected_bin] < stats::MIN_EXPECTED {
        // A rejection rate below the integral's accuracy (about 1e-4: a GGX tail reflected
        // below the horizon) cannot be tested through 1 - integral; it must stay that small.
        let bound = stats::MIN_EXPECTED + 2e-4 * SAMPLES as f64;
        assert!(
            counts[rejected_bin] <= bound,
            "{name}: {} draws rejected, more than {bound}",
            counts[rejected_bin]
        );
        counts[rejected_bin] = 0.0;
        expected[rejected_bin] = 0.0;
    }
    let t = stats::pearson_chi2(&counts, &expected);
    assert!(
        t.stray == 0.0,
        "{name}: {} samples where the pdf is zero",
        t.stray
    );
    assert!(t.bins >= 20, "{name}: only {} usable bins", t.bins);
    let p = t.p_value();
    eprintln!(
        "{name}: chi2 {:.1}, {} dof, p = {p:.3}; pdf integral {total:.6}, rejected {:.6}",
        t.chi2,
        t.bins - 1,
        counts[rejected_bin] / SAMPLES as f64
    );
    let limit = 1.0 - (1.0 - ALPHA).powf(1.0 / CASES);
    assert!(
        p > limit,
        "{name}: chi2 {:.1} with {} dof, p = {p:.2e} < {limit:.2e}",
        t.chi2,
        t.bins - 1
    );
    p
}

fn flat() -> Normals {
    Normals::flat(DVec3::Z)
}

fn label(d: &Distribution) -> String {
    format!("{:?} {}x{}", d.kind, d.alpha_u, d.alpha_v)
}

fn conductor_case(d: Distribution, cos: f64) -> Case {
    Case {
        name: format!("conductor {} cos {cos}", label(&d)),
        m: conductor(Some(d), gold()),
        wo: dir(cos, 0.7, false),
        nn: flat(),
        scale: (d.alpha_u * d.alpha_v).sqrt(),
        delta: None,
        eta: None,
    }
}

/// Rough glass of index 1.5 seen from outside or (`inside`) from within.
fn glass_case(d: Distribution, cos: f64, inside: bool) -> Case {
    let where_ = if inside { "inside" } else { "outside" };
    Case {
        name: format!("glass {} cos {cos} {where_}", label(&d)),
        m: rough_glass(d, 1.5),
        wo: dir(cos, 0.7, inside),
        nn: flat(),
        scale: (d.alpha_u * d.alpha_v).sqrt(),
        delta: None,
        eta: Some(if inside { 1.0 / 1.5 } else { 1.5 }),
    }
}

/// Plastic of index 1.49, smooth (None) or rough. The smooth coat, of base colour 0.5, draws
/// its delta lobe with probability F s / (F s + (1 - F)(1 - s)), s = 1 / (1 + 0.5) the share
/// of the specular factor (1) in specular plus base colour (Mitsuba's `plastic`). The rough
/// coats are of colour 1, the other tests' (their tables are built once).
fn plastic_case(d: Option<Distribution>, cos: f64) -> Case {
    let wo = dir(cos, 0.7, false);
    let color = if d.is_some() { 1.0 } else { 0.5 };
    let delta = d.is_none().then(|| {
        let f = fresnel::dielectric(cos, 1.49).reflectance;
        let s = 1.0 / (1.0 + color);
        (
            f * s / (f * s + (1.0 - f) * (1.0 - s)),
            DVec3::new(-wo.x, -wo.y, wo.z),
        )
    });
    Case {
        name: format!(
            "plastic {} cos {cos}",
            d.as_ref().map_or("smooth".into(), label)
        ),
        m: plastic(1.49, color, d),
        wo,
        nn: flat(),
        scale: d.map_or(0.3, |d| d.alpha_u),
        delta,
        eta: None,
    }
}

/// Fails if any case fails, after running them all (so one run reports every p-value).
fn run_all(cases: Vec<Case>) {
    let failed: Vec<String> = cases
        .iter()
        .filter_map(|c| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(c)))
                .err()
                .map(|_| c.name.clone())
        })
        .collect();
    assert!(failed.is_empty(), "failed: {failed:?}");
}

/// Sharp (0.01) and rough (1) lobes, at normal, oblique and grazing (cos 0.05) views, GGX and
/// Beckmann, anisotropic: the cases most likely to show a sampler and pdf apart.
#[test]
fn rough_conductor_samples_its_pdf() {
    run_all(vec![
        conductor_case(ggx(0.01, 0.01), 0.05),
        conductor_case(beckmann(0.05, 0.05), 0.5),
        conductor_case(ggx(1.0, 1.0), 0.05),
        conductor_case(beckmann(1.0, 1.0), 0.05),
        conductor_case(beckmann(0.3, 0.05), 0.5),
        conductor_case(ggx(0.05, 0.5), 0.95),
    ]);
}

/// Reflection and refraction from outside and inside, past the critical angle (cos 0.5 from
/// inside: total internal reflection of the macro-surface, leaving only the microfacets tilted
/// enough to transmit), sharp and rough, grazing, anisotropic.
#[test]
fn rough_glass_samples_its_pdf() {
    run_all(vec![
        glass_case(ggx(0.05, 0.05), 0.5, false),
        glass_case(beckmann(0.3, 0.3), 0.5, true),
        glass_case(ggx(1.0, 1.0), 0.9, true),
        glass_case(ggx(0.01, 0.01), 0.05, false),
        glass_case(beckmann(0.02, 0.02), 0.9, true),
        glass_case(ggx(0.05, 0.3), 0.7, false),
    ]);
}

/// The smooth coat's delta lobe is drawn as often as its discrete probability says, the base's
/// lobe follows its pdf; the rough coat's two lobes follow theirs.
#[test]
fn plastic_samples_its_pdf() {
    run_all(vec![
        plastic_case(None, 0.5),
        plastic_case(None, 0.05),
        plastic_case(Some(ggx(0.05, 0.05)), 0.05),
        plastic_case(Some(beckmann(0.5, 0.5)), 0.9),
        plastic_case(Some(ggx(0.01, 0.01)), 0.6),
    ]);
}

/// With a shading normal 30 degrees off the geometric one (a smooth mesh), the lobes are built
/// about the shading normal and whatever would cross the geometric surface the wrong way is
/// rejected by `sample` and zero in `eval` alike.
#[test]
fn lobes_about_a_shading_normal_sample_their_pdf() {
    let g = DVec3::new(0.2, -0.3, 1.0).normalize();
    let tilt = 30f64.to_radians();
    let s = Frame::from_normal(g).to_world(DVec3::new(tilt.sin(), 0.0, tilt.cos()));
    let nn = Normals::new(g, s);
    let frame = Frame::from_normal(g);
    let mut cases = vec![
        // wo in front of the shading normal, 20 degrees above the geometric surface.
        Case {
            name: "conductor about a shading normal".into(),
            wo: frame.to_world(dir(20f64.to_radians().sin(), 0.3, false)),
            ..conductor_case(ggx(0.1, 0.1), 0.5)
        },
        // wo behind the shading normal (a silhouette): the geometric frame takes over.
        Case {
            name: "conductor at a silhouette".into(),
            wo: frame.to_world(dir(10f64.to_radians().sin(), PI, false)),
            ..conductor_case(beckmann(0.2, 0.2), 0.5)
        },
        Case {
            name: "glass about a shading normal".into(),
            wo: frame.to_world(dir(0.6, 0.3, false)),
            ..glass_case(ggx(0.1, 0.1), 0.5, false)
        },
        Case {
            name: "glass about a shading normal, inside".into(),
            wo: frame.to_world(dir(0.8, 2.0, true)),
            ..glass_case(ggx(0.2, 0.2), 0.5, true)
        },
        Case {
            name: "plastic about a shading normal".into(),
            wo: frame.to_world(dir(0.4, 0.3, false)),
            ..plastic_case(Some(ggx(0.05, 0.05)), 0.5)
        },
    ];
    for c in &mut cases {
        c.nn = nn;
    }
    run_all(cases);
}

/// The whole grid: every alpha of {0.01, 0.05, 0.3, 1} at cos {0.95, 0.5, 0.05}, GGX and
/// Beckmann, plus anisotropic pairs.
#[test]
#[ignore = "deep: 32 chi-square tests of the rough conductor"]
fn deep_rough_conductor_grid() {
    let mut cases = Vec::new();
    for make in [ggx, beckmann] {
        for a in [0.01, 0.05, 0.3, 1.0] {
            for cos in [0.95, 0.5, 0.05] {
                cases.push(conductor_case(make(a, a), cos));
            }
        }
        for (au, av) in [(0.05, 0.3), (1.0, 0.1)] {
            for cos in [0.5, 0.05] {
                cases.push(conductor_case(make(au, av), cos));
            }
        }
    }
    run_all(cases);
}

#[test]
#[ignore = "deep: 56 chi-square tests of the rough glass"]
fn deep_rough_glass_grid() {
    let mut cases = Vec::new();
    for make in [ggx, beckmann] {
        for inside in [false, true] {
            for a in [0.01, 0.05, 0.3, 1.0] {
                for cos in [0.9, 0.5, 0.05] {
                    cases.push(glass_case(make(a, a), cos, inside));
                }
            }
            for cos in [0.7, 0.05] {
                cases.push(glass_case(make(0.05, 0.3), cos, inside));
            }
        }
    }
    run_all(cases);
}

#[test]
#[ignore = "deep: 27 chi-square tests of plastic"]
fn deep_plastic_grid() {
    let mut cases = Vec::new();
    for cos in [0.9, 0.5, 0.05] {
        cases.push(plastic_case(None, cos));
        for make in [ggx, beckmann] {
            for a in [0.01, 0.05, 0.3, 1.0] {
                cases.push(plastic_case(Some(make(a, a)), cos));
            }
        }
    }
    run_all(cases);
}

/// The Fresnel-free conductor: only its sampling, the furnace tests' material.
#[test]
fn fresnel_free_conductor_samples_its_pdf() {
    let mut c = conductor_case(ggx(0.2, 0.2), 0.3);
    c.m = conductor(Some(ggx(0.2, 0.2)), ConductorFresnel::None);
    c.name = "Fresnel-free conductor".into();
    run(&c);
}
