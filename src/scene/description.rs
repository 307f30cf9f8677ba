//! The scene file format: serde structs with defaults, unknown keys rejected, and values checked
//! as they are read so each error carries the span (hence line) of the offending value.
//!
//! ```toml
//! background = [0, 0, 0]  # a constant sky; or the [environment] table
//! accel = "auto"           # auto | flat | bvh; top-level keys come before any [table]
//! [camera]                 # see `camera`
//! [render]                 # see `settings`
//!
//! [environment]            # see `light::environment`
//! map = "sky.exr"          # or color = [r, g, b]
//! intensity = 1
//! rotate = [0, 90, 0]
//!
//! [[sphere]]
//! name = "left"            # optional, unique
//! center = [100001, 40.8, 81.6]
//! radius = 1e5
//! color = [0.75, 0.25, 0.25]
//!
//! [[triangle]]
//! vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]   # front: counter-clockwise
//! emission = 5             # emits from the front face only...
//! two_sided = true         # ...unless both faces emit
//!
//! [[quad]]                 # parallelogram, two triangles
//! corner = [213, 548.7, 227]
//! edge1 = [130, 0, 0]
//! edge2 = [0, 0, 105]
//!
//! [[mesh]]
//! path = "meshes/bunny.obj"   # or torus_knot = { p = 2, q = 3, segments = 1024, sides = 64, tube = 0.45 }
//! scale = 10
//! rotate = [-90, 0, 0]        # degrees about x, then y, then z
//! translate = [0, 4, 0]
//! ```

pub use crate::checked::{
    Albedo, Dir, Fov, Ior, NonNegative, Positive, Rgb, Roughness, IOR_RANGE, MAX_MAGNITUDE,
    MIN_MAGNITUDE, V3,
};
use crate::settings::SettingsOverrides;
use serde::de::{self, Deserializer, IntoDeserializer, Visitor};
use serde::Deserialize;
use std::marker::PhantomData;
use toml::Spanned;

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    #[serde(default)]
    pub camera: CameraDesc,
    #[serde(default)]
    pub render: SettingsOverrides,
    pub background: Option<Rgb>,
    /// Light from all directions at infinity: a map or a constant colour (see
    /// `light::environment`).
    pub environment: Option<Spanned<EnvironmentDesc>>,
    #[serde(default)]
    pub sphere: Vec<SphereDesc>,
    /// What `ptui check` expects of this scene (`scene::check`); a scene only holds it.
    pub check: Option<super::check::CheckDesc>,
    /// Accelerator: auto (default), flat or bvh (see `accel`).
    pub accel: Option<crate::accel::AccelChoice>,
    #[serde(default)]
    pub triangle: Vec<TriangleDesc>,
    #[serde(default)]
    pub quad: Vec<QuadDesc>,
    #[serde(default)]
    pub mesh: Vec<MeshDesc>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub position: Option<V3>,
    pub direction: Option<Spanned<Dir>>,
    pub look_at: Option<Spanned<V3>>,
    pub up: Option<Spanned<Dir>>,
    pub vfov: Option<Fov>,
    pub near: Option<NonNegative>,
    /// Lens radius (0, the default: a pinhole); see `camera`.
    pub aperture: Option<NonNegative>,
    pub focus_distance: Option<Spanned<Positive>>,
    pub focus_on: Option<Spanned<V3>>,
}

/// `[environment]`: `map` (an equirectangular EXR/HDR file relative to the scene file, or
/// `"builtin:sky"`) or `color` (a constant sky), scaled by `intensity` and, for a map, turned by
/// `rotate` (degrees about x, then y, then z).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDesc {
    pub map: Option<Spanned<String>>,
    pub color: Option<Spanned<Rgb>>,
    pub intensity: Option<NonNegative>,
    pub rotate: Option<V3>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaterialName {
    #[default]
    Diffuse,
    Mirror,
    Glass,
    /// A microfacet metal (`material::conductor`).
    Conductor,
    /// A diffuse base under a dielectric coat (`material::plastic`).
    Plastic,
    /// glTF's material (`material::metallic_roughness`).
    MetallicRoughness,
}

impl MaterialName {
    pub const ALL: [MaterialName; 6] = [
        MaterialName::Diffuse,
        MaterialName::Mirror,
        MaterialName::Glass,
        MaterialName::Conductor,
        MaterialName::Plastic,
        MaterialName::MetallicRoughness,
    ];

