//! A scene object's material keys turned into a [`Material`], each key checked against the
//! material it is given to, with the error at that key.
//!
//! | key | applies to | default |
//! |---|---|---|
//! | `material` | | `diffuse` |
//! | `color` | all (conductor: a factor on the reflectance) | 0.75; conductor 1; emitters 0 |
//! | `emission`, `two_sided` | all | 0; front face only |
//! | `ior` | glass, plastic | 1.5; plastic 1.49 |
//! | `alpha` or `alpha_u` + `alpha_v` | glass, conductor (`alpha` also plastic) | 0 (smooth); glass of `ior` 1 is smooth |
//! | `distribution` | glass, conductor, plastic | `ggx` |
//! | `metal`, or `eta` + `k` | conductor | Fresnel 1 |
//! | `specular` | plastic | 1 |

use super::description::{DistributionName, MaterialDesc, MaterialName, Textured, Unit};
use super::textures::{MaterialTextures, TextureLoader, Use};
use super::SceneError;
use crate::material::{
    metals, ConductorFresnel, Distribution, Glossy, Material, MaterialKind, Microfacet,
    RoughDielectric, SPECULAR_ALPHA,
};
use crate::math::DVec3;
use crate::texture::Texture;
use std::ops::Range;
use toml::Spanned;

/// Default reflectance of an object that states none (and is not a light).
pub const DEFAULT_COLOR: f64 = 0.75;
/// Default index of refraction of glass.
pub const DEFAULT_IOR: f64 = 1.5;
/// Default index of a plastic's coat: polypropylene, Mitsuba's default.
pub const DEFAULT_PLASTIC_IOR: f64 = 1.49;

/// Glass whose index is within this of 1 is built smooth whatever its `alpha`: an interface the
/// light barely sees (it turns rays by under 1e-6 radians and reflects under 1e-12 of them) has
/// no roughness to show, and rough refraction's Jacobian divides by about (ior - 1)^2, so at
/// index 1 every refracted sample had an infinite pdf and was dropped: the sphere rendered
/// black, not invisible. (Mitsuba refuses equal indices; smooth glass of index 1 is ptui's
/// `index-matched` extreme scene.)
pub const INDEX_MATCHED: f64 = 1e-6;

/// The material keys that apply to some materials only, with those materials (the loader
/// refuses them on any other; the TUI drops them when it steps an object to another material).
/// `material`, `color`, `emission` and `two_sided` apply to all.
pub const KEY_MATERIALS: &[(&str, &[MaterialName])] = {
    use MaterialName::*;
    &[
        ("ior", &[Glass, Plastic, MetallicRoughness]),
        ("alpha", &[Glass, Conductor, Plastic, MetallicRoughness]),
        ("alpha_u", &[Glass, Conductor]),
        ("alpha_v", &[Glass, Conductor]),
        ("distribution", &[Glass, Conductor, Plastic]),
        ("eta", &[Conductor]),
        ("k", &[Conductor]),
        ("metal", &[Conductor]),
        ("specular", &[Plastic, MetallicRoughness]),
        ("metallic", &[MetallicRoughness]),
    ]
};

/// The materials `key` applies to: those [`KEY_MATERIALS`] lists, or all.
fn materials_of(key: &str) -> &'static [MaterialName] {
    KEY_MATERIALS
        .iter()
        .find(|(k, _)| *k == key)
        .map_or(&MaterialName::ALL, |(_, kinds)| kinds)
}

/// Whether an object of material `kind` may set `key`.
pub fn applies(key: &str, kind: MaterialName) -> bool {
    materials_of(key).contains(&kind)
}

/// Where an object's material keys are read from, for errors.
struct At<'a> {
    src: &'a str,
    file: &'a str,
    object: &'a str,
}

