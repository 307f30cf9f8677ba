//! A large textured glTF binary for the load benchmark (benches/HISTORY.md, issue 47): a real
//! model's triangles subdivided and its texture enlarged, so that both the geometry and the
//! textures are the size of a detailed download, while the picture stays the model's.
//!
//! ```sh
//! harness/get_easy_gltf.sh
//! cargo xtask large-model scenes/models/easy-gltf/head.glb target/large/head-large.glb
//! ```
//!
//! Each subdivision level splits every triangle into four at its edges' midpoints, shared
//! between the triangles on either side (positions, normals and texture coordinates averaged),
//! so the mesh stays indexed as exporters write it: 5 levels take the head's 2,492 triangles
//! to 2,551,808. The base colour texture is resampled (bilinear) to `--size` texels a side and
//! given +-6 levels of hashed grain, so the PNG does not shrink to nothing as a smooth
//! enlargement would; a metallic-roughness texture of half that side (roughness 0.3-0.7, no
//! metal, the same grain) is added. Both PNGs are embedded in the binary chunk, the mesh under
//! the node rotation the original has.

use anyhow::{bail, Context};
use image::{ImageEncoder, RgbImage};
use std::collections::HashMap;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// A .glb with one textured triangle mesh (the head of harness/get_easy_gltf.sh).
    pub from: std::path::PathBuf,
    /// Where to write the .glb.
    pub out: std::path::PathBuf,
    /// Subdivision levels (each multiplies the triangles by 4).
    #[arg(long, default_value_t = 5)]
    pub levels: u32,
    /// Texels a side of the base colour texture.
    #[arg(long, default_value_t = 8192)]
    pub size: u32,
}

/// An indexed mesh: per vertex position, normal and (u, v); triangles as index triples.
struct Indexed {
    p: Vec<[f32; 3]>,
    n: Vec<[f32; 3]>,
    uv: Vec<[f32; 2]>,
    tris: Vec<[u32; 3]>,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let t = std::time::Instant::now();
    let bytes = std::fs::read(&args.from).with_context(|| args.from.display().to_string())?;
    let gltf = gltf::Gltf::from_slice(&bytes)?;
    let blob = gltf
        .blob
        .as_deref()
        .context("not a .glb with a binary chunk")?;
    let doc = &gltf.document;
    let (node, mesh) = doc
        .nodes()
        .find_map(|n| n.mesh().map(|m| (n.clone(), m)))
        .context("no mesh node")?;
    let prim = mesh.primitives().next().context("no primitive")?;
    let reader = prim.reader(|_| Some(blob));
    let p: Vec<[f32; 3]> = reader.read_positions().context("no positions")?.collect();
    let n: Vec<[f32; 3]> = reader.read_normals().context("no normals")?.collect();
    let uv: Vec<[f32; 2]> = reader
        .read_tex_coords(0)
        .context("no TEXCOORD_0")?
        .into_f32()
        .collect();
    let idx: Vec<u32> = reader
        .read_indices()
        .context("no indices")?
        .into_u32()
        .collect();
    let mut m = Indexed {
        p,
        n,
        uv,
        tris: idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    for _ in 0..args.levels {
        m = subdivide(&m);
    }
    let texture = doc
        .materials()
        .find_map(|mat| mat.pbr_metallic_roughness().base_color_texture())
        .context("no base colour texture")?;
    let gltf::image::Source::View { view, .. } = texture.texture().source().source() else {
        bail!("the base colour image is not in the binary chunk");
    };
    let png = &blob[view.offset()..view.offset() + view.length()];
    let base = image::load_from_memory(png)?.to_rgb8();
    let side = args.size;
    let color = grain(
        image::imageops::resize(&base, side, side, image::imageops::FilterType::Triangle),
        1,
    );
    let mr = grain(
        RgbImage::from_fn(side / 2, side / 2, |x, _| {
            let r = 77 + (102 * x / (side / 2).max(1)) as u8; // roughness 0.3..0.7 across u
            image::Rgb([0, r, 0])
        }),
        2,
    );
    let pngs = [encode(&color)?, encode(&mr)?];
    let rotation = node.transform().decomposed().1;
    let glb = write_glb(&m, rotation, &pngs)?;
    if let Some(dir) = args.out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = args.out.with_extension("glb.tmp");
    std::fs::write(&tmp, &glb)?;
    std::fs::rename(&tmp, &args.out)?;
    let texels = color.len() + mr.len();
    println!(
        "wrote {}: {} triangles, {} vertices; textures {}x{} and {}x{} RGB ({:.1} MiB of texels, \
         {:.1} MB of PNG); {:.1} MB in all, in {:.1} s",
        args.out.display(),
        m.tris.len(),
        m.p.len(),
        side,
        side,
        side / 2,
        side / 2,
        texels as f64 / (1 << 20) as f64,
        (pngs[0].len() + pngs[1].len()) as f64 / 1e6,
        glb.len() as f64 / 1e6,
        t.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Every triangle split into four at its edges' midpoints, each midpoint made once per edge.
fn subdivide(m: &Indexed) -> Indexed {
    let mut out = Indexed {
        p: m.p.clone(),
        n: m.n.clone(),
        uv: m.uv.clone(),
        tris: Vec::with_capacity(m.tris.len() * 4),
    };
    let mut mids: HashMap<(u32, u32), u32> = HashMap::with_capacity(m.tris.len() * 2);
    let mut mid = |a: u32, b: u32, out: &mut Indexed| -> u32 {
        *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (a, b) = (a as usize, b as usize);
            let avg3 = |x: [f32; 3], y: [f32; 3]| [0, 1, 2].map(|k| 0.5 * (x[k] + y[k]));
            let nn = avg3(m.n[a], m.n[b]);
            let len = (nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2])
                .sqrt()
                .max(1e-12);
            out.p.push(avg3(m.p[a], m.p[b]));
            out.n.push(nn.map(|c| c / len));
            out.uv.push([0, 1].map(|k| 0.5 * (m.uv[a][k] + m.uv[b][k])));
            (out.p.len() - 1) as u32
        })
    };
    for &[a, b, c] in &m.tris {
        let (ab, bc, ca) = (
            mid(a, b, &mut out),
            mid(b, c, &mut out),
            mid(c, a, &mut out),
        );
        out.tris
            .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    out
}

/// `img` with +-6 levels of grain from a hash of the texel and `seed`.
fn grain(mut img: RgbImage, seed: u32) -> RgbImage {
    for (x, y, px) in img.enumerate_pixels_mut() {
        let mut h = x.wrapping_mul(0x9E37_79B1) ^ y.wrapping_mul(0x85EB_CA77) ^ seed;
        for c in px.0.iter_mut() {
            h ^= h >> 15;
            h = h.wrapping_mul(0x2C1B_3C6D);
            h ^= h >> 12;
            *c = (*c as i32 + (h % 13) as i32 - 6).clamp(0, 255) as u8;
        }
    }
    img
}

fn encode(img: &RgbImage) -> anyhow::Result<Vec<u8>> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out).write_image(
        img.as_raw(),
        img.width(),
        img.height(),
        image::ExtendedColorType::Rgb8,
    )?;
    Ok(out)
}

