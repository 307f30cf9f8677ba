//! Wavefront material libraries (`.mtl`, named by an OBJ's `mtllib`): read, and each material
//! mapped onto ptui's material keys by one table (docs/SCENES-meshes.md, "OBJ materials"):
//!
//! | MTL | ptui |
//! |---|---|
//! | `Kd` / `map_Kd` | `color` (a texture replaces `Kd`, as Blender's importer does) |
//! | `Ke` / `map_Ke` | `emission` (one-sided; `Ke` multiplies the texture) |
//! | `Ks` > 0 with a non-black `Kd` (and `illum` not 0 or 1) | `material = "plastic"`, `specular = Ks`, `ior = Ni` |
//! | `Ks` > 0 with a black `Kd` | `material = "conductor"`, `color = Ks` (no Fresnel) |
//! | `Ns` | `alpha = (1 - sqrt(Ns) / 30)^2`: Blender's roughness from `Ns` (its exporter writes `Ns = (30 (1 - roughness))^2`), squared |
//! | `illum` 4, 6, 7, or `d` < 1 (without `map_d`), or `Tf` < 1 | `material = "glass"`, `ior = Ni` (1.5 when absent or 1), `color = Tf` |
//!
//! Anything else (`map_Bump`, `map_Ks`, `map_d`, `refl`, ...) is named once in the summary.
//! Texture paths are relative to the .mtl file; `-s` and `-o` scale and offset the texture
//! coordinates; a texture that is missing or not an image is an error naming the .mtl file and
//! line.

use super::description::{MaterialDesc, MaterialName, TextureDesc, Textured, UvPair};
use crate::checked::{Albedo, Ior, Rgb, Roughness, IOR_RANGE};
use crate::texture::load::Cache;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// One `newmtl` block as written.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    pub name: String,
    pub kd: Option<[f64; 3]>,
    pub ks: Option<[f64; 3]>,
    pub ke: Option<[f64; 3]>,
    pub tf: Option<[f64; 3]>,
    pub ns: Option<f64>,
    pub ni: Option<f64>,
    pub d: Option<f64>,
    pub illum: Option<u32>,
    pub map_kd: Option<MapStatement>,
    pub map_ke: Option<MapStatement>,
    pub map_d: bool,
}

/// A `map_...` statement: the file as written, its `-s` and `-o`, and its line.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MapStatement {
    pub file: String,
    pub scale: [f64; 2],
    pub offset: [f64; 2],
    pub line: usize,
}

/// A library's materials and the statements it skipped (keyword, first line, count).
#[derive(Clone, Debug, Default)]
pub struct Library {
    pub materials: Vec<MtlMaterial>,
    pub skipped: Vec<(String, usize, usize)>,
}

/// Parse an MTL file's bytes; `name` names it in errors (`name:line: reason`).
pub fn parse(bytes: &[u8], name: &str) -> Result<Library, String> {
    let mut lib = Library::default();
    let err = |line: usize, msg: String| format!("{name}:{line}: {msg}");
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = i + 1;
        let text = String::from_utf8_lossy(raw);
        let content = text.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        if keyword == "newmtl" {
            let name = content["newmtl".len()..].trim().to_string();
            lib.materials.push(MtlMaterial {
                name,
                ..MtlMaterial::default()
            });
            continue;
        }
        let Some(m) = lib.materials.last_mut() else {
            // Statements before the first `newmtl` belong to no material.
            skip(&mut lib.skipped, keyword, line);
            continue;
        };
        let rest: Vec<&str> = words.collect();
        let number = |w: &str| -> Result<f64, String> {
            let x: f64 = w
                .parse()
                .map_err(|_| err(line, format!("`{keyword}`: `{}` is not a number", short(w))))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(err(
                    line,
                    format!("`{keyword}`: {x} is not a finite number"),
                ))
            }
        };
        let color = |rest: &[&str]| -> Result<[f64; 3], String> {
            match rest {
                [] => Err(err(line, format!("truncated `{keyword}`: needs r [g b]"))),
                [w, ..] if w.starts_with("spectral") || w.starts_with("xyz") => Err(err(
                    line,
                    format!("`{keyword} {w}`: only RGB colours are read"),
                )),
                [r] => Ok([number(r)?; 3]),
                [r, g, b, ..] => Ok([number(r)?, number(g)?, number(b)?]),
                _ => Err(err(line, format!("`{keyword}`: needs r g b"))),
            }
        };
        let scalar = |rest: &[&str]| -> Result<f64, String> {
            match rest.first() {
                Some(w) => number(w),
                None => Err(err(line, format!("truncated `{keyword}`: needs a number"))),
            }
        };
        match keyword {
            "Kd" => m.kd = Some(color(&rest)?),
            "Ks" => m.ks = Some(color(&rest)?),
            "Ke" => m.ke = Some(color(&rest)?),
            "Tf" => m.tf = Some(color(&rest)?),
            "Ns" => m.ns = Some(scalar(&rest)?),
            "Ni" => m.ni = Some(scalar(&rest)?),
            "d" => m.d = Some(scalar(&rest)?),
            "Tr" => m.d = Some(1.0 - scalar(&rest)?),
            "illum" => m.illum = Some(scalar(&rest)?.max(0.0) as u32),
            "map_Kd" => m.map_kd = Some(map(&rest, line).map_err(|e| err(line, e))?),
            "map_Ke" => m.map_ke = Some(map(&rest, line).map_err(|e| err(line, e))?),
            "map_d" => {
                m.map_d = true;
                skip(&mut lib.skipped, keyword, line);
            }
            // The ambient colour has no meaning under global illumination.
            "Ka" | "map_Ka" => {}
            _ => skip(&mut lib.skipped, keyword, line),
        }
    }
    Ok(lib)
}

