//! The textures of a scene: which material keys are textured, the texture coordinates of every
//! primitive, and the material a textured surface has at one hit.
//!
//! A scene without textures has none of this ([`Scene::textures`] is `None`): its hits look
//! nothing up, and the integrators pay one test of that pointer per vertex.
//!
//! Texture coordinates: triangles of a mesh carry their corners' (OBJ `vt`, turned to run
//! downwards; glTF `TEXCOORD_0` as it is), a triangle without them the barycentrics (b1, b2)
//! as Mitsuba gives; a quad (corner, edge1, edge2) runs u along edge1 and v from 1 at the
//! corner to 0 at corner + edge2, so an image reads upright with edge2 pointing up; a sphere's
//! are Mitsuba's with its pole along +y: u = phi / 2 pi with phi = atan2(-z, x) from the
//! centre, v = theta / pi from the top (+y) down.

use super::description::{TextureDesc, Textured};
use super::{Scene, SceneError};
use crate::geometry::{Hit, Shape};
use crate::material::Material;
use crate::math::DVec3;
use crate::progress::Progress;
use crate::texture::{load::Cache, Encoding, Pattern, Texture, Uv};
use std::f64::consts::{FRAC_1_PI, PI};
use std::ops::Range;
use std::path::PathBuf;

/// The textured keys of one material.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MaterialTextures {
    pub color: Option<Texture>,
    pub emission: Option<Texture>,
    /// The microfacet alpha; `true`: the texture holds glTF's roughness, alpha its square.
    pub alpha: Option<(Texture, bool)>,
    /// The metallic-roughness material's metalness.
    pub metallic: Option<Texture>,
}

impl MaterialTextures {
    pub fn is_empty(&self) -> bool {
        *self == MaterialTextures::default()
    }

    /// `base` with its textured keys looked up at `uv`.
    pub fn apply(&self, base: &Material, uv: Uv) -> Material {
        let mut m = base.clone();
        if let Some(t) = &self.color {
            m.color = t.rgb(uv);
        }
        if let Some(t) = &self.emission {
            m.emission = t.rgb(uv);
        }
        if self.alpha.is_some() || self.metallic.is_some() {
            let alpha = self.alpha.as_ref().map(|(t, squared)| {
                let a = t.value(uv).clamp(0.0, 1.0);
                if *squared {
                    a * a
                } else {
                    a
                }
            });
            let metallic = self.metallic.as_ref().map(|t| t.value(uv).clamp(0.0, 1.0));
            m.kind.set_parameters(alpha, metallic);
        }
        m
    }
}

/// A scene's textures: per material its textured keys, per primitive its texture coordinates.
#[derive(Clone, Debug, Default)]
pub struct SceneTextures {
    /// Indexed by material; `None` for an untextured one.
    pub materials: Vec<Option<Box<MaterialTextures>>>,
    /// Indexed by primitive: its corners' (u, v); empty entries (all zero) for spheres, and
    /// where a triangle has no coordinates of its own, its barycentrics are used.
    pub uvs: Vec<Option<[[f32; 2]; 3]>>,
    /// How many images and the bytes their texels hold, for the summary.
    pub images: usize,
    pub bytes: u64,
}

impl SceneTextures {
    /// The texture coordinates of `hit` on primitive `shape`.
    #[inline]
    pub fn uv(&self, shape: &Shape, hit: &Hit) -> Uv {
        let (b1, b2) = (hit.uv[0] as f64, hit.uv[1] as f64);
        match shape {
            Shape::Sphere(s) => sphere_uv((hit.p - s.center) / s.radius),
            Shape::Triangle(_) => {
                triangle_uv(self.uvs.get(hit.prim as usize).copied().flatten(), b1, b2)
            }
        }
    }

    /// The material at `hit`, if its material is textured.
    #[inline(never)]
    pub fn material_at(&self, scene: &Scene, hit: &Hit) -> Option<Material> {
        let prim = &scene.prims[hit.prim as usize];
        let tex = self.materials.get(prim.material as usize)?.as_ref()?;
        let base = &scene.materials[prim.material as usize];
        Some(tex.apply(base, self.uv(&prim.shape, hit)))
    }