/// A GLB of the mesh (one node with `rotation`, one primitive, one material with both
/// textures) and the two PNGs, all in the binary chunk.
fn write_glb(m: &Indexed, rotation: [f32; 4], pngs: &[Vec<u8>; 2]) -> anyhow::Result<Vec<u8>> {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut push = |bin: &mut Vec<u8>, data: &[u8]| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push((bin.len(), data.len()));
        bin.extend_from_slice(data);
    };
    let floats = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    push(&mut bin, &floats(m.p.as_flattened()));
    push(&mut bin, &floats(m.n.as_flattened()));
    push(&mut bin, &floats(m.uv.as_flattened()));
    let idx: Vec<u8> = m
        .tris
        .as_flattened()
        .iter()
        .flat_map(|i| i.to_le_bytes())
        .collect();
    push(&mut bin, &idx);
    push(&mut bin, &pngs[0]);
    push(&mut bin, &pngs[1]);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (lo, hi) = m.p.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [0, 1, 2].map(|k| lo[k].min(p[k])),
                [0, 1, 2].map(|k| hi[k].max(p[k])),
            )
        },
    );
    let view_json: Vec<String> = views
        .iter()
        .map(|(o, l)| format!(r#"{{"buffer":0,"byteOffset":{o},"byteLength":{l}}}"#))
        .collect();
    let (nv, ni) = (m.p.len(), m.tris.len() * 3);
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"cargo xtask large-model"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"rotation":[{},{},{},{}]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"indices":3,"material":0}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}},"metallicRoughnessTexture":{{"index":1}},"metallicFactor":1,"roughnessFactor":1}}}}],
"textures":[{{"source":0}},{{"source":1}}],
"images":[{{"bufferView":4,"mimeType":"image/png"}},{{"bufferView":5,"mimeType":"image/png"}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{nv},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},
{{"bufferView":1,"componentType":5126,"count":{nv},"type":"VEC3"}},
{{"bufferView":2,"componentType":5126,"count":{nv},"type":"VEC2"}},
{{"bufferView":3,"componentType":5125,"count":{ni},"type":"SCALAR"}}],
"bufferViews":[{}],"buffers":[{{"byteLength":{}}}]}}"#,
        rotation[0],
        rotation[1],
        rotation[2],
        rotation[3],
        lo[0],
        lo[1],
        lo[2],
        hi[0],
        hi[1],
        hi[2],
        view_json.join(","),
        bin.len()
    );
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&u32::try_from(total)?.to_le_bytes());
    out.extend_from_slice(&u32::try_from(json.len())?.to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&u32::try_from(bin.len())?.to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}
