//! Chi-square goodness-of-fit tests for the direction samplers, after Mitsuba's `chi2.py`: bin
//! the sphere of directions, compare sample counts with the counts the claimed pdf predicts
//! (integrated numerically over each bin), and pool sparse bins.

use ptui::analysis::stats;
use ptui::geometry::{Normals, Sphere};
use ptui::light::environment::{EnvMap, Environment};
use ptui::light::sphere::SphereLight;
use ptui::material::{Material, MaterialKind};
use ptui::math::{luminance, DVec3, Frame, Ray};
use ptui::sampling::distribution::Distribution2D;
use ptui::sampling::{warp, Rng};
use std::f64::consts::PI;

const THETA_BINS: usize = 20;
const PHI_BINS: usize = 40;
const SAMPLES: usize = 400_000;
/// Family-wise significance level over all tests in this file (Sidak-corrected per test).
const ALPHA: f64 = 0.01;
const TESTS: f64 = 24.0;

fn bin_of(w: DVec3) -> usize {
    let z = w.z.clamp(-1.0, 1.0);
    let i = (((z + 1.0) * 0.5) * THETA_BINS as f64).min(THETA_BINS as f64 - 1.0) as usize;
    let mut phi = w.y.atan2(w.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let j = ((phi / (2.0 * PI)) * PHI_BINS as f64).min(PHI_BINS as f64 - 1.0) as usize;
    i * PHI_BINS + j
}

/// Integral of `pdf` over each bin (in z = cos theta and phi, where d(omega) = dz dphi),
/// by the midpoint rule on a sub-grid of `sub` x `sub` points per bin.
fn expected_fractions(pdf: &dyn Fn(DVec3) -> f64, sub: usize) -> Vec<f64> {
    let mut out = vec![0.0; THETA_BINS * PHI_BINS];
    let dz = 2.0 / (THETA_BINS * sub) as f64;
    let dphi = 2.0 * PI / (PHI_BINS * sub) as f64;
    for (b, slot) in out.iter_mut().enumerate() {
        let (i, j) = (b / PHI_BINS, b % PHI_BINS);
        let mut sum = 0.0;
        for si in 0..sub {
            let z = -1.0 + ((i * sub + si) as f64 + 0.5) * dz;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for sj in 0..sub {
                let phi = ((j * sub + sj) as f64 + 0.5) * dphi;
                sum += pdf(DVec3::new(r * phi.cos(), r * phi.sin(), z));
            }
        }
        *slot = sum * dz * dphi;
    }
    out
}

/// Run the test over the whole sphere of directions; panics if the histogram does not match.
pub(crate) fn chi2_test(
    name: &str,
    sample: impl FnMut(&mut Rng) -> Option<DVec3>,
    pdf: impl Fn(DVec3) -> f64,
) {
    chi2_test_with(name, 24, false, sample, pdf)
}

/// [`chi2_test`] integrating the pdf on `sub` x `sub` points per bin (a pdf with a sharp edge
/// across the bins, a cap's rim, needs more than the default). With `rejects`, the sampler may
/// return nothing for part of its draws (it samples a bounding cone and keeps what reaches the
/// light): its pdf is then a density over all draws, integrating to the fraction kept, and the
/// rejections are one more bin, expected 1 - that integral.
pub(crate) fn chi2_test_with(
    name: &str,
    sub: usize,
    rejects: bool,
    mut sample: impl FnMut(&mut Rng) -> Option<DVec3>,
    pdf: impl Fn(DVec3) -> f64,
) {
    let mut rng = Rng::new(0x5eed ^ name.len() as u64);
    let mut counts = vec![0.0f64; THETA_BINS * PHI_BINS];
    let mut n = 0usize;
    for _ in 0..SAMPLES {
        if let Some(w) = sample(&mut rng) {
            assert!(
                (w.length() - 1.0).abs() < 1e-9,
                "{name}: non-unit direction {w:?}"
            );
            counts[bin_of(w)] += 1.0;
            n += 1;
        }
    }
    let mut expected = expected_fractions(&pdf, sub);
    let total: f64 = expected.iter().sum();
    if rejects {
        assert!(total <= 1.0 + 2e-3, "{name}: pdf integrates to {total} > 1");
        counts.push((SAMPLES - n) as f64);
        expected.push((1.0 - total).max(0.0));
        eprintln!(
            "{name}: {:.1}% of draws kept",
            100.0 * n as f64 / SAMPLES as f64
        );
        chi2_compare(name, &counts, &expected, SAMPLES);
    } else {
        assert!(
            (total - 1.0).abs() < 2e-3,
            "{name}: pdf integrates to {total}, not 1"
        );
        chi2_compare(name, &counts, &expected, n);
    }
}

/// Pearson's test of observed `counts` against `expected` fractions of `n` samples, the bins
/// expecting fewer than 5 samples pooled (the chi-square approximation needs more).
fn chi2_compare(name: &str, counts: &[f64], expected: &[f64], n: usize) {
    let expected: Vec<f64> = expected.iter().map(|frac| frac * n as f64).collect();
    let t = stats::pearson_chi2(counts, &expected);
    // A sample where the pdf claims nothing is a hard failure.
    assert!(
        t.stray == 0.0,
        "{name}: {} samples in bins of zero pdf",
        t.stray
    );
    assert!(
        t.bins >= 20,
        "{name}: only {} usable bins: the test has no power",
        t.bins
    );
    let p = t.p_value();
    eprintln!(
        "{name}: chi2 = {:.1}, {} dof, p = {p:.3}",
        t.chi2,
        t.bins - 1
    );
    let alpha = 1.0 - (1.0 - ALPHA).powf(1.0 / TESTS);
    assert!(
        p > alpha,
        "{name}: chi2 = {:.1} with {} dof, p = {p:.2e} < {alpha:.2e}",
        t.chi2,
        t.bins - 1
    );
}

#[test]
fn cosine_hemisphere_matches_its_pdf() {
    for n in [DVec3::Z, -DVec3::Z, DVec3::new(1.0, -2.0, 0.5).normalize()] {
        let frame = Frame::from_normal(n);
        chi2_test(
            "cosine hemisphere",
            |rng| Some(frame.to_world(warp::cosine_hemisphere((rng.next_f64(), rng.next_f64())))),
            |w| warp::cosine_hemisphere_pdf(w.dot(n)),
        );
    }
}

#[test]
fn diffuse_material_samples_what_it_evaluates() {
    let m = Material {
        kind: MaterialKind::Diffuse,
        color: DVec3::splat(0.5),
        emission: DVec3::ZERO,
        one_sided: false,
    };
    let n = DVec3::new(0.3, 0.4, -0.866).normalize();
    let wo = DVec3::new(0.1, -0.2, -1.0).normalize();
    chi2_test(
        "diffuse bsdf",
        |rng| {
            let s = m.sample(
                wo,
                Normals::flat(n),
                rng.next_f64(),
                (rng.next_f64(), rng.next_f64()),
            )?;
            let e = m.eval(wo, s.wi, Normals::flat(n));
            assert!((e.pdf - s.pdf).abs() < 1e-9 * s.pdf.max(1.0));
            assert!((s.weight - e.f_cos / e.pdf).abs().max_element() < 1e-9);
            Some(s.wi)
        },
        |w| m.eval(wo, w, Normals::flat(n)).pdf,
    );
}

/// The diffuse BSDF about a shading normal 25 degrees off the geometric one: its samples follow
/// the cosine lobe about the shading normal, except those falling below the geometric surface,
/// which it drops (the extra "rejected" bin, whose expected share is the lobe's mass in that
/// wedge: eval's pdf is 0 there). Each kept sample's weight is eval's f cos / pdf. Two views:
/// `wo` well in front of both normals, and `wo` in front of the geometric normal but behind the
/// shading one (a silhouette), where the lobe must still be on `wo`'s side of the surface.
fn diffuse_about_a_shading_normal(name: &str, wo: DVec3) {
    let m = Material {
        kind: MaterialKind::Diffuse,
        color: DVec3::new(0.2, 0.5, 0.9),
        emission: DVec3::ZERO,
        one_sided: false,
    };
    let g = DVec3::new(0.3, 0.4, -0.866).normalize();
    let tilt = Frame::from_normal(g).to_world(DVec3::new(
        25f64.to_radians().sin(),
        0.0,
        25f64.to_radians().cos(),
    ));
    let nn = Normals::new(g, tilt);
    let wo = Frame::from_normal(g).to_world(wo.normalize());
    assert!(wo.dot(g) > 0.0);
    let (mut drawn, mut kept) = (0u32, 0u32);
    chi2_test_with(
        name,
        24,
        true,
        |rng| {
            drawn += 1;
            let s = m.sample(wo, nn, rng.next_f64(), (rng.next_f64(), rng.next_f64()))?;
            kept += 1;
            assert!(
                s.wi.dot(g) > 0.0,
                "{name}: a sample leaked below the surface"
            );
            let e = m.eval(wo, s.wi, nn);
            assert!((e.pdf - s.pdf).abs() < 1e-9 * s.pdf.max(1.0));
            assert!((s.weight - e.f_cos / e.pdf).abs().max_element() < 1e-9);
            Some(s.wi)
        },
        |w| m.eval(wo, w, nn).pdf,
    );
    // The lobe is the one on wo's side of the surface whatever side of the shading normal wo
    // is on: only its sliver below the face is dropped. A lobe turned to wo's side of the
    // shading normal would, at the silhouette, lie mostly below the face and drop most
    // samples: the dark rims of pbrt-v3's approach.
    let share = kept as f64 / drawn as f64;
    eprintln!("{name}: {share:.4} of the samples kept");
    assert!(share > 0.9, "{name}: only {share:.3} of the samples kept");
}

#[test]
fn diffuse_samples_about_a_shading_normal() {
    diffuse_about_a_shading_normal("shading normal", DVec3::new(0.2, 0.3, 1.0));
}

#[test]
fn diffuse_samples_about_a_shading_normal_at_the_silhouette() {
    // 10 degrees above the geometric surface, on the side the shading normal tilts away from:
    // wo . ns < 0 < wo . ng.
    let a = 10f64.to_radians();
    diffuse_about_a_shading_normal("shading silhouette", DVec3::new(-a.cos(), 0.0, a.sin()));
}

fn light(center: DVec3, radius: f64) -> SphereLight {
    SphereLight::new(0, Sphere::new(center, radius), DVec3::ONE)
}

/// The cone sampler from outside the light: directions uniform over the subtended cone, and every
/// one of them actually hits the sphere. Binned in the cone's own coordinates (equal solid-angle
/// bins in 1 - cos and phi, measured in an independently built frame), so even a narrow cone
/// gets many bins and the boundary is exact.
#[test]
fn sphere_light_cone_matches_its_pdf() {
    let p = DVec3::new(0.2, -0.1, 0.3);
    for (center, radius) in [
        (DVec3::new(1.0, 2.0, -0.5), 1.2),
        (DVec3::new(-3.0, 0.5, 2.0), 0.4),
        (DVec3::new(0.2, -0.1, -1e3), 1e-2),
    ] {
        let l = light(center, radius);
        let axis = (center - p).normalize();
        let sin2 = radius * radius / (center - p).length_squared();
        let one_minus_cos_max = sin2 / (1.0 + (1.0 - sin2).sqrt());
        // Gram-Schmidt frame, deliberately not `Frame::from_normal`.
        let helper = if axis.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let e1 = (helper - axis * helper.dot(axis)).normalize();
        let e2 = axis.cross(e1);
        let mut counts = vec![0.0; THETA_BINS * PHI_BINS];
        let mut rng = Rng::new(11);
        for _ in 0..SAMPLES {
            let s = l
                .sample(p, p, (rng.next_f64(), rng.next_f64()))
                .expect("sample");
            assert!((s.pdf - l.pdf(p, p, p + s.wi)).abs() <= 1e-12 * s.pdf);
            assert!((s.pdf * 2.0 * PI * one_minus_cos_max - 1.0).abs() < 1e-9);
            assert!(
                l.sphere
                    .intersect(&Ray::new(p, s.wi), f64::INFINITY)
                    .is_some(),
                "cone sample misses the light"
            );
            // 1 - cos(theta) from the cross product: accurate for tiny angles.
            let sin_t = s.wi.cross(axis).length();
            let one_minus_cos = sin_t * sin_t / (1.0 + s.wi.dot(axis));
            let v = one_minus_cos / one_minus_cos_max;
            assert!(v <= 1.0 + 1e-6, "sample outside the cone: {v}");
            let i = ((v * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
            let mut phi = s.wi.dot(e2).atan2(s.wi.dot(e1));
            if phi < 0.0 {
                phi += 2.0 * PI;
            }
            let j = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
            counts[i * PHI_BINS + j] += 1.0;
        }
        let uniform = vec![1.0 / (THETA_BINS * PHI_BINS) as f64; THETA_BINS * PHI_BINS];
        chi2_compare("sphere light cone", &counts, &uniform, SAMPLES);
    }
}

/// Inside the light every direction reaches it (uniform sphere); on its surface, the hemisphere
/// towards the centre (the cone opens to 90 degrees).
#[test]
fn sphere_light_from_inside_and_on_the_surface() {
    let l = light(DVec3::new(0.5, 0.0, 0.0), 2.0);
    let inside = DVec3::new(0.0, 0.3, -0.2);
    chi2_test(
        "sphere light inside",
        |rng| {
            l.sample(inside, inside, (rng.next_f64(), rng.next_f64()))
                .map(|s| s.wi)
        },
        |_| 0.25 / PI,
    );
    let on = l.sphere.center + DVec3::new(0.0, 0.0, 2.0);
    chi2_test(
        "sphere light on surface",
        |rng| {
            l.sample(on, on, (rng.next_f64(), rng.next_f64()))
                .map(|s| s.wi)
        },
        |w| if w.z <= 0.0 { 0.5 / PI } else { 0.0 },
    );
}

/// A light mostly hidden inside a bigger sphere, as smallpt's is behind its ceiling: from a
/// point inside the cutting sphere only the light's cap inside it is sampled (through the cone
/// around the ball that holds the cap, or by area from inside that ball), and the directions
/// follow the claimed pdf, which is zero towards the hidden part; the draws that miss the cap
/// are counted against 1 - the pdf's integral. From outside the cutting sphere the other part is
/// sampled.
#[test]
fn clipped_sphere_light_samples_its_visible_cap() {
    let cutter = Sphere::new(DVec3::new(0.0, 0.0, -7.5), 10.0);
    let l = light(DVec3::new(0.0, 0.0, 4.0), 2.0).with_clips([&cutter]);
    assert_eq!(l.clips().count(), 1);
    let clip = l.clips().next().copied().expect("one clip");
    // 1 - cos of the cap's half-angle by the law of cosines: (r^2 + d^2 - ro^2) / (2 r d).
    let z0 = (4.0 + 11.5f64 * 11.5 - 100.0) / (2.0 * 2.0 * 11.5);
    assert!((clip.h_in - (1.0 - z0)).abs() < 1e-12, "h_in {}", clip.h_in);
    assert!((clip.h_in + clip.h_out - 2.0).abs() < 1e-12);
    check_cap_samples(
        &l,
        &cutter,
        96,
        &[
            (
                "clipped light, inside the cutter",
                DVec3::new(0.3, -0.2, 0.0),
                true,
            ),
            // Inside the ball around the cap's rim: the cap is sampled by area.
            (
                "clipped light, next to the cap",
                DVec3::new(0.3, 0.2, 1.6),
                true,
            ),
            (
                "clipped light, outside the cutter",
                DVec3::new(0.5, 0.4, 9.0),
                false,
            ),
        ],
    );
}

/// A cap about as flat as smallpt's (a radius-100 light poking 0.5 through a radius-1000
/// ceiling: 1 - cos of its half-angle 0.0045, below `FLAT_CAP`), sampled by area alone also from
/// outside the ball around its rim (radius 9.5), where a curved cap mixes in the cone.
#[test]
fn a_flat_clipped_cap_is_sampled_by_area_from_everywhere() {
    let cutter = Sphere::new(DVec3::new(0.0, 0.0, -1000.0), 1000.0);
    let l = light(DVec3::new(0.0, 0.0, 99.5), 100.0).with_clips([&cutter]);
    let clip = l.clips().next().copied().expect("one clip");
    // (ro - d + r)(ro + d - r) / (2 r d), the law of cosines above as products of differences.
    let h = 0.5 * 1999.5 / (2.0 * 100.0 * 1099.5);
    assert!((clip.h_in - h).abs() < 1e-12, "h_in {}", clip.h_in);
    // Outside the rim's ball (the first two) and inside it.
    let cases = [
        ("flat cap, far below", DVec3::new(4.0, -3.0, -15.0), true),
        ("flat cap, to the side", DVec3::new(15.0, 5.0, -8.0), true),
        ("flat cap, next to it", DVec3::new(3.0, -2.0, -2.0), true),
    ];
    // The flat cap's rim cuts across bins as a thinner sliver than the curved one's.
    check_cap_samples(&l, &cutter, 256, &cases);
    // By area alone, no draw is lost from below: the cone around the rim's ball loses those
    // that miss the cap.
    let mut rng = Rng::new(3);
    for &(_, p, _) in &cases[..2] {
        let kept = (0..10_000)
            .filter(|_| l.sample(p, p, (rng.next_f64(), rng.next_f64())).is_some())
            .count();
        assert_eq!(kept, 10_000, "from {p}");
    }
}

/// The samples of clipped light `l` from each point p of `cases` (name, p, whether p and its
/// samples are inside `cutter`) against the pdf the light claims for them.
/// `sub` as for [`chi2_test_with`].
fn check_cap_samples(l: &SphereLight, cutter: &Sphere, sub: usize, cases: &[(&str, DVec3, bool)]) {
    let first_hit = |p: DVec3, w: DVec3| {
        l.sphere
            .intersect(&Ray::new(p, w), f64::INFINITY)
            .map(|t| p + w * t)
    };
    for &(name, p, below) in cases {
        chi2_test_with(
            name,
            sub,
            true,
            |rng| {
                let s = l.sample(p, p, (rng.next_f64(), rng.next_f64()))?;
                let x = first_hit(p, s.wi).expect("a cap sample hits the light");
                // Sampled points lie on the cap on p's side of the cutting surface.
                let x_below = (x - cutter.center).length() < cutter.radius;
                assert_eq!(x_below, below, "{name}: sample on the hidden side");
                // Evaluated at the sampled point itself: by area the pdf has 1 / cos at the
                // light, and at grazing points the hit found again along wi, a hair off it,
                // moves the value by up to ~1e-5.
                // (Cone samples of the whole sphere, from the other side, carry no point.)
                let at = s.point.unwrap_or(x);
                assert!(
                    (at - x).length() < 1e-9,
                    "{name}: sampled point is not the first hit"
                );
                let back = l.pdf(p, p, at);
                assert!(
                    (s.pdf - back).abs() <= 1e-9 * s.pdf,
                    "{name}: pdf {} vs {back}",
                    s.pdf
                );
                Some(s.wi)
            },
            |w| first_hit(p, w).map_or(0.0, |x| l.pdf(p, p, x)),
        );
    }
}

/// A tiny light far away: the cone is ~1e-12 sr wide; pdf times solid angle must still be 1 and
/// samples must still hit it (the naive 1 - sqrt(1 - sin^2) rounds to zero here).
#[test]
fn tiny_sphere_light_keeps_its_cone() {
    let p = DVec3::new(50.0, 0.0, 81.6);
    let l = light(DVec3::new(50.0, 65.1, 81.6), 1e-4);
    let d = 65.1f64;
    let solid_angle = 2.0 * PI * (1.0 - (1.0 - (1e-4 / d).powi(2)).sqrt());
    let exact = PI * (1e-4 / d).powi(2); // small-angle limit, accurate to ~1e-12 relative
    assert!(solid_angle == 0.0 || (solid_angle - exact).abs() / exact > 1e-6); // naive form fails
    assert!((1.0 / l.pdf(p, p, l.sphere.center) - exact).abs() / exact < 1e-6);
    let mut rng = Rng::new(1);
    for _ in 0..1000 {
        let s = l
            .sample(p, p, (rng.next_f64(), rng.next_f64()))
            .expect("sample");
        assert!(l
            .sphere
            .intersect(&Ray::new(p, s.wi), f64::INFINITY)
            .is_some());
    }
}

/// A map with smooth variation, a bright patch and a dim band (row 0 at the top).
fn test_map() -> EnvMap {
    EnvMap::from_fn(48, 24, |x, y| {
        if (14..16).contains(&y) {
            return [0.02; 3];
        }
        let base = 1.0 + ((x * 7 + y * 3) % 5) as f32;
        if (30..34).contains(&x) && (5..8).contains(&y) {
            [60.0, 50.0, 40.0]
        } else {
            [base, 0.5 * base, 0.2]
        }
    })
}

/// The 2D distribution's samples fall in its cells in proportion to the function it was built
/// from (luminance times sin theta of the cell's centre here, as the environment builds it).
#[test]
fn distribution_2d_samples_cells_in_proportion_to_the_map() {
    let m = test_map();
    let f: Vec<f64> = m
        .texels
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let theta = PI * ((i / m.width) as f64 + 0.5) / m.height as f64;
            luminance(DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)) * theta.sin()
        })
        .collect();
    let d = Distribution2D::new(&f, m.width, m.height);
    let total: f64 = f.iter().sum();
    let mut rng = Rng::new(0xd157);
    let mut counts = vec![0.0; f.len()];
    for _ in 0..SAMPLES {
        let s = d.sample((rng.next_f64(), rng.next_f64()));
        counts[s.cell.1 * m.width + s.cell.0] += 1.0;
    }
    let expected: Vec<f64> = f.iter().map(|v| v / total).collect();
    chi2_compare("distribution 2d", &counts, &expected, SAMPLES);
}