fn skip(skipped: &mut Vec<(String, usize, usize)>, keyword: &str, line: usize) {
    let keyword: String = keyword.chars().take(32).collect();
    match skipped.iter_mut().find(|(k, _, _)| *k == keyword) {
        Some((_, _, n)) => *n += 1,
        None => skipped.push((keyword, line, 1)),
    }
}

fn short(s: &str) -> String {
    s.chars().take(32).collect()
}

/// `map_... [-option args]... file`: `-s` and `-o` kept (u and v), other options passed over.
fn map(words: &[&str], line: usize) -> Result<MapStatement, String> {
    let mut out = MapStatement {
        scale: [1.0; 2],
        line,
        ..MapStatement::default()
    };
    let mut i = 0;
    while i < words.len() && words[i].starts_with('-') && words[i].len() > 1 {
        let option = words[i];
        i += 1;
        // Up to three numbers follow -s, -o and -t; the other options take a fixed count.
        let mut numbers = Vec::new();
        let most = match option {
            "-s" | "-o" | "-t" => 3,
            "-mm" => 2,
            _ => 1,
        };
        while numbers.len() < most && i < words.len() {
            match words[i].parse::<f64>() {
                Ok(x) if x.is_finite() => numbers.push(x),
                _ if matches!(option, "-s" | "-o" | "-t" | "-mm") => break,
                _ => {}
            }
            i += 1;
            if !matches!(option, "-s" | "-o" | "-t" | "-mm") {
                break;
            }
        }
        match (option, numbers.as_slice()) {
            ("-s", [u, rest @ ..]) => out.scale = [*u, rest.first().copied().unwrap_or(1.0)],
            ("-o", [u, rest @ ..]) => out.offset = [*u, rest.first().copied().unwrap_or(0.0)],
            ("-s" | "-o", []) => return Err(format!("`{option}` needs numbers")),
            _ => {}
        }
    }
    let file = words[i.min(words.len())..].join(" ");
    if file.is_empty() {
        return Err("a map statement needs a file name".into());
    }
    out.file = file;
    Ok(out)
}

/// The libraries an OBJ at `obj` names, by the `mtllib` statements as written: a name found
/// whole is one file (names may hold spaces), else each word is one.
pub fn library_paths(obj: &Path, written: &str) -> Vec<PathBuf> {
    let dir = obj.parent().unwrap_or(Path::new(""));
    let whole = dir.join(written);
    if whole.is_file() || !written.contains(' ') {
        return vec![whole];
    }
    written.split_whitespace().map(|w| dir.join(w)).collect()
}

/// Roughness from the Phong exponent as Blender's OBJ importer reads it, squared to alpha.
pub fn alpha_from_ns(ns: f64) -> f64 {
    let roughness = (1.0 - ns.max(0.0).sqrt() / 30.0).clamp(0.0, 1.0);
    roughness * roughness
}

