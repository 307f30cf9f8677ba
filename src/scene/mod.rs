//! The validated, immutable scene: primitives, materials, lights, camera, and the machinery
//! (accelerator, light sampling) chosen for this scene.

pub mod builtin;
mod camera;
pub mod check;
pub mod description;
pub mod edit;
pub mod error;
pub mod gltf;
pub mod gltf_material;
pub mod gltf_outline;
pub mod load;
mod load_mesh;
pub mod materials;
pub mod mesh;
pub mod model;
pub mod mtl;
pub mod obj;
pub mod reload;
mod sky;
pub mod textures;

use crate::accel::lanes::RayBatch;
use crate::accel::Accel;
use crate::camera::Camera;
use crate::geometry::{Aabb, Hit, Primitive};
use crate::light::environment::Environment;
use crate::light::Lights;
use crate::material::Material;
use crate::math::{DVec3, Ray};
use crate::settings::SettingsOverrides;
use std::sync::Arc;
use std::time::Duration;

pub use camera::DEFAULT_VFOV;
pub use error::SceneError;
pub use load::{load, load_str, load_str_with, load_text, load_with, BuildOptions};
pub use sky::BUILTIN_SKY;

/// Most triangles all meshes of one scene may hold together, whatever the memory: the BVH
/// indexes nodes and primitives with u32, and a tree has fewer than two nodes per primitive.
pub const MAX_MESH_TRIANGLES: u64 = (u32::MAX / 2) as u64;

/// Peak memory of a scene build per mesh triangle: the triangle primitive, its shading normals,
/// the mesh it was read into, the BVH (~180-220 bytes a triangle) and the build's own working
/// copy. Measured peak RSS over triangles was ~440 bytes (benches/HISTORY.md, "Meshes at
/// scale"); this leaves a margin.
pub const BUILD_BYTES_PER_TRIANGLE: u64 = 512;

/// How many more mesh triangles a scene that holds `so_far` may take: the index bound, and
/// what the available memory holds at [`BUILD_BYTES_PER_TRIANGLE`] (where the system says).
/// The text says which bound it is, with the numbers, for the error.
pub fn mesh_triangle_room(so_far: u64) -> (u64, String) {
    let by_index = MAX_MESH_TRIANGLES.saturating_sub(so_far);
    match crate::memory::available() {
        Some(avail) if avail / BUILD_BYTES_PER_TRIANGLE < MAX_MESH_TRIANGLES => (
            (avail / BUILD_BYTES_PER_TRIANGLE).saturating_sub(so_far),
            format!(
                "at about {BUILD_BYTES_PER_TRIANGLE} bytes a triangle for the triangles and their \
                 BVH, the {} of memory available hold {} mesh triangles per scene",
                crate::memory::human_bytes(avail),
                avail / BUILD_BYTES_PER_TRIANGLE
            ),
        ),
        _ => (
            by_index,
            format!("at most {MAX_MESH_TRIANGLES} mesh triangles per scene (the BVH's indices)"),
        ),
    }
}

/// What the scene build chose, reported to the user.
#[derive(Clone, Debug)]
pub struct BuildReport {
    /// The materials the objects use (`scene::materials::describe`).
    pub materials: String,
    pub accel: String,
    pub light_sampling: String,
    /// What lights the scene from infinity, and how it is sampled.
    pub environment: String,
    pub build_time: Duration,
    /// Things the build skipped that the user may want to know (OBJ materials).
    pub warnings: Vec<String>,
}

impl std::fmt::Display for BuildReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "accel: {}; light sampling: {}; environment: {}; materials: {}",
            self.accel, self.light_sampling, self.environment, self.materials
        )?;
        for w in &self.warnings {
            write!(f, "; warning: {w}")?;
        }
        Ok(())
    }
}

/// One object of the scene file (a `[[sphere]]`, `[[triangle]]`, `[[quad]]` or `[[mesh]]`
/// table) and the primitives it became.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneObject {
    /// The array of tables it is in: `sphere`, `triangle`, `quad` or `mesh`.
    pub table: &'static str,
    /// Its place in that array.
    pub index: usize,
    pub name: Option<String>,
    /// Its primitives: `prims[first..first + count]`.
    pub first: u32,
    pub count: u32,
}

impl SceneObject {
    /// The loader's name for it: `quad[4]`.
    pub fn path(&self) -> String {
        format!("{}[{}]", self.table, self.index)
    }

    /// Its name, else its path.
    pub fn label(&self) -> String {
        self.name.clone().unwrap_or_else(|| self.path())
    }
}

/// The built scene. Its geometry (primitives, accelerator, shading normals) is shared between
/// scenes that differ only in their camera, so a camera move builds a new scene in microseconds
/// whatever the meshes.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Built-in name or file path, for messages and output file names.
    pub name: String,
    pub camera: Camera,
    pub prims: Arc<[Primitive]>,
    pub materials: Vec<Material>,
    pub lights: Lights,
    pub accel: Arc<Accel>,
    /// Per primitive, the shading normals of its three corners (all zero: flat); empty when
    /// the scene has no smooth-shaded mesh, so flat scenes pay one bounds check per hit.
    pub shading: Arc<[[[f32; 3]; 3]]>,
    /// The scene file's objects in the order their primitives were built.
    pub objects: Vec<SceneObject>,
    /// The textured materials and the primitives' texture coordinates; `None` without
    /// textures, so untextured scenes pay one test per vertex (`Scene::material_at`). Shared,
    /// like the geometry, by scenes that differ only in their camera.
    pub textures: Option<Arc<textures::SceneTextures>>,
    /// Every file the build read besides the scene file (meshes, material libraries, glTF
    /// buffers, textures), in the order read: what a change of the scene is watched by.
    pub files: Vec<std::path::PathBuf>,
    /// Radiance of the constant sky (black without one); unused when `environment` is set.
    pub background: DVec3,
    /// The environment map's light, when the scene has a map that is not black.
    pub environment: Option<Environment>,
    /// The probability that next-event estimation samples the environment rather than an
    /// emitter (1 without emitters; 0 without an environment map).
    pub env_select: f64,
    /// The scene file's `[render]` table: what it changes from the defaults.
    pub render: SettingsOverrides,
    pub report: BuildReport,
}