    /// The material a scene file names `name`.
    pub fn from_name(name: &str) -> Option<MaterialName> {
        MaterialName::ALL.into_iter().find(|m| m.as_str() == name)
    }

    pub const fn as_str(self) -> &'static str {
        match self {
            MaterialName::Diffuse => "diffuse",
            MaterialName::Mirror => "mirror",
            MaterialName::Glass => "glass",
            MaterialName::Conductor => "conductor",
            MaterialName::Plastic => "plastic",
            MaterialName::MetallicRoughness => "metallic-roughness",
        }
    }
}

/// `distribution`: the microfacet normal distribution of the rough materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DistributionName {
    Ggx,
    Beckmann,
}

/// The material fields every object carries (flattening is not possible with unknown-key
/// rejection in serde, so [`object_desc`] adds them to each object type).
#[derive(Debug, Default, Clone)]
pub struct MaterialDesc {
    pub material: Option<MaterialName>,
    pub color: Option<Spanned<Textured<Albedo>>>,
    pub emission: Option<Spanned<Textured<Rgb>>>,
    pub ior: Option<Spanned<Ior>>,
    pub two_sided: Option<Spanned<bool>>,
    pub alpha: Option<Spanned<Textured<Roughness>>>,
    pub alpha_u: Option<Spanned<Roughness>>,
    pub alpha_v: Option<Spanned<Roughness>>,
    pub distribution: Option<Spanned<DistributionName>>,
    pub eta: Option<Spanned<Rgb>>,
    pub k: Option<Spanned<Rgb>>,
    pub metal: Option<Spanned<String>>,
    pub specular: Option<Spanned<Albedo>>,
    pub metallic: Option<Spanned<Textured<Unit>>>,
}

