//! The models people download: a textured OBJ with its .mtl against Mitsuba 3, the same scene
//! as a glTF binary against the OBJ (equivalence), and bad model files refused in one line,
//! naming the file, quickly and without half a scene.

use crate::common;
use ptui::analysis::reference;
use ptui::render::Renderer;
use ptui::scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn textured_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/examples/textured")
}

/// `scene`'s render at 160x120 with `spp` independent samples per pixel (no adaptive sampling).
fn render(scene: scene::Scene, spp: u32, seed: u64) -> Renderer {
    common::render_160x120(scene, spp, Some(seed))
}

fn load(name: &str) -> scene::Scene {
    let path = textured_dir().join(name);
    scene::load(path.to_str().expect("utf-8 path")).unwrap_or_else(|e| panic!("{e}"))
}

/// The mean of each channel over the pixel rectangle [x0, x1) x [y0, y1) of an RGB image.
fn region_mean(
    img: &[f32],
    width: usize,
    (x0, x1, y0, y1): (usize, usize, usize, usize),
) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for y in y0..y1 {
        for x in x0..x1 {
            for c in 0..3 {
                sum[c] += img[(y * width + x) * 3 + c] as f64;
            }
        }
    }
    sum.map(|s| s / ((x1 - x0) * (y1 - y0)) as f64)
}

/// The wall's top-left quadrant in the 160x120 image: red in the texture's top-left.
const WALL_TOP_LEFT: (usize, usize, usize, usize) = (60, 75, 40, 50);

/// The textured OBJ renders as Mitsuba 3 renders the same files (tests/refs/textured-room.exr,
/// harness/mitsuba_textured.py): each channel's mean within 1% (or 4 standard errors where that
/// is wider), and the wall's picture the right way round (its top-left quadrant red in both).
#[test]
fn a_textured_obj_renders_as_mitsuba_renders_it() {
    let reference = reference::load(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/refs/textured-room.exr"),
    )
    .expect("reference");
    let r = render(load("room.toml"), 64, 1);
    let img = r.film().mean_rgb_f32();
    let (ours, theirs) = (reference::channel_means(&img), reference.channel_means());
    let film = r.film();
    let n = film.pixels() as f64;
    for c in 0..3 {
        let var: f64 = (0..film.pixels())
            .map(|i| film.variance_of_mean(i)[c])
            .sum();
        let se = (var / (n * n)).sqrt();
        let tolerance = (4.0 * se / theirs[c]).max(0.01);
        let rel = ours[c] / theirs[c] - 1.0;
        assert!(
            rel.abs() < tolerance,
            "channel {c}: {:.5} vs Mitsuba's {:.5}",
            ours[c],
            theirs[c]
        );
    }
    for (what, image) in [("ptui", &img), ("Mitsuba", &reference.data)] {
        let [r, g, b] = region_mean(image, 160, WALL_TOP_LEFT);
        assert!(
            r > 5.0 * g && r > 5.0 * b,
            "{what}: the wall's top left is {r:.3} {g:.3} {b:.3}, not red"
        );
    }
}

/// The same at 1024 samples per pixel, the error falling like 1/sqrt(spp) down to the
/// reference's noise (`common::assert_converges_to`).
#[test]
#[ignore = "deep tier: cargo test --release -- --ignored"]
fn a_textured_obj_converges_to_mitsuba() {
    common::assert_converges_to_mitsuba(load("room.toml"), "textured-room", common::Length::Long);
}

/// The scene as a glTF binary (node transforms placing the wall and the box, textures in the
/// binary, metallic-roughness materials of metalness 0 and KHR_materials_specular factor 0, the
/// Lambertian base alone) renders the image of the OBJ + MTL: per pixel the two differ by no
/// more than their noise (the mean of the squared z-scores near 1), and a mirrored texture or a
/// misplaced node would differ by many.
#[test]
fn a_gltf_renders_as_the_same_scene_as_obj() {
    let a = render(load("room.toml"), 32, 1);
    let b = render(load("room-gltf.toml"), 32, 2);
    let (fa, fb) = (a.film(), b.film());
    let (mut z2, mut count) = (0.0, 0usize);
    for i in 0..fa.pixels() {
        let (ma, mb) = (fa.mean(i), fb.mean(i));
        let (va, vb) = (fa.variance_of_mean(i), fb.variance_of_mean(i));
        for c in 0..3 {
            let v = va[c] + vb[c];
            if v > 0.0 {
                z2 += (ma[c] - mb[c]).powi(2) / v;
                count += 1;
            }
        }
    }
    let mean_z2 = z2 / count as f64;
    // With 32 samples the variance estimates make z^2 an F(1, 62)-like variable: mean ~1.03.
    assert!(
        count > 20_000 && mean_z2 < 1.2,
        "mean z^2 {mean_z2:.3} over {count} values"
    );
}

