//! Smooth shading from OBJ vertex normals: a furnace inside a closed smooth-shaded sphere mesh
//! (the analytic Le / (1 - a) up to the shading normals' small, bounded loss), a coarse smooth
//! sphere in a uniform environment whose silhouette must not go dark, and the `smooth` key.

use crate::common::{assert_furnace, load_str, render};
use ptui::analysis::stats::bonferroni_z;
use ptui::settings::{IntegratorKind, SettingsOverrides};
use std::f64::consts::PI;
use std::fmt::Write;

/// A unit UV sphere as OBJ text: `stacks` x `slices` quads (triangles at the poles), every
/// corner's normal the exact sphere normal, outwards or inwards; the faces are written with
/// their winding against those normals, so the reader's rewinding is exercised too.
fn sphere_obj(stacks: usize, slices: usize, inwards: bool) -> String {
    let mut s = String::from("# UV sphere\no sphere\ns 1\n");
    let sign = if inwards { -1.0 } else { 1.0 };
    let idx = |i: usize, j: usize| 1 + i * slices + (j % slices);
    for i in 0..=stacks {
        let theta = PI * i as f64 / stacks as f64;
        for j in 0..slices {
            let phi = 2.0 * PI * j as f64 / slices as f64;
            let (x, y, z) = (
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            writeln!(s, "v {x} {y} {z}").unwrap();
            writeln!(s, "vn {} {} {}", sign * x, sign * y, sign * z).unwrap();
        }
    }
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, c, d) = (idx(i, j), idx(i, j + 1), idx(i + 1, j + 1), idx(i + 1, j));
            // At the poles two corners coincide: the loader drops the zero-area half.
            writeln!(s, "f {a}//{a} {b}//{b} {c}//{c} {d}//{d}").unwrap();
        }
    }
    s
}

fn temp_obj(text: &str) -> tempfile::NamedTempFile {
    let mut f = tempfile::Builder::new()
        .prefix("ptui-smooth-")
        .suffix(".obj")
        .tempfile()
        .expect("temp OBJ");
    std::io::Write::write_all(&mut f, text.as_bytes()).expect("write OBJ");
    f
}

/// A camera inside a closed sphere mesh, normals inwards, albedo a, emitting Le: Le / (1 - a) in
/// every pixel for an energy-conserving surface. Shading normals lose the part of the cosine lobe
/// that falls below the faces, (1 - cos theta) / 2 at theta between face and vertex normal (6e-4
/// at this tessellation's 2.8 degrees at most; 4.7% at 25 degrees, as `sampling_chi2` measures),
/// which moves the answer by about a / (1 - a) times that: far below the test's resolution
/// (se < 1% of the answer, z at 1e-4).
fn furnace(albedo: f64, emission: f64, integrator: IntegratorKind) {
    let obj = temp_obj(&sphere_obj(32, 64, true));
    let src = format!(
        r#"
        [camera]
        position = [0.1, -0.2, 0.05]
        direction = [0.3, 0.2, -1]
        vfov = 90
        [render]
        width = 10
        height = 10
        spp = 512
        [[mesh]]
        path = {:?}
        color = {albedo}
        emission = {emission}
        "#,
        obj.path().display().to_string()
    );
    let scene = load_str(&src);
    assert!(scene.has_shading_normals());
    let r = render(
        scene,
        &SettingsOverrides {
            integrator: Some(integrator),
            ..Default::default()
        },
    );
    assert_eq!(r.stats().invalid, 0);
    let expected = emission / (1.0 - albedo);
    assert_furnace(r.film(), expected, &format!("{integrator:?}"));
}

#[test]
fn furnace_in_a_smooth_sphere_mesh_path() {
    furnace(0.5, 1.0, IntegratorKind::Path);
}

#[test]
fn furnace_in_a_smooth_sphere_mesh_naive() {
    furnace(0.7, 0.3, IntegratorKind::Naive);
}

/// A coarse smooth sphere (8 x 12: up to 22 degrees between a face and its corners' normals) of
/// albedo a in a uniform environment of radiance 1: every pixel sees a (the object reflects the
/// environment; it is convex, so nothing else), 1 (the environment) or a mix at the edge. Where
/// the view grazes past the shading normal (the silhouette band) the pixel must not go dark: a
/// BSDF that sampled only on `wo`'s side of the shading normal would drop most of its samples
/// below the face there. The loss of the cosine lobe below the faces is bounded by a few
/// percent at these angles, hence the floor of 0.9 a.
#[test]
fn a_coarse_smooth_sphere_has_no_dark_silhouette() {
    let albedo = 0.6;
    let obj = temp_obj(&sphere_obj(8, 12, false));
    for smooth in [true, false] {
        let src = format!(
            r#"
            background = 1
            [camera]
            position = [0, 0, 3.2]
            look_at = [0, 0, 0]
            vfov = 40
            [render]
            width = 24
            height = 24
            spp = 256
            [[mesh]]
            path = {:?}
            smooth = {smooth}
            rotate = [20, 10, 0]
            color = {albedo}
            "#,
            obj.path().display().to_string()
        );
        let scene = load_str(&src);
        assert_eq!(scene.has_shading_normals(), smooth);
        let r = render(scene, &SettingsOverrides::default());
        assert_eq!(r.stats().invalid, 0);
        let film = r.film();
        let p = film.pixels();
        let z = bonferroni_z(1e-4, p);
        let mut darkest = f64::INFINITY;
        for i in 0..p {
            let (m, v) = (film.mean(i).x, film.variance_of_mean(i).x.sqrt());
            darkest = darkest.min(m);
            assert!(
                m + z * v >= 0.9 * albedo && m - z * v <= 1.0,
                "smooth = {smooth}: pixel {i} ({}, {}) is {m:.4} +- {v:.4}",
                i % 24,
                i / 24
            );
        }
        // The object is in the picture.
        assert!(darkest < 0.7, "smooth = {smooth}: darkest pixel {darkest}");
    }
}

/// Real exporters' output: n-gons, negative indices, normals on some faces only, groups,
/// smoothing groups and a material library (one warning, in the build report).
#[test]
fn an_exporter_style_obj_loads_with_one_warning() {
    let obj = temp_obj(
        "# Blender 4.1\nmtllib thing.mtl\no Thing\nv -1 -1 0\nv 1 -1 0\nv 1.5 0.5 0\nv 0 1.5 0\n\
         v -1.5 0.5 0\nvn 0 0 1\nvt 0 0\ns 1\nusemtl Material.001\ng part\n\
         f -5/1/1 -4/1/1 -3/1/1 -2/1/1 -1/1/1\nusemtl Other\nf 1 3 4\n",
    );
    let src = format!(
        "[camera]\nposition = [0, 0, 4]\n[[mesh]]\npath = {:?}\n[[sphere]]\ncenter = [0, 0, 6]\n\
         radius = 1\nemission = 1\n",
        obj.path().display().to_string()
    );
    let scene = load_str(&src);
    // The pentagon is three triangles, the plain face one more (flat: no normals).
    assert_eq!(scene.prims.len(), 4 + 1);
    assert!(scene.has_shading_normals());
    let report = scene.report.to_string();
    assert_eq!(report.matches("warning").count(), 1, "{report}");
    assert!(
        report.contains("mtllib") && report.contains(".obj"),
        "{report}"
    );
}
