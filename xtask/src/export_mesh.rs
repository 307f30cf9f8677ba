//! `cargo xtask export-meshes SCENE DIR`: each `[[mesh]]` of a scene file as ptui places it, one
//! binary PLY per entry (`DIR/mesh<i>.ply`, i counting the scene's `[[mesh]]` tables from 0), for
//! the Mitsuba reference harness (harness/mitsuba_mesh.py). Exporting what ptui built, rather
//! than letting Mitsuba read the OBJ or regenerate the knot, makes the two renderers see the same
//! triangles (winding included: the OBJ reader rewinds a face whose normals point the other way)
//! and the same shading normals (the knot's analytic ones, or the angle-weighted normals
//! `smooth = true` computes per OBJ position, where Mitsuba's OBJ loader would split vertices at
//! texture seams and average each side apart).
//!
//! Every triangle gets its own three vertices, so each corner carries the normal ptui interpolates
//! there; a flat mesh is written without normals (Mitsuba then shades by face normals).

use anyhow::{bail, Context};
use ptui::geometry::Shape;
use ptui::scene::{self, BuildOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

pub fn run(scene_path: &Path, dir: &Path) -> anyhow::Result<()> {
    let src = std::fs::read_to_string(scene_path)
        .with_context(|| format!("{}: cannot read", scene_path.display()))?;
    let table: toml::Table =
        toml::from_str(&src).with_context(|| format!("{}: not TOML", scene_path.display()))?;
    let meshes = match table.get("mesh") {
        Some(toml::Value::Array(a)) => a.clone(),
        Some(_) => bail!("{}: `mesh` is not an array of tables", scene_path.display()),
        None => Vec::new(),
    };
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let base_dir = scene_path
        .parent()
        .map_or_else(PathBuf::new, Path::to_path_buf);
    for (i, mesh) in meshes.into_iter().enumerate() {
        // A scene of this one entry, loaded by ptui itself: every primitive is one of its
        // triangles, in the order and placement the full scene has.
        let mut one = toml::Table::new();
        one.insert("mesh".into(), toml::Value::Array(vec![mesh]));
        let text = toml::to_string(&one)?;
        let options = BuildOptions {
            base_dir: Some(base_dir.clone()),
            ..Default::default()
        };
        let what = format!("{} mesh[{i}]", scene_path.display());
        let built =
            scene::load_str_with(&text, &what, &options).map_err(|e| anyhow::anyhow!("{e}"))?;
        let out = dir.join(format!("mesh{i}.ply"));
        let (tris, smooth) = write_ply(&built, &out)?;
        let normals = if smooth { "vertex normals" } else { "flat" };
        println!("{what}: {tris} triangles, {normals} -> {}", out.display());
    }
    Ok(())
}

/// Binary little-endian PLY: three vertices per triangle (x y z, and nx ny nz when the scene has
/// shading normals), faces (0 1 2), (3 4 5), ... Returns the triangle count and whether normals
/// were written.
fn write_ply(scene: &scene::Scene, out: &Path) -> anyhow::Result<(usize, bool)> {
    let smooth = scene.has_shading_normals();
    let mut tris = Vec::with_capacity(scene.prims.len());
    for (k, prim) in scene.prims.iter().enumerate() {
        let Shape::Triangle(t) = &prim.shape else {
            bail!("primitive {k} is not a triangle");
        };
        let p = t.p();
        let ns = if smooth {
            let ns = scene.shading[k];
            if ns[0] == [0.0; 3] {
                // A flat triangle among smooth ones: its face normal at every corner.
                let n = t.normal().context("degenerate triangle")?;
                let n = [n.x as f32, n.y as f32, n.z as f32];
                Some([n; 3])
            } else {
                Some(ns)
            }
        } else {
            None
        };
        tris.push((p, ns));
    }
    let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
    header += &format!("element vertex {}\n", 3 * tris.len());
    header += "property float x\nproperty float y\nproperty float z\n";
    if smooth {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    header += &format!(
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        tris.len()
    );
    let file = std::fs::File::create(out).with_context(|| format!("{}", out.display()))?;
    let mut w = std::io::BufWriter::new(file);
    w.write_all(header.as_bytes())?;
    for (p, ns) in &tris {
        for c in 0..3 {
            for v in [p[c].x, p[c].y, p[c].z] {
                w.write_all(&(v as f32).to_le_bytes())?;
            }
            if let Some(ns) = ns {
                for v in ns[c] {
                    w.write_all(&v.to_le_bytes())?;
                }
            }
        }
    }
    for k in 0..tris.len() {
        w.write_all(&[3u8])?;
        for c in 0..3 {
            let index = i32::try_from(3 * k + c).context("more vertices than a PLY int holds")?;
            w.write_all(&index.to_le_bytes())?;
        }
    }
    w.flush()?;
    Ok((tris.len(), smooth))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header's `element NAME COUNT` and whether vertex normals are declared.
    fn header(path: &Path) -> (usize, usize, bool) {
        let bytes = std::fs::read(path).unwrap();
        let end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap();
        let text = std::str::from_utf8(&bytes[..end]).unwrap();
        let count = |what: &str| -> usize {
            text.lines()
                .find_map(|l| l.strip_prefix(what))
                .unwrap()
                .trim()
                .parse()
                .unwrap()
        };
        let normals = text.contains("property float nx");
        let (v, f) = (count("element vertex "), count("element face "));
        let stride = if normals { 24 } else { 12 };
        // The body is exactly the vertices and the faces (1 count byte + 3 indices each).
        assert_eq!(bytes.len() - end - 11, v * stride + f * 13);
        (v, f, normals)
    }

    /// Each `[[mesh]]` becomes its own file, three vertices per triangle, with normals exactly
    /// when ptui shades it smooth; the other objects of the scene are left out.
    #[test]
    fn exports_each_mesh_with_its_normals() {
        let dir = std::env::temp_dir().join(format!("ptui-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("scene.toml");
        std::fs::write(
            &scene,
            "[[quad]]\ncorner = [0, 0, 0]\nedge1 = [1, 0, 0]\nedge2 = [0, 0, 1]\nemission = 1\n\
             [[mesh]]\ntorus_knot = { p = 2, q = 3, segments = 16, sides = 4, tube = 0.3 }\n\
             [[mesh]]\ntorus_knot = { p = 2, q = 3, segments = 16, sides = 4, tube = 0.3 }\n\
             smooth = false\nscale = 2\n",
        )
        .unwrap();
        run(&scene, &dir).unwrap();
        let smooth = header(&dir.join("mesh0.ply"));
        let flat = header(&dir.join("mesh1.ply"));
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(smooth, (3 * 128, 128, true));
        assert_eq!(flat, (3 * 128, 128, false));
    }
}
