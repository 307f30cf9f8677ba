//! The thin-lens camera: a point light off the focus plane spreads over the disc the lens
//! formula gives, a point on it stays sharp, and `aperture = 0` is the pinhole image bit for bit.

use crate::common::{load_str, render};
use ptui::analysis::stats::bonferroni_z;
use ptui::render::film::Film;
use ptui::settings::SettingsOverrides;

const SIZE: u32 = 96;
const VFOV: f64 = 30.0;
/// The light: a sphere of this radius on the view axis at depth `DEPTH`.
const LIGHT_RADIUS: f64 = 0.04;
const DEPTH: f64 = 10.0;

fn scene(lens: &str) -> String {
    format!(
        "[camera]\nposition = [0, 0, 0]\ndirection = [0, 0, -1]\nvfov = {VFOV}\n{lens}\n\
         [render]\nwidth = {SIZE}\nheight = {SIZE}\nspp = 2048\nseed = 3\nadaptive = false\n\
         [[sphere]]\ncenter = [0, 0, -{DEPTH}]\nradius = {LIGHT_RADIUS}\ncolor = 0\nemission = 100\n"
    )
}

/// The light's image's second moment about the image centre (x and y together, in pixels^2)
/// and its standard error, by the delta method on the ratio of sums with the film's per-pixel
/// variances (the pixel means are independent).
fn second_moment(film: &Film) -> (f64, f64) {
    let c = SIZE as f64 / 2.0;
    let (mut a, mut b, mut var_a, mut var_b, mut cov) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..film.pixels() {
        let (x, y) = (
            (i as u32 % SIZE) as f64 + 0.5,
            (i as u32 / SIZE) as f64 + 0.5,
        );
        let d2 = (x - c).powi(2) + (y - c).powi(2);
        let (w, v) = (film.mean(i).x, film.variance_of_mean(i).x);
        a += w * d2;
        b += w;
        var_a += v * d2 * d2;
        var_b += v;
        cov += v * d2;
    }
    let m = a / b;
    let var = (var_a - 2.0 * m * cov + m * m * var_b) / (b * b);
    (m, var.sqrt())
}

/// What [`second_moment`] should read when the light's image is a disc of radius `blur` pixels
/// (the lens) spread again by the light's own disc image: the expected pixel-centre moment of
/// a point drawn from both discs, by quadrature on polar grids (the film integrates over pixel
/// squares, so a point counts at its pixel's centre).
fn expected_moment(blur: f64) -> f64 {
    let tan = (VFOV.to_radians() / 2.0).tan();
    let light = LIGHT_RADIUS / DEPTH * SIZE as f64 / (2.0 * tan);
    let c = SIZE as f64 / 2.0;
    let disc = |radius: f64, n_r: usize, n_t: usize| {
        let mut points = Vec::with_capacity(n_r * n_t);
        for i in 0..n_r {
            let r = radius * ((i as f64 + 0.5) / n_r as f64).sqrt();
            for j in 0..n_t {
                let t = std::f64::consts::TAU * (j as f64 + 0.5) / n_t as f64;
                points.push((r * t.cos(), r * t.sin()));
            }
        }
        points
    };
    let (lens, own) = (disc(blur, 200, 400), disc(light, 8, 16));
    let mut sum = 0.0;
    for &(lx, ly) in &lens {
        for &(ox, oy) in &own {
            let (x, y) = (c + lx + ox, c + ly + oy);
            sum += (x.floor() + 0.5 - c).powi(2) + (y.floor() + 0.5 - c).powi(2);
        }
    }
    sum / (lens.len() * own.len()) as f64
}

#[test]
fn a_point_off_the_focus_plane_spreads_over_the_lens_formula_disc() {
    let (aperture, focus) = (0.2, 5.0);
    let s = load_str(&scene(&format!(
        "aperture = {aperture}\nfocus_distance = {focus}"
    )));
    let blur = s.camera.blur_radius_pixels(SIZE, DEPTH);
    // R |z - F| / z on the focus plane, in pixels there: 0.1 of 2 F tan(15 deg) per 96 px.
    assert!((blur - 0.1 * 96.0 / (10.0 * (15f64).to_radians().tan())).abs() < 1e-9);
    let r = render(s, &SettingsOverrides::default());
    let (m, se) = second_moment(r.film());
    let expected = expected_moment(blur);
    let z = (m - expected) / se;
    assert!(
        z.abs() < bonferroni_z(1e-4, 1),
        "second moment {m:.3} px^2 vs {expected:.3} (se {se:.3}, z {z:.2}); blur radius {blur:.3} px"
    );
    // Power: the test tells a disc 3% wider from this one.
    let wrong = expected_moment(1.03 * blur);
    assert!(
        (wrong - expected).abs() > 4.0 * se,
        "a 3% wider disc is within noise (se {se:.3})"
    );
    // The tracer connects light paths to a pinhole, so it is not built behind a lens.
    assert!(
        r.caustics_note().contains("thin-lens"),
        "{}",
        r.caustics_note()
    );
}

#[test]
fn a_point_on_the_focus_plane_is_sharp() {
    let s = load_str(&scene(&format!("aperture = 0.2\nfocus_distance = {DEPTH}")));
    assert!(s.camera.blur_radius_pixels(SIZE, DEPTH) < 1e-12);
    let r = render(s, &SettingsOverrides::default());
    let (m, se) = second_moment(r.film());
    let expected = expected_moment(0.0);
    assert!(
        (m - expected).abs() < bonferroni_z(1e-4, 1) * se + 1e-3,
        "in focus: second moment {m:.4} px^2 vs {expected:.4} (se {se:.4})"
    );
}

#[test]
fn focus_on_sets_the_focus_plane_through_the_point() {
    let s = load_str(&scene("aperture = 0.2\nfocus_on = [3, -1, -7]"));
    assert!((s.camera.focus_distance - 7.0).abs() < 1e-12);
    // Without either, the lens focuses on what the centre ray hits: the light.
    let s = load_str(&scene("aperture = 0.2"));
    assert!((s.camera.focus_distance - (DEPTH - LIGHT_RADIUS)).abs() < 1e-9);
}

#[test]
fn no_aperture_is_the_pinhole_image_bit_for_bit() {
    let pinhole = render(load_str(&scene("")), &SettingsOverrides::default());
    let zero = render(
        load_str(&scene("aperture = 0\nfocus_distance = 2")),
        &SettingsOverrides::default(),
    );
    // The settings' lens (CLI, TUI) replaces the scene's: a zero aperture there too.
    let overridden = render(
        load_str(&scene("aperture = 0.3")),
        &SettingsOverrides {
            aperture: Some(0.0),
            ..Default::default()
        },
    );
    for other in [&zero, &overridden] {
        for i in 0..pinhole.film().pixels() {
            assert_eq!(
                pinhole.film().mean(i).to_array().map(f64::to_bits),
                other.film().mean(i).to_array().map(f64::to_bits),
                "pixel {i}"
            );
        }
    }
}