    /// The radiance emitted at point `x` of primitive `prim`, if its emission is textured.
    #[inline(never)]
    pub fn emission_at(&self, scene: &Scene, prim: u32, x: DVec3) -> Option<DVec3> {
        let p = &scene.prims[prim as usize];
        let tex = self.materials.get(p.material as usize)?.as_ref()?;
        let emission = tex.emission.as_ref()?;
        let (b1, b2) = match &p.shape {
            Shape::Triangle(t) => t.barycentrics(x),
            Shape::Sphere(_) => (0.0, 0.0),
        };
        let hit = Hit {
            t: 0.0,
            p: x,
            n: DVec3::Z,
            prim,
            err: 0.0,
            ns: DVec3::Z,
            uv: [b1 as f32, b2 as f32],
            smooth: false,
        };
        Some(emission.rgb(self.uv(&p.shape, &hit)))
    }

    /// The summary's line: how many images and their memory.
    pub fn describe(&self) -> String {
        let textured = self.materials.iter().filter(|m| m.is_some()).count();
        format!(
            "{textured} textured material(s), {} image(s), {:.1} MiB of texels",
            self.images,
            self.bytes as f64 / (1 << 20) as f64
        )
    }
}

/// The texture coordinates at barycentrics (b1, b2) of a triangle with coordinates `c` at its
/// corners; without them, the barycentrics themselves.
#[inline]
fn triangle_uv(c: Option<[[f32; 2]; 3]>, b1: f64, b2: f64) -> Uv {
    let Some(c) = c else {
        return [b1, b2];
    };
    let b0 = 1.0 - b1 - b2;
    let at = |k: usize| c[0][k] as f64 * b0 + c[1][k] as f64 * b1 + c[2][k] as f64 * b2;
    [at(0), at(1)]
}

/// The mean of a textured emission over a triangle with corner coordinates `uv` (None: the
/// barycentrics), from a 4 x 4 stratified grid of points: the light's power for choosing among
/// lights. A triangle whose points all read black is not sampled as a light; its emission is
/// still found by the paths that hit it, counted in full (nothing else could have found it).
pub fn mean_over_triangle(t: &Texture, uv: Option<[[f32; 2]; 3]>) -> DVec3 {
    const N: usize = 4;
    let mut sum = DVec3::ZERO;
    for i in 0..N {
        for j in 0..N {
            let u = ((i as f64 + 0.5) / N as f64, (j as f64 + 0.5) / N as f64);
            let (b1, b2) = crate::sampling::warp::uniform_triangle(u);
            sum += t.rgb(triangle_uv(uv, b1, b2));
        }
    }
    sum / (N * N) as f64
}

/// A sphere's (u, v) at unit offset `d` from its centre (see the module docs).
#[inline]
pub fn sphere_uv(d: DVec3) -> Uv {
    let mut phi = (-d.z).atan2(d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let theta = d.y.clamp(-1.0, 1.0).acos();
    [phi * 0.5 * FRAC_1_PI, theta * FRAC_1_PI]
}

/// What a textured key holds, which decides the image's encoding and the checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Use {
    /// A reflectance: sRGB-encoded, at most 1.
    Color,
    /// A radiance: sRGB-encoded for 8-bit images, EXR/HDR as they are.
    Emission,
    /// A single value (roughness): linear, one channel.
    Value,
}

/// Loads the images a scene's textures name, relative to `base_dir`, each once.
pub struct TextureLoader<'a> {
    pub base_dir: Option<PathBuf>,
    pub cache: Cache,
    pub progress: Option<&'a Progress>,
    /// False to check the keys without reading any image (the textures then read 0.5).
    pub load: bool,
}