/// Declares an object table: its own fields, then the material keys every object carries
/// (`material`, `color`, `emission`, `ior`, `two_sided`, `alpha`, `alpha_u`, `alpha_v`,
/// `distribution`, `eta`, `k`, `metal`, `specular`, `metallic`; see `material`), and `material()`, which
/// gathers the latter into a [`MaterialDesc`].
macro_rules! object_desc {
    ($(#[$meta:meta])* pub struct $name:ident { $($(#[$fmeta:meta])* pub $field:ident: $ty:ty,)* }) => {
        $(#[$meta])*
        #[derive(Debug, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $($(#[$fmeta])* pub $field: $ty,)*
            pub material: Option<MaterialName>,
            pub color: Option<Spanned<Textured<Albedo>>>,
            pub emission: Option<Spanned<Textured<Rgb>>>,
            pub ior: Option<Spanned<Ior>>,
            /// Emitters only: whether both faces emit (default: the front face alone).
            pub two_sided: Option<Spanned<bool>>,
            pub alpha: Option<Spanned<Textured<Roughness>>>,
            pub alpha_u: Option<Spanned<Roughness>>,
            pub alpha_v: Option<Spanned<Roughness>>,
            pub distribution: Option<Spanned<DistributionName>>,
            pub eta: Option<Spanned<Rgb>>,
            pub k: Option<Spanned<Rgb>>,
            pub metal: Option<Spanned<String>>,
            pub specular: Option<Spanned<Albedo>>,
            pub metallic: Option<Spanned<Textured<Unit>>>,
        }

        impl $name {
            pub fn material(&self) -> MaterialDesc {
                MaterialDesc {
                    material: self.material,
                    color: self.color.clone(),
                    emission: self.emission.clone(),
                    ior: self.ior.clone(),
                    two_sided: self.two_sided.clone(),
                    alpha: self.alpha.clone(),
                    alpha_u: self.alpha_u.clone(),
                    alpha_v: self.alpha_v.clone(),
                    distribution: self.distribution.clone(),
                    eta: self.eta.clone(),
                    k: self.k.clone(),
                    metal: self.metal.clone(),
                    specular: self.specular.clone(),
                    metallic: self.metallic.clone(),
                }
            }
        }
    };
}

object_desc! {
    pub struct SphereDesc {
        pub name: Option<Spanned<String>>,
        pub center: V3,
        pub radius: Positive,
    }
}

object_desc! {
    /// `[[triangle]]`: one triangle; the front side sees the vertices counter-clockwise.
    pub struct TriangleDesc {
        pub name: Option<Spanned<String>>,
        pub vertices: Spanned<[V3; 3]>,
    }
}

object_desc! {
    /// `[[quad]]`: the parallelogram corner, corner + edge1, corner + edge1 + edge2, corner +
    /// edge2 (two triangles; the front side is the one edge1 x edge2 points to).
    pub struct QuadDesc {
        pub name: Option<Spanned<String>>,
        pub corner: V3,
        pub edge1: V3,
        pub edge2: Spanned<V3>,
    }
}

object_desc! {
    /// `[[mesh]]`: triangles from a Wavefront OBJ file (`path`, relative to the scene file) or
    /// from a built-in generator (`torus_knot`), placed by scale, then rotation (degrees about
    /// x, then y, then z), then translation.
    pub struct MeshDesc {
        pub name: Option<Spanned<String>>,
        pub path: Option<Spanned<String>>,
        pub torus_knot: Option<Spanned<TorusKnotDesc>>,
        /// Interpolate vertex normals (default: where the file has them; the torus knot's exact
        /// ones); false shades every triangle flat.
        pub smooth: Option<bool>,
        /// Use the OBJ's material libraries (default true; see `scene::mtl`).
        pub mtl: Option<bool>,
        pub translate: Option<V3>,
        pub scale: Option<Positive>,
        pub rotate: Option<V3>,
    }
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TorusKnotDesc {
    pub p: u32,
    pub q: u32,
    pub segments: u32,
    pub sides: u32,
    pub tube: Positive,
}

/// A material key's value: a constant (`T`, as the key reads it) or a texture table.
#[derive(Clone, Debug, PartialEq)]
pub enum Textured<T> {
    Value(T),
    Texture(Box<TextureDesc>),
}

impl<T> Textured<T> {
    /// The constant, if the key is one.
    pub fn value(&self) -> Option<&T> {
        match self {
            Textured::Value(v) => Some(v),
            Textured::Texture(_) => None,
        }
    }
}

/// `{ texture = "file.png" }` or `{ checker = [c0, c1] }`, with `scale` and `offset` for the
/// texture coordinates, a `factor` on the value and, for single values (`alpha`), the
/// `channel` read (see `texture`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureDesc {
    pub texture: Option<Spanned<String>>,
    pub checker: Option<Spanned<[Rgb; 2]>>,
    pub scale: Option<Spanned<UvPair>>,
    pub offset: Option<UvPair>,
    pub factor: Option<Spanned<Rgb>>,
    pub channel: Option<Spanned<Channel>>,
}

/// A fraction: a number in [0, 1] (`metallic`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit(pub f64);

impl<'de> Deserialize<'de> for Unit {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = f64::deserialize(d)?;
        if (0.0..=1.0).contains(&v) {
            Ok(Unit(v))
        } else {
            Err(de::Error::custom(format!(
                "must be between 0 and 1, got {v}"
            )))
        }
    }
}

/// A channel of an image, for a single value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Channel {
    R,
    G,
    B,
    A,
}

impl Channel {
    pub fn index(self) -> usize {
        self as usize
    }
}

/// A number for both texture coordinates or [u, v]: finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvPair(pub [f64; 2]);

impl<'de> Deserialize<'de> for UvPair {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            One(f64),
            Two([f64; 2]),
        }
        let v = match Raw::deserialize(d)
            .map_err(|_| de::Error::custom("expected a number or an array of 2 numbers"))?
        {
            Raw::One(x) => [x, x],
            Raw::Two(v) => v,
        };
        if v.iter().all(|x| x.is_finite() && x.abs() <= MAX_MAGNITUDE) {
            Ok(UvPair(v))
        } else {
            Err(de::Error::custom(format!(
                "must be finite numbers of magnitude at most {MAX_MAGNITUDE:e}, got {v:?}"
            )))
        }
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Textured<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = Textured<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, an array of 3 numbers or a texture table")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(Textured::Value)
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(Textured::Value)
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                T::deserialize(v.into_deserializer()).map(Textured::Value)
            }
            fn visit_seq<A: de::SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
                T::deserialize(de::value::SeqAccessDeserializer::new(seq)).map(Textured::Value)
            }
            fn visit_map<A: de::MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
                TextureDesc::deserialize(de::value::MapAccessDeserializer::new(map))
                    .map(|t| Textured::Texture(Box::new(t)))
            }
        }
        d.deserialize_any(V(PhantomData))
    }
}
