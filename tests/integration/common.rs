//! Shared helpers for the integration tests: rendering a scene to a film, and statistics.

use ptui::render::film::Film;
use ptui::render::Renderer;
use ptui::scene::{self, Scene};
use ptui::settings::{RenderSettings, SettingsOverrides};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// The shared reference directory, beside the checkout.
pub fn refs_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/refs")
}

pub fn settings_for(scene: &Scene, layer: &SettingsOverrides) -> RenderSettings {
    RenderSettings::merged(&[&scene.render, layer])
}

/// Render `scene` with the given overrides to completion and return the renderer.
pub fn render(scene: Arc<Scene>, layer: &SettingsOverrides) -> Renderer {
    let settings = settings_for(&scene, layer);
    let mut r = Renderer::new(scene, settings).expect("valid settings");
    r.render(&AtomicBool::new(false), |_| true);
    r
}

pub fn load_str(src: &str) -> Arc<Scene> {
    Arc::new(scene::load_str(src, "test.toml").unwrap_or_else(|e| panic!("{e}")))
}

/// Upper tail probability of the chi-square distribution with `dof` degrees of freedom.
pub fn chi2_sf(x: f64, dof: f64) -> f64 {
    1.0 - regularized_gamma_p(dof / 2.0, x / 2.0)
}

/// Regularised lower incomplete gamma P(a, x) (Numerical Recipes: series below a+1, continued
/// fraction above).
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let ln_gamma_a = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut term, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        sum * (-x + a * x.ln() - ln_gamma_a).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        1.0 - (-x + a * x.ln() - ln_gamma_a).exp() * h
    }
}

/// Lanczos approximation of ln Gamma(x), x > 0.
pub fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Two-sided normal tail: the |z| exceeded with probability `p`.
pub fn z_for_two_sided(p: f64) -> f64 {
    // Bisection on the complementary error function: plenty fast for a test.
    let (mut lo, mut hi) = (0.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if erfc(mid / std::f64::consts::SQRT_2) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// erfc via the continued-fraction-free Chebyshev fit of Numerical Recipes (erfcc), |err| < 1.2e-7.
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// A furnace's check: every pixel of `film` reads `expected` (per-pixel z-tests, Bonferroni over
/// the 3P tests at a 1e-4 family-wise level), so does the image mean (the pixel means are
/// independent, so the variance of their average is the sum of their variances over P^2), and
/// the image mean's standard error is under 1% of `expected`, tight enough to mean something.
pub fn assert_furnace(film: &Film, expected: f64, what: &str) {
    let p = film.pixels();
    let (mut sum, mut var) = (0.0, 0.0);
    let z_pixel = z_for_two_sided(1e-4 / (3 * p) as f64);
    for i in 0..p {
        let m = film.mean(i);
        let v = film.variance_of_mean(i);
        for c in 0..3 {
            let z = (m[c] - expected) / v[c].sqrt();
            assert!(
                z.abs() < z_pixel,
                "{what}: pixel {i} channel {c}: {} vs {expected} (z = {z:.2}, limit {z_pixel:.2})",
                m[c]
            );
        }
        sum += m.x;
        var += v.x;
    }
    let mean = sum / p as f64;
    let se = var.sqrt() / p as f64;
    let z = (mean - expected) / se;
    assert!(
        z.abs() < z_for_two_sided(1e-4),
        "{what}: image mean {mean:.5} vs {expected} (se {se:.5}, z {z:.2})"
    );
    assert!(
        se < 0.01 * expected,
        "{what}: se {se} too large to test anything"
    );
}
