//! glTF materials mapped to ptui's:
//!
//! | glTF | ptui |
//! |---|---|
//! | `baseColorFactor` x `baseColorTexture` | `color` (sRGB texture; alpha left out) |
//! | `metallicFactor`, `roughnessFactor`, `metallicRoughnessTexture` (B, G; linear) | `material = "metallic-roughness"`: `metallic`, `alpha` = roughness^2 |
//! | `emissiveFactor` x `emissiveTexture` x `KHR_materials_emissive_strength` | `emission` (one-sided unless `doubleSided`) |
//! | `KHR_materials_ior` | the coat's index (f0), or the glass's |
//! | `KHR_materials_specular` factor and colour | the coat's f90 and f0 tint |
//! | `KHR_materials_transmission` factor > 0 | `material = "glass"`, `alpha` = roughness^2, `ior`, `color` = base colour |
//! | `KHR_texture_transform` offset and scale | the texture's `offset` and `scale` |
//!
//! Normal and occlusion maps, alpha blending and masking, rotated texture transforms, other
//! texture coordinate sets and non-repeating samplers are named in the summary, once each.

use super::textures::MaterialTextures;
use crate::material::{Distribution, Microfacet, SPECULAR_ALPHA};
use crate::material::{Glossy, Material, MaterialKind, MetallicRoughness, RoughDielectric};
use crate::math::DVec3;
use crate::texture::{Encoding, Image, Pattern, Texture};
use std::collections::HashSet;
use std::sync::Arc;

/// Per glTF material index its material and textures, the default material (the
/// specification's: white, metallic 1, roughness 1) last.
pub type Materials = Vec<(Material, Option<MaterialTextures>)>;

/// The images the materials use.
pub fn used_images(doc: &gltf::Document) -> HashSet<usize> {
    let mut used = HashSet::new();
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        for info in [
            pbr.base_color_texture(),
            pbr.metallic_roughness_texture(),
            m.emissive_texture(),
        ]
        .into_iter()
        .flatten()
        {
            used.insert(info.texture().source().index());
        }
    }
    used
}

/// Every material of `doc` and the default one, `images` decoded by image index.
pub fn build(
    doc: &gltf::Document,
    images: &[Option<Arc<Image>>],
    shown: &str,
    warnings: &mut Vec<String>,
) -> Result<Materials, String> {
    let mut notes: Vec<&str> = Vec::new();
    let mut out = Vec::new();
    for m in doc.materials() {
        out.push(material(&m, images, &mut notes)?);
    }
    // The specification's default: white, metallic 1, roughness 1, one-sided.
    out.push((
        Material {
            kind: Glossy::MetallicRoughness(MetallicRoughness::new(1.0, 1.0, 1.5, 1.0, DVec3::ONE))
                .kind(),
            color: DVec3::ONE,
            emission: DVec3::ZERO,
            one_sided: true,
        },
        None,
    ));
    notes.sort_unstable();
    notes.dedup();
    if !notes.is_empty() {
        warnings.push(format!("{shown}: not used: {}", notes.join(", ")));
    }
    Ok(out)
}

/// One texture reference as a texture of `encoding`, `channel` and `factor`.
fn texture(
    info: &gltf::texture::Info,
    images: &[Option<Arc<Image>>],
    encoding: Encoding,
    channel: usize,
    factor: DVec3,
    notes: &mut Vec<&str>,
) -> Result<Texture, String> {
    let index = info.texture().source().index();
    let image = images
        .get(index)
        .cloned()
        .flatten()
        .ok_or_else(|| format!("image {index} was not read"))?;
    let mut t = Texture::new(Pattern::Image { image, encoding });
    t.channel = channel;
    t.factor = factor;
    let mut set = info.tex_coord();
    if let Some(tt) = info.texture_transform() {
        t.scale = tt.scale().map(f64::from);
        t.offset = tt.offset().map(f64::from);
        if tt.rotation() != 0.0 {
            notes.push("rotated KHR_texture_transform (read unrotated)");
        }
        set = tt.tex_coord().unwrap_or(set);
    }
    if set != 0 {
        notes.push("texture coordinate sets other than TEXCOORD_0 (read from TEXCOORD_0)");
    }
    let sampler = info.texture().sampler();
    let repeat = gltf::texture::WrappingMode::Repeat;
    if sampler.wrap_s() != repeat || sampler.wrap_t() != repeat {
        notes.push("clamped or mirrored samplers (read as repeat)");
    }
    Ok(t)
}