impl At<'_> {
    fn err(&self, span: Range<usize>, key: &str, msg: impl Into<String>) -> SceneError {
        SceneError::at(
            self.file,
            self.src,
            Some(span),
            Some(format!("{}.{key}", self.object)),
            msg,
        )
    }

    /// `key` (if given) must be one [`applies`] to `kind`.
    fn only<T>(
        &self,
        value: &Option<Spanned<T>>,
        key: &str,
        kind: MaterialName,
    ) -> Result<(), SceneError> {
        let kinds = materials_of(key);
        match value {
            Some(v) if !kinds.contains(&kind) => {
                let names: Vec<String> = kinds
                    .iter()
                    .map(|k| format!("\"{}\"", k.as_str()))
                    .collect();
                Err(self.err(
                    v.span(),
                    key,
                    format!(
                        "`{key}` only applies to material = {} (this is \"{}\")",
                        names.join(" or "),
                        kind.as_str()
                    ),
                ))
            }
            _ => Ok(()),
        }
    }
}

/// The material of an object; `flat` for a triangle, quad or mesh (whose emission may be
/// one-sided), not a sphere. Textures are checked but not read (they read 0.5): for checks of
/// the keys alone; the scene build uses [`build_material_with`].
pub fn build_material(
    m: &MaterialDesc,
    src: &str,
    file: &str,
    object: &str,
    flat: bool,
) -> Result<Material, SceneError> {
    let mut loader = TextureLoader::checks_only();
    build_material_with(m, src, file, object, flat, &mut loader).map(|(m, _)| m)
}