/// A file's error: one line naming `needle` (the file, its accessor or line), found within a
/// second, and no scene.
fn refused(scene_toml: &Path, needles: &[&str]) -> String {
    let t = Instant::now();
    let e = scene::load(scene_toml.to_str().expect("utf-8"))
        .expect_err("refused")
        .to_string();
    assert!(
        t.elapsed().as_secs_f64() < 1.0,
        "took {:?}: {e}",
        t.elapsed()
    );
    assert!(!e.contains('\n'), "more than one line: {e}");
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
    e
}

/// `[[mesh]] path = <model>` in a scene file in `dir`.
fn mesh_scene(dir: &Path, model: &str) -> PathBuf {
    let p = dir.join("scene.toml");
    std::fs::write(
        &p,
        format!("[camera]\nposition = [0, 1, 6]\n\n[[mesh]]\npath = \"{model}\"\n"),
    )
    .unwrap();
    p
}

/// The GLB's JSON chunk and binary chunk start (bytes).
fn glb_chunks(glb: &[u8]) -> (usize, usize) {
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    (20, 20 + json_len + 8)
}

#[test]
fn broken_gltf_files_are_refused_naming_the_file_and_part() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let glb = std::fs::read(textured_dir().join("room.glb")).unwrap();
    let (_, bin) = glb_chunks(&glb);

    // Cut in its binary chunk: the buffer is shorter than it says.
    std::fs::write(dir.join("cut.glb"), &glb[..bin + 100]).unwrap();
    refused(&mesh_scene(dir, "cut.glb"), &["cut.glb"]);

    // A NaN where the floor's first vertex is (accessor 0 starts the binary chunk).
    let mut nan = glb.clone();
    nan[bin..bin + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(dir.join("nan.glb"), &nan).unwrap();
    refused(
        &mesh_scene(dir, "nan.glb"),
        &["nan.glb", "accessor 0", "not finite"],
    );

    // A .gltf whose .bin is missing.
    let gltf = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
        "bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":"gone.bin","byteLength":36}]}"#;
    std::fs::write(dir.join("lost.gltf"), gltf).unwrap();
    refused(
        &mesh_scene(dir, "lost.gltf"),
        &["lost.gltf", "buffer 0", "gone.bin"],
    );

    // An index past the vertices.
    let mut tri = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        tri.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 7] {
        tri.extend_from_slice(&i.to_le_bytes());
    }
    std::fs::write(dir.join("tri.bin"), &tri).unwrap();
    let indexed = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
                     {"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],
        "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}],
        "buffers":[{"uri":"tri.bin","byteLength":42}]}"#;
    std::fs::write(dir.join("index.gltf"), indexed).unwrap();
    refused(
        &mesh_scene(dir, "index.gltf"),
        &["index.gltf", "accessor 1", "index 7 is out of range"],
    );

    // Not glTF at all.
    std::fs::write(dir.join("text.glb"), "v 0 0 0\n").unwrap();
    refused(&mesh_scene(dir, "text.glb"), &["text.glb"]);
}

#[test]
fn broken_textures_and_materials_are_refused_naming_the_file_and_line() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    std::fs::write(dir.join("quad.obj"), "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nusemtl a\nf 1/1 2/2 3/3\n").unwrap();
    // A texture that is not an image.
    std::fs::write(dir.join("notes.png"), "these are notes\n").unwrap();
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl a\nKd 1 1 1\n\nmap_Kd notes.png\n",
    )
    .unwrap();
    refused(
        &mesh_scene(dir, "quad.obj"),
        &["m.mtl:4", "notes.png", "not an image"],
    );
    // A texture that is missing.
    std::fs::write(dir.join("m.mtl"), "newmtl a\nmap_Kd gone.png\n").unwrap();
    refused(
        &mesh_scene(dir, "quad.obj"),
        &["m.mtl:2", "gone.png", "no such file"],
    );
    // A PNG whose header claims 100000 x 100000 texels, refused from the header.
    let mut png = std::fs::read(textured_dir().join("floor.png")).unwrap();
    png[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    png[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32fast::hash(&png[12..29]);
    png[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(dir.join("huge.png"), &png).unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl a\nmap_Kd huge.png\n").unwrap();
    refused(
        &mesh_scene(dir, "quad.obj"),
        &["m.mtl:2", "huge.png", "100000 x 100000"],
    );
    // Texture coordinate indices out of range.
    std::fs::write(dir.join("m.mtl"), "newmtl a\nKd 1 1 1\n").unwrap();
    std::fs::write(
        dir.join("uv.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/2 3/1\n",
    )
    .unwrap();
    refused(
        &mesh_scene(dir, "uv.obj"),
        &["uv.obj:5", "texture coordinate index 2"],
    );
    // A scene file's texture key.
    let p = dir.join("tex.toml");
    std::fs::write(
        &p,
        "[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\ncolor = { texture = \"huge.png\" }\n",
    )
    .unwrap();
    refused(
        &p,
        &[
            "tex.toml:4",
            "sphere[0].color.texture",
            "huge.png",
            "100000 x 100000",
        ],
    );
}