impl TextureLoader<'_> {
    /// A loader that reads nothing.
    pub fn checks_only() -> TextureLoader<'static> {
        TextureLoader {
            base_dir: None,
            cache: Cache::default(),
            progress: None,
            load: false,
        }
    }

    /// The texture a table describes. `at` builds an error at a span for a key below `key`.
    pub fn texture(
        &mut self,
        desc: &TextureDesc,
        usage: Use,
        span: Range<usize>,
        err: &dyn Fn(Range<usize>, &str, String) -> SceneError,
    ) -> Result<Texture, SceneError> {
        let pattern = match (&desc.texture, &desc.checker) {
            (Some(path), None) => {
                if !self.load {
                    Pattern::Checker {
                        colors: [DVec3::splat(0.5); 2],
                    }
                } else {
                    let full = match &self.base_dir {
                        Some(b) => b.join(path.get_ref()),
                        None => PathBuf::from(path.get_ref()),
                    };
                    let image = self
                        .cache
                        .get(&full, self.progress)
                        .map_err(|e| err(path.span(), "texture", e))?;
                    let encoding = match usage {
                        Use::Value => Encoding::Linear,
                        Use::Color | Use::Emission => Encoding::Srgb,
                    };
                    Pattern::Image { image, encoding }
                }
            }
            (None, Some(c)) => Pattern::Checker {
                colors: c.get_ref().map(|c| DVec3::from_array(c.0)),
            },
            (Some(_), Some(c)) => {
                return Err(err(
                    c.span(),
                    "checker",
                    "give either `texture` or `checker`, not both".into(),
                ))
            }
            (None, None) => {
                return Err(err(
                    span,
                    "",
                    "a texture table needs `texture = \"file\"` or `checker = [c0, c1]`".into(),
                ))
            }
        };
        let mut t = Texture::new(pattern);
        if let Some(s) = &desc.scale {
            t.scale = s.get_ref().0;
        }
        if let Some(o) = &desc.offset {
            t.offset = o.0;
        }
        if let Some(f) = &desc.factor {
            t.factor = DVec3::from_array(f.get_ref().0);
        }
        match (&desc.channel, usage) {
            (Some(c), Use::Value) => t.channel = c.get_ref().index(),
            (Some(c), _) => {
                return Err(err(
                    c.span(),
                    "channel",
                    "`channel` applies to single values (`alpha`), not to colours".into(),
                ))
            }
            (None, _) => {}
        }
        if usage == Use::Color {
            let max = t.max_rgb();
            if max.max_element() > 1.0 {
                return Err(err(
                    span,
                    "",
                    format!(
                        "a reflectance texture must stay within [0, 1] (more creates energy); \
                         this one reaches {:.3}",
                        max.max_element()
                    ),
                ));
            }
        }
        Ok(t)
    }

    /// A key's constant value (as a colour) or its texture with the constant the material is
    /// built with (the texture's mean).
    pub fn value<T: Copy>(
        &mut self,
        key: &toml::Spanned<Textured<T>>,
        usage: Use,
        constant: impl Fn(T) -> DVec3,
        err: &dyn Fn(Range<usize>, &str, String) -> SceneError,
    ) -> Result<(DVec3, Option<Texture>), SceneError> {
        match key.get_ref() {
            Textured::Value(v) => Ok((constant(*v), None)),
            Textured::Texture(desc) => {
                let t = self.texture(desc, usage, key.span(), err)?;
                let mean = match usage {
                    Use::Value => DVec3::splat(t.mean_value()),
                    Use::Color | Use::Emission => t.mean_rgb(),
                };
                Ok((mean, Some(t)))
            }
        }
    }
}

impl Scene {
    /// The material at `hit`: the scene's own, or with its textures looked up into `slot`. The
    /// one place the integrators ask; a scene without textures pays one test here.
    #[inline(always)]
    pub fn material_at<'a>(&'a self, hit: &Hit, slot: &'a mut Option<Material>) -> &'a Material {
        match &self.textures {
            None => self.material(hit),
            Some(t) => match t.material_at(self, hit) {
                Some(m) => slot.insert(m),
                None => self.material(hit),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_coordinates_run_from_the_top_pole() {
        assert_eq!(sphere_uv(DVec3::Y)[1], 0.0);
        assert_eq!(sphere_uv(-DVec3::Y)[1], 1.0);
        assert_eq!(sphere_uv(DVec3::X), [0.0, 0.5]);
        // A quarter turn from +x towards -z.
        let uv = sphere_uv(-DVec3::Z);
        assert!((uv[0] - 0.25).abs() < 1e-15 && (uv[1] - 0.5).abs() < 1e-15);
        let uv = sphere_uv(DVec3::Z);
        assert!((uv[0] - 0.75).abs() < 1e-15);
    }
}