/// What the table maps `m` to, its textures read (relative to `dir`) into `cache` so that a
/// missing or broken one fails here, naming `mtl` and the statement's line.
pub fn material_desc(
    m: &MtlMaterial,
    mtl: &str,
    dir: &Path,
    cache: &mut Cache,
) -> Result<MaterialDesc, String> {
    fn span<T>(v: T) -> Spanned<T> {
        Spanned::new(0..0, v)
    }
    let clamp3 = |c: [f64; 3]| c.map(|x| x.clamp(0.0, 1.0));
    let texture = |s: &MapStatement, cache: &mut Cache, factor: Option<[f64; 3]>| {
        // Absolute: the scene build joins relative texture paths to the scene file's folder.
        let path = std::path::absolute(dir.join(&s.file)).unwrap_or_else(|_| dir.join(&s.file));
        cache
            .get(&path, None)
            .map_err(|e| format!("{mtl}:{}: {e}", s.line))?;
        // MTL's -s and -o act on v growing upwards; ptui's v grows downwards: t = 1 - v.
        let scale = [s.scale[0], s.scale[1]];
        let offset = [s.offset[0], 1.0 - s.offset[1] - s.scale[1]];
        Ok::<_, String>(Box::new(TextureDesc {
            texture: Some(span(path.to_string_lossy().into_owned())),
            checker: None,
            scale: Some(span(UvPair(scale))),
            offset: Some(UvPair(offset)),
            factor: factor.map(|f| span(Rgb(f))),
            channel: None,
        }))
    };
    let mut desc = MaterialDesc::default();
    let kd_black = m.map_kd.is_none() && m.kd.is_some_and(|k| k.iter().all(|&x| x <= 0.0));
    desc.color = match (&m.map_kd, m.kd) {
        (Some(s), _) => Some(span(Textured::Texture(texture(s, cache, None)?))),
        (None, Some(kd)) => Some(span(Textured::Value(Albedo(clamp3(kd))))),
        (None, None) => None,
    };
    let ke = m.ke.map(|k| k.map(|x| x.max(0.0)));
    desc.emission = match (&m.map_ke, ke) {
        (Some(s), ke) => {
            let factor = ke.filter(|k| k.iter().any(|&x| x > 0.0));
            Some(span(Textured::Texture(texture(s, cache, factor)?)))
        }
        (None, Some(ke)) if ke.iter().any(|&x| x > 0.0) => Some(span(Textured::Value(Rgb(ke)))),
        _ => None,
    };
    let alpha = || {
        span(Textured::Value(Roughness(alpha_from_ns(
            m.ns.unwrap_or(0.0),
        ))))
    };
    let ior = |default: f64| {
        let ni =
            m.ni.filter(|&n| n > 1.0 && n >= IOR_RANGE.0 && n <= IOR_RANGE.1);
        span(Ior(ni.unwrap_or(default)))
    };
    let glass = matches!(m.illum, Some(4 | 6 | 7))
        || (m.d.is_some_and(|d| d < 1.0) && !m.map_d)
        || m.tf.is_some_and(|t| t.iter().any(|&x| x < 1.0));
    let ks = m.ks.map(clamp3).filter(|k| k.iter().any(|&x| x > 0.0));
    let specular_on = !matches!(m.illum, Some(0 | 1));
    if glass {
        desc.material = Some(MaterialName::Glass);
        desc.ior = Some(ior(1.5));
        desc.color = Some(span(Textured::Value(Albedo(clamp3(
            m.tf.unwrap_or([1.0; 3]),
        )))));
        if m.ns.is_some() {
            desc.alpha = Some(alpha());
        }
    } else if let (Some(ks), true) = (ks, specular_on) {
        desc.alpha = Some(alpha());
        if kd_black {
            desc.material = Some(MaterialName::Conductor);
            desc.color = Some(span(Textured::Value(Albedo(ks))));
        } else {
            desc.material = Some(MaterialName::Plastic);
            desc.specular = Some(span(Albedo(ks)));
            desc.ior = Some(ior(crate::scene::materials::DEFAULT_PLASTIC_IOR));
        }
    }
    Ok(desc)
}