impl Scene {
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f64) -> Option<Hit> {
        self.accel
            .intersect(&self.prims, ray, t_max)
            .map(|h| self.shade(h))
    }

    /// Depth along the view of the first surface the pinhole ray through film position
    /// (`fx`, `fy`) hits: the focus distance that makes it sharp. None when the ray hits nothing.
    pub fn depth_at(&self, width: u32, height: u32, fx: f64, fy: f64) -> Option<f64> {
        let ray = self.camera.ray(width, height, fx, fy);
        let hit = self.accel.intersect(&self.prims, &ray, f64::INFINITY)?;
        let z = (ray.o + ray.d * hit.t - self.camera.position).dot(self.camera.forward);
        (z > 0.0 && z.is_finite()).then_some(z)
    }

    /// Whether any primitive has vertex normals.
    pub fn has_shading_normals(&self) -> bool {
        !self.shading.is_empty()
    }

    /// The hit with its shading normal (see [`Scene::interpolate_normal`]); flat scenes pay
    /// one test.
    #[inline(always)]
    fn shade(&self, hit: Hit) -> Hit {
        if self.shading.is_empty() {
            hit
        } else {
            self.interpolate_normal(hit)
        }
    }

    /// The corners' normals interpolated at the hit's barycentrics, within 90 degrees of the
    /// geometric normal; the geometric normal where the primitive has none or the
    /// interpolation degenerates (normals that cancel, or point away from the face). Kept out
    /// of line so flat scenes' hot loops stay as small as they were.
    #[inline(never)]
    fn interpolate_normal(&self, mut hit: Hit) -> Hit {
        let Some(ns) = self.shading.get(hit.prim as usize) else {
            return hit;
        };
        if ns[0] == [0.0; 3] {
            return hit;
        }
        let v = |i: usize| DVec3::new(ns[i][0] as f64, ns[i][1] as f64, ns[i][2] as f64);
        let (b1, b2) = (hit.uv[0] as f64, hit.uv[1] as f64);
        let s = v(0) * (1.0 - b1 - b2) + v(1) * b1 + v(2) * b2;
        let len = s.length();
        let s = s / len;
        if len > 0.0 && s.is_finite() && s.dot(hit.n) > 0.0 {
            hit.ns = s;
            hit.smooth = s != hit.n;
        }
        hit
    }

    /// The closest hit of every ray of `batch` within its t_max (t and primitive, u32::MAX for
    /// none); the hit record of one is [`Scene::hit_at`]. The same answers as
    /// [`Scene::intersect`].
    #[inline]
    pub fn intersect_batch(&self, batch: &mut RayBatch) {
        self.accel.closest_batch(&self.prims, batch)
    }

    /// The hit record of `ray` hitting primitive `prim` at distance `t`.
    #[inline(always)]
    pub fn hit_at(&self, ray: &Ray, t: f64, prim: u32) -> Hit {
        self.shade(self.prims[prim as usize].shape.hit(ray, t, prim))
    }

    /// Index of the first primitive along `ray` within `t_max` (shadow rays: is it the sampled
    /// light, or is nothing in the way?).
    #[inline]
    pub fn first_prim(&self, ray: &Ray, t_max: f64) -> Option<u32> {
        self.accel.closest_prim(&self.prims, ray, t_max)
    }

    #[inline]
    pub fn material(&self, hit: &Hit) -> &Material {
        &self.materials[self.prims[hit.prim as usize].material as usize]
    }

    /// Whether next-event estimation has anything to aim at.
    pub fn has_lights(&self) -> bool {
        !self.lights.is_empty() || self.environment.is_some()
    }

    /// Whether light sampling has more than one thing to choose from (then it reads a number
    /// for the choice).
    pub fn light_choices(&self) -> usize {
        self.lights.len() + usize::from(self.environment.is_some())
    }

    /// Radiance arriving from infinity against unit direction `d` (seen looking along it).
    #[inline]
    pub fn sky(&self, d: DVec3) -> DVec3 {
        match &self.environment {
            Some(env) => env.le(d),
            None => self.background,
        }
    }

    /// The object primitive `prim` belongs to.
    pub fn object_of(&self, prim: u32) -> Option<&SceneObject> {
        let i = self.objects.partition_point(|o| o.first <= prim);
        let o = self.objects.get(i.checked_sub(1)?)?;
        (prim < o.first + o.count).then_some(o)
    }

    /// The object the pinhole ray through film position (`fx`, `fy`) hits first.
    pub fn object_at(&self, width: u32, height: u32, fx: f64, fy: f64) -> Option<&SceneObject> {
        let ray = self.camera.ray(width, height, fx, fy);
        let prim = self.accel.closest_prim(&self.prims, &ray, f64::INFINITY)?;
        self.object_of(prim)
    }

    pub fn bounds(&self) -> Aabb {
        self.prims
            .iter()
            .fold(Aabb::EMPTY, |b, p| b.union(p.shape.bounds()))
    }
}