/// [`build_material`] with its textures read by `loader`: the material (textured keys at
/// their texture's mean) and the textures, if any key has one.
pub fn build_material_with(
    m: &MaterialDesc,
    src: &str,
    file: &str,
    object: &str,
    flat: bool,
    loader: &mut TextureLoader,
) -> Result<(Material, Option<MaterialTextures>), SceneError> {
    use MaterialName::*;
    let at = At { src, file, object };
    let err = |span: Range<usize>, key: &str, msg: String| at.err(span, key, msg);
    let kind_name = m.material.unwrap_or_default();
    let mut textures = MaterialTextures::default();
    let (emission, tex) = match &m.emission {
        None => (DVec3::ZERO, None),
        Some(e) => {
            let err = |span, sub: &str, msg| err(span, &sub_key("emission", sub), msg);
            loader.value(e, Use::Emission, |v| DVec3::from_array(v.0), &err)?
        }
    };
    textures.emission = tex;
    // Emitters do not reflect unless the scene gives them a colour; a conductor's colour is a
    // factor on its Fresnel reflectance.
    let default_color = if emission.max_element() > 0.0 || textures.emission.is_some() {
        0.0
    } else if kind_name == Conductor {
        1.0
    } else {
        DEFAULT_COLOR
    };
    let (color, tex) = match &m.color {
        None => (DVec3::splat(default_color), None),
        Some(c) => {
            let err = |span, sub: &str, msg| err(span, &sub_key("color", sub), msg);
            loader.value(c, Use::Color, |v| DVec3::from_array(v.0), &err)?
        }
    };
    textures.color = tex;
    at.only(&m.ior, "ior", kind_name)?;
    at.only(&m.alpha, "alpha", kind_name)?;
    at.only(&m.alpha_u, "alpha_u", kind_name)?;
    at.only(&m.alpha_v, "alpha_v", kind_name)?;
    at.only(&m.distribution, "distribution", kind_name)?;
    at.only(&m.eta, "eta", kind_name)?;
    at.only(&m.k, "k", kind_name)?;
    at.only(&m.metal, "metal", kind_name)?;
    at.only(&m.specular, "specular", kind_name)?;
    at.only(&m.metallic, "metallic", kind_name)?;
    if let Some(a) = &m.alpha {
        if let Textured::Texture(desc) = a.get_ref() {
            if kind_name == Plastic {
                return Err(at.err(
                    a.span(),
                    "alpha",
                    "a plastic's `alpha` cannot be a texture: its coat's tables are computed for one alpha when the scene is built",
                ));
            }
            let err = |span, sub: &str, msg| err(span, &sub_key("alpha", sub), msg);
            let t = loader.texture(desc, Use::Value, a.span(), &err)?;
            textures.alpha = Some((t, false));
        }
    }
    let distribution = roughness(m, &at, textures.alpha.as_ref().map(|(t, _)| t))?;
    let ior = |default: f64| m.ior.as_ref().map_or(default, |i| i.get_ref().0);
    let kind = match kind_name {
        Diffuse => MaterialKind::Diffuse,
        Mirror => MaterialKind::Mirror,
        Glass => match distribution {
            Some(distribution) if (ior(DEFAULT_IOR) - 1.0).abs() > INDEX_MATCHED => {
                Glossy::RoughGlass(RoughDielectric {
                    distribution,
                    ior: ior(DEFAULT_IOR),
                })
                .kind()
            }
            _ => MaterialKind::Glass {
                ior: ior(DEFAULT_IOR),
            },
        },
        Conductor => {
            let fresnel = conductor_fresnel(m, &at)?;
            match distribution {
                None => MaterialKind::SmoothConductor(Box::new(fresnel)),
                Some(distribution) => Glossy::Conductor(crate::material::Conductor {
                    distribution,
                    fresnel,
                })
                .kind(),
            }
        }
        Plastic => {
            let specular = m
                .specular
                .as_ref()
                .map_or(DVec3::ONE, |s| DVec3::from_array(s.get_ref().0));
            let mean = color.element_sum() / 3.0;
            Glossy::Plastic(crate::material::Plastic::new(
                ior(DEFAULT_PLASTIC_IOR),
                specular,
                mean,
                distribution,
            ))
            .kind()
        }
        MetallicRoughness => {
            let (metallic, tex) = match &m.metallic {
                None => (DVec3::ZERO, None),
                Some(x) => {
                    let err = |span, sub: &str, msg| err(span, &sub_key("metallic", sub), msg);
                    loader.value(x, Use::Value, |v: Unit| DVec3::splat(v.0), &err)?
                }
            };
            textures.metallic = tex;
            // KHR_materials_specular's colour and factor, from `specular` as [r, g, b]: the
            // factor its largest component, the colour the rest.
            let specular = m
                .specular
                .as_ref()
                .map_or(DVec3::ONE, |s| DVec3::from_array(s.get_ref().0));
            let factor = specular.max_element();
            let tint = if factor > 0.0 {
                specular / factor
            } else {
                DVec3::ONE
            };
            let alpha = distribution.map_or(0.0, |d| d.alpha_u);
            Glossy::MetallicRoughness(crate::material::MetallicRoughness::new(
                alpha,
                metallic.x,
                ior(DEFAULT_IOR),
                factor,
                tint,
            ))
            .kind()
        }
    };
    if let Some(two_sided) = &m.two_sided {
        let problem = if !flat {
            Some("`two_sided` applies to triangles, quads and meshes: a sphere emits outwards")
        } else if emission.max_element() <= 0.0 {
            Some("`two_sided` only applies to emitters (objects with an `emission`)")
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(at.err(two_sided.span(), "two_sided", problem));
        }
    }
    // Flat emitters emit from their front face alone unless asked, as in pbrt and Mitsuba.
    let one_sided = flat && !m.two_sided.as_ref().is_some_and(|t| *t.get_ref());
    let material = Material {
        kind,
        color,
        emission,
        one_sided,
    };
    Ok((material, (!textures.is_empty()).then_some(textures)))
}

/// `key.sub` (or `key` for the table itself), for errors inside a texture table.
fn sub_key(key: &str, sub: &str) -> String {
    if sub.is_empty() {
        key.to_string()
    } else {
        format!("{key}.{sub}")
    }
}

