//! Emitters for next-event estimation: which light to sample (in proportion to power) and how
//! (sphere lights by the cone of directions they subtend, triangles and quads by area), and the
//! environment map's light (`environment`).

pub mod environment;
pub mod sky;
pub mod sphere;
pub mod triangle;

use crate::math::{luminance, DVec3};
use crate::sampling::warp;

/// A direction towards a light, ready for a shadow ray.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub wi: DVec3,
    /// Solid-angle pdf, including the probability of having chosen this light.
    pub pdf: f64,
    /// Emitted radiance arriving along `wi` if the light is visible.
    pub le: DVec3,
    /// The primitive the shadow ray must hit first for the sample to count.
    pub prim: u32,
    /// The point on the light `wi` reaches, when the sampler found it anyway (saves the shadow
    /// ray's aim a ray-light test).
    pub point: Option<DVec3>,
}

// A sphere light carries its cuts inline (a few hundred bytes): scenes hold a handful of
// lights, and keeping them `Copy` and free of indirection matters more than their size.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
pub enum Light {
    Sphere(sphere::SphereLight),
    Triangle(triangle::TriangleLight),
}

impl Light {
    pub fn prim(&self) -> u32 {
        match self {
            Light::Sphere(l) => l.prim,
            Light::Triangle(l) => l.prim,
        }
    }

    /// Emitted power up to a constant factor shared by all lights (pi * area * luminance).
    pub fn power(&self) -> f64 {
        match self {
            Light::Sphere(l) => {
                std::f64::consts::PI * l.sphere.area() * luminance(l.emission).max(0.0)
            }
            // Each face that emits gives pi * area * L.
            Light::Triangle(l) => {
                l.sides()
                    * std::f64::consts::PI
                    * l.triangle.area()
                    * luminance(l.emission).max(0.0)
            }
        }
    }
}

/// The set of lights with a power-proportional selection distribution.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    pub lights: Vec<Light>,
    /// Probability of choosing each light.
    pmf: Vec<f64>,
    /// Running sum of `pmf`, last entry 1.
    cdf: Vec<f64>,
}

impl Lights {
    pub fn new(lights: Vec<Light>) -> Self {
        let powers: Vec<f64> = lights.iter().map(Light::power).collect();
        let total: f64 = powers.iter().sum();
        let pmf: Vec<f64> = if total > 0.0 && total.is_finite() {
            powers.iter().map(|p| p / total).collect()
        } else {
            vec![1.0 / lights.len().max(1) as f64; lights.len()]
        };
        let mut acc = 0.0;
        let mut cdf: Vec<f64> = pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Lights { lights, pmf, cdf }
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    pub fn len(&self) -> usize {
        self.lights.len()
    }

    pub fn pmf(&self, light: usize) -> f64 {
        self.pmf[light]
    }

    /// Choose a light with `u_select` and a direction towards it from `p` with `u`. `side` is a
    /// point just off the surface at `p` on the side the path arrived from: it tells which part
    /// of a light cut by a surface through `p` can be seen.
    #[inline(always)]
    pub fn sample(
        &self,
        p: DVec3,
        side: DVec3,
        u_select: f64,
        u: (f64, f64),
    ) -> Option<LightSample> {
        let index = match self.lights.len() {
            0 => return None,
            1 => 0,
            n => self.cdf.partition_point(|&c| c <= u_select).min(n - 1),
        };
        let pmf = self.pmf[index];
        if pmf <= 0.0 {
            return None;
        }
        let mut s = match &self.lights[index] {
            Light::Sphere(l) => l.sample(p, side, u)?,
            Light::Triangle(l) => l.sample(p, u)?,
        };
        s.pdf *= pmf;
        Some(s)
    }

    /// Solid-angle pdf (with selection) that [`Lights::sample`] picks direction `wi` from `p`
    /// towards light `light`, given that `wi` hits it first at `x`; `side` as for `sample`.
    #[inline]
    pub fn pdf(&self, light: usize, p: DVec3, side: DVec3, wi: DVec3, x: DVec3) -> f64 {
        let pdf = match &self.lights[light] {
            Light::Sphere(l) => l.pdf(p, side, x),
            Light::Triangle(l) => l.pdf(p, wi),
        };
        pdf * self.pmf[light]
    }
}

/// Re-exported so tests of light sampling can use the same cone warp.
pub use warp::uniform_cone_pdf;