fn material(
    m: &gltf::Material,
    images: &[Option<Arc<Image>>],
    notes: &mut Vec<&str>,
) -> Result<(Material, Option<MaterialTextures>), String> {
    let name = m.index().map_or("the default material".to_string(), |i| {
        format!("material {i}")
    });
    let fail = |e: String| format!("{name}: {e}");
    let pbr = m.pbr_metallic_roughness();
    let f = pbr.base_color_factor();
    let base = DVec3::new(f[0] as f64, f[1] as f64, f[2] as f64).clamp(DVec3::ZERO, DVec3::ONE);
    let mut textures = MaterialTextures::default();
    if let Some(info) = pbr.base_color_texture() {
        textures.color =
            Some(texture(&info, images, Encoding::Srgb, 0, base, notes).map_err(fail)?);
    }
    let metallic = (pbr.metallic_factor() as f64).clamp(0.0, 1.0);
    let roughness = (pbr.roughness_factor() as f64).clamp(0.0, 1.0);
    if let Some(info) = pbr.metallic_roughness_texture() {
        let r = texture(
            &info,
            images,
            Encoding::Linear,
            1,
            DVec3::splat(roughness),
            notes,
        );
        let k = texture(
            &info,
            images,
            Encoding::Linear,
            2,
            DVec3::splat(metallic),
            notes,
        );
        textures.alpha = Some((r.map_err(fail)?, true));
        textures.metallic = Some(k.map_err(fail)?);
    }
    let strength = m.emissive_strength().unwrap_or(1.0) as f64;
    let e = m.emissive_factor();
    let emissive = DVec3::new(e[0] as f64, e[1] as f64, e[2] as f64).max(DVec3::ZERO) * strength;
    if let (Some(info), true) = (m.emissive_texture(), emissive.max_element() > 0.0) {
        let t = texture(&info, images, Encoding::Srgb, 0, emissive, notes).map_err(fail)?;
        textures.emission = Some(t);
    }
    if m.normal_texture().is_some() {
        notes.push("normal maps");
    }
    if m.occlusion_texture().is_some() {
        notes.push("occlusion maps");
    }
    if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
        notes.push("alpha blending and masking (read as opaque)");
    }
    let ior = m.ior().map_or(1.5, f64::from).clamp(1.0, 10.0);
    let mean_or = |t: &Option<Texture>, c: f64| t.as_ref().map_or(c, Texture::mean_value);
    let alpha = {
        let r = textures
            .alpha
            .as_ref()
            .map_or(roughness, |(t, _)| t.mean_value());
        r * r
    };
    let transmission = m
        .transmission()
        .map_or(0.0, |t| t.transmission_factor() as f64);
    let kind = if transmission > 0.0 {
        if transmission < 1.0 {
            notes.push("partial KHR_materials_transmission (read as glass)");
        }
        textures.metallic = None;
        if alpha < SPECULAR_ALPHA && textures.alpha.is_none() {
            MaterialKind::Glass { ior }
        } else {
            Glossy::RoughGlass(RoughDielectric {
                distribution: Distribution::isotropic(Microfacet::Ggx, alpha.max(SPECULAR_ALPHA)),
                ior,
            })
            .kind()
        }
    } else {
        let (factor, tint) = match m.specular() {
            Some(s) => {
                if s.specular_texture().is_some() || s.specular_color_texture().is_some() {
                    notes.push("KHR_materials_specular textures");
                }
                let c = s.specular_color_factor();
                (
                    s.specular_factor() as f64,
                    DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64).max(DVec3::ZERO),
                )
            }
            None => (1.0, DVec3::ONE),
        };
        Glossy::MetallicRoughness(MetallicRoughness::new(
            alpha,
            mean_or(&textures.metallic, metallic),
            ior,
            factor.clamp(0.0, 1.0),
            tint,
        ))
        .kind()
    };
    let color = textures.color.as_ref().map_or(base, Texture::mean_rgb);
    let emission = textures
        .emission
        .as_ref()
        .map_or(emissive, Texture::mean_rgb);
    let material = Material {
        kind,
        color,
        emission,
        one_sided: !m.double_sided(),
    };
    Ok((material, (!textures.is_empty()).then_some(textures)))
}