/// The microfacet distribution the keys ask for, or None for a smooth surface: `alpha`, or
/// `alpha_u` with `alpha_v`, below [`SPECULAR_ALPHA`] in both directions is smooth; above it a
/// direction's roughness is at least that (as Mitsuba clamps).
fn roughness(
    m: &MaterialDesc,
    at: &At,
    texture: Option<&Texture>,
) -> Result<Option<Distribution>, SceneError> {
    let (alpha_u, alpha_v) = match (&m.alpha, &m.alpha_u, &m.alpha_v) {
        // A textured alpha builds the material at its mean; every hit sets its own.
        (Some(a), None, None) => {
            let a = match (a.get_ref(), texture) {
                (Textured::Value(v), _) => v.0,
                (Textured::Texture(_), Some(t)) => {
                    t.mean_value().clamp(0.0, 1.0).max(SPECULAR_ALPHA)
                }
                (Textured::Texture(_), None) => SPECULAR_ALPHA,
            };
            (a, a)
        }
        (None, Some(u), Some(v)) => (u.get_ref().0, v.get_ref().0),
        (None, None, None) => (0.0, 0.0),
        (Some(_), Some(x), _) | (Some(_), None, Some(x)) => {
            return Err(at.err(
                x.span(),
                if m.alpha_u.is_some() {
                    "alpha_u"
                } else {
                    "alpha_v"
                },
                "give either `alpha` (isotropic) or `alpha_u` and `alpha_v`, not both",
            ))
        }
        (None, Some(x), None) | (None, None, Some(x)) => {
            let (given, missing) = if m.alpha_u.is_some() {
                ("alpha_u", "alpha_v")
            } else {
                ("alpha_v", "alpha_u")
            };
            return Err(at.err(
                x.span(),
                given,
                format!("`{given}` needs `{missing}` too (or use `alpha`)"),
            ));
        }
    };
    if alpha_u.max(alpha_v) < SPECULAR_ALPHA {
        return Ok(None);
    }
    let kind = match m.distribution.as_ref().map(|d| *d.get_ref()) {
        None | Some(DistributionName::Ggx) => Microfacet::Ggx,
        Some(DistributionName::Beckmann) => Microfacet::Beckmann,
    };
    Ok(Some(Distribution::new(
        kind,
        alpha_u.max(SPECULAR_ALPHA),
        alpha_v.max(SPECULAR_ALPHA),
    )))
}

/// A conductor's Fresnel term: a named metal, an explicit complex index, or none (1).
fn conductor_fresnel(m: &MaterialDesc, at: &At) -> Result<ConductorFresnel, SceneError> {
    match (&m.metal, &m.eta, &m.k) {
        (Some(name), None, None) => match metals::lookup(name.get_ref()) {
            Some((eta, k)) => Ok(ConductorFresnel::Complex { eta, k }),
            None => Err(at.err(
                name.span(),
                "metal",
                format!(
                    "unknown metal `{}`; known: {}",
                    name.get_ref(),
                    metals::names().collect::<Vec<_>>().join(", ")
                ),
            )),
        },
        (Some(_), Some(x), _) | (Some(_), None, Some(x)) => Err(at.err(
            x.span(),
            if m.eta.is_some() { "eta" } else { "k" },
            "give either `metal` or `eta` and `k`, not both",
        )),
        (None, Some(eta), Some(k)) => Ok(ConductorFresnel::Complex {
            eta: DVec3::from_array(eta.get_ref().0),
            k: DVec3::from_array(k.get_ref().0),
        }),
        (None, Some(x), None) | (None, None, Some(x)) => {
            let (given, missing) = if m.eta.is_some() {
                ("eta", "k (the absorption; 0 for none)")
            } else {
                ("k", "eta (the real part of the index)")
            };
            Err(at.err(x.span(), given, format!("`{given}` needs `{missing}` too")))
        }
        (None, None, None) => Ok(ConductorFresnel::None),
    }
}

/// The materials a scene's objects use, in order of first use, with how many objects use each:
/// what the summaries list.
pub fn describe(materials: &[Material]) -> String {
    let mut seen: Vec<(String, usize)> = Vec::new();
    for m in materials {
        // A light that does not reflect is listed as what it is.
        let d = if m.is_emissive() && m.color == DVec3::ZERO {
            "emitter".to_string()
        } else {
            m.kind.describe()
        };
        match seen.iter_mut().find(|(s, _)| *s == d) {
            Some((_, n)) => *n += 1,
            None => seen.push((d, 1)),
        }
    }
    seen.iter()
        .map(|(d, n)| {
            if *n == 1 {
                d.clone()
            } else {
                format!("{d} x{n}")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}