/// `own` over `mtl`: each key the `[[mesh]]` entry gives replaces the library's; giving
/// `material` keeps only the library's colours and textures (its other keys belong to the
/// material it chose).
pub fn overlay(mtl: MaterialDesc, own: &MaterialDesc) -> MaterialDesc {
    let mtl = if own.material.is_some() {
        MaterialDesc {
            color: mtl.color,
            emission: mtl.emission,
            ..MaterialDesc::default()
        }
    } else {
        mtl
    };
    MaterialDesc {
        material: own.material.or(mtl.material),
        color: own.color.clone().or(mtl.color),
        emission: own.emission.clone().or(mtl.emission),
        ior: own.ior.clone().or(mtl.ior),
        two_sided: own.two_sided.clone().or(mtl.two_sided),
        alpha: own.alpha.clone().or(mtl.alpha),
        alpha_u: own.alpha_u.clone().or(mtl.alpha_u),
        alpha_v: own.alpha_v.clone().or(mtl.alpha_v),
        distribution: own.distribution.clone().or(mtl.distribution),
        eta: own.eta.clone().or(mtl.eta),
        k: own.k.clone().or(mtl.k),
        metal: own.metal.clone().or(mtl.metal),
        specular: own.specular.clone().or(mtl.specular),
        metallic: own.metallic.clone().or(mtl.metallic),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statements_are_read_per_material_and_the_rest_named() {
        let lib = parse(
            b"# Blender MTL\nnewmtl wood\nNs 225\nKa 1 1 1\nKd 0.8 0.5 0.2\nKs 0.5 0.5 0.5\n\
              Ni 1.45\nd 1\nillum 2\nmap_Kd -s 2 2 1 -o 0.5 0 0 tex/wood grain.png\n\
              map_Bump -bm 1 n.png\nnewmtl lamp\nKe 5 5 5\n",
            "a.mtl",
        )
        .unwrap();
        assert_eq!(lib.materials.len(), 2);
        let w = &lib.materials[0];
        assert_eq!(w.kd, Some([0.8, 0.5, 0.2]));
        let map = w.map_kd.as_ref().unwrap();
        assert_eq!(map.file, "tex/wood grain.png");
        assert_eq!(
            (map.scale, map.offset, map.line),
            ([2.0, 2.0], [0.5, 0.0], 10)
        );
        assert_eq!(lib.skipped, [("map_Bump".to_string(), 11, 1)]);
        assert_eq!(lib.materials[1].ke, Some([5.0; 3]));
    }

    #[test]
    fn bad_numbers_name_the_file_and_line() {
        let e = parse(b"newmtl a\nKd 1 x 1\n", "a.mtl").unwrap_err();
        assert!(e.starts_with("a.mtl:2: `Kd`: `x`"), "{e}");
        let e = parse(b"newmtl a\nNs nan\n", "a.mtl").unwrap_err();
        assert!(e.starts_with("a.mtl:2: ") && e.contains("finite"), "{e}");
        let e = parse(b"newmtl a\nmap_Kd -s 1 1\n", "a.mtl").unwrap_err();
        assert!(e.starts_with("a.mtl:2: ") && e.contains("file name"), "{e}");
    }

    fn kind(src: &str) -> MaterialDesc {
        let lib = parse(src.as_bytes(), "a.mtl").unwrap();
        material_desc(
            &lib.materials[0],
            "a.mtl",
            Path::new("."),
            &mut Cache::default(),
        )
        .unwrap()
    }

    #[test]
    fn the_table_chooses_the_material() {
        assert_eq!(kind("newmtl a\nKd 0.5 0.5 0.5\nKs 0 0 0\n").material, None);
        let p = kind("newmtl a\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nNs 225\n");
        assert_eq!(p.material, Some(MaterialName::Plastic));
        let alpha = match p.alpha.unwrap().into_inner() {
            Textured::Value(a) => a.0,
            Textured::Texture(_) => unreachable!(),
        };
        assert!((alpha - 0.25).abs() < 1e-12, "{alpha}");
        let c = kind("newmtl a\nKd 0 0 0\nKs 0.9 0.6 0.3\n");
        assert_eq!(c.material, Some(MaterialName::Conductor));
        assert_eq!(
            kind("newmtl a\nKd 1 1 1\nKs 1 1 1\nillum 1\n").material,
            None
        );
        let g = kind("newmtl a\nKd 1 1 1\nNi 1.33\nd 0.2\n");
        assert_eq!(g.material, Some(MaterialName::Glass));
        assert_eq!(g.ior.unwrap().into_inner().0, 1.33);
        assert_eq!(
            kind("newmtl a\nillum 7\nNi 1\n")
                .ior
                .unwrap()
                .into_inner()
                .0,
            1.5
        );
        let e = kind("newmtl a\nKe 4 4 0\n").emission.unwrap().into_inner();
        assert_eq!(e, Textured::Value(Rgb([4.0, 4.0, 0.0])));
    }

    #[test]
    fn a_missing_texture_names_the_mtl_file_and_line() {
        let lib = parse(b"newmtl a\n\nmap_Kd nowhere.png\n", "dir/a.mtl").unwrap();
        let e = material_desc(
            &lib.materials[0],
            "dir/a.mtl",
            Path::new("/nonexistent"),
            &mut Cache::default(),
        )
        .unwrap_err();
        assert!(
            e.starts_with("dir/a.mtl:3: /nonexistent/nowhere.png: cannot read texture"),
            "{e}"
        );
    }
}