/// The environment's directions have the density the map implies: in each texel's cell,
/// luminance x sin(theta of the cell's centre) / (I x 2 pi^2 sin theta), I the mean of
/// luminance x sin(theta_c) over the texels; computed here from the map alone, not by the
/// environment's `pdf`. A sampler that left out the sin theta factor (or flipped the rows)
/// would sample the poles (or the wrong hemisphere) too often.
#[test]
fn environment_samples_directions_as_the_map_implies() {
    let m = test_map();
    let env = Environment::new(&m, 1.0, DVec3::ZERO).expect("lit");
    let weight = |x: usize, y: usize| {
        let t = m.texels[y * m.width + x];
        let theta_c = PI * (y as f64 + 0.5) / m.height as f64;
        luminance(DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64)) * theta_c.sin()
    };
    let mean: f64 = (0..m.width * m.height)
        .map(|i| weight(i % m.width, i / m.width))
        .sum::<f64>()
        / (m.width * m.height) as f64;
    let pdf = |w: DVec3| {
        let mut u = w.x.atan2(-w.z) / (2.0 * PI);
        if u < 0.0 {
            u += 1.0;
        }
        let theta = w.y.clamp(-1.0, 1.0).acos();
        let x = ((u * m.width as f64) as usize).min(m.width - 1);
        let y = ((theta / PI * m.height as f64) as usize).min(m.height - 1);
        let sin_t = theta.sin();
        if sin_t <= 0.0 {
            return 0.0;
        }
        weight(x, y) / (mean * 2.0 * PI * PI * sin_t)
    };
    chi2_test(
        "environment map directions",
        |rng| env.sample((rng.next_f64(), rng.next_f64())).map(|s| s.wi),
        pdf,
    );
}

/// Turned by `rotate`, the environment's samples still have the density its `pdf` claims.
#[test]
fn rotated_environment_samples_match_its_pdf() {
    let env = Environment::new(&test_map(), 3.0, DVec3::new(30.0, -50.0, 70.0)).expect("lit");
    chi2_test(
        "rotated environment map",
        |rng| env.sample((rng.next_f64(), rng.next_f64())).map(|s| s.wi),
        |w| env.pdf(w),
    );
}
