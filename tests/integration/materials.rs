//! Tests of the microfacet materials (rough conductor, rough glass, smooth and rough plastic):
//! one submodule per property, this file the constructors they share.
//!
//! - `chi2`: sampling against `eval`'s pdf (chi-square in a frame about each lobe);
//! - `consistency`: `sample`'s weight and pdf against `eval`, reciprocity;
//! - `furnace`: directional albedo against an independent integral, per sample and rendered;
//! - `energy`: no material reflects more than it receives;
//! - `extreme`: extreme parameters and directions stay finite; the scene-level rules for
//!   `alpha` below [`ptui::material::SPECULAR_ALPHA`] and `alpha = 0`.

mod chi2;
mod consistency;
mod energy;
mod extreme;
mod furnace;

use ptui::geometry::Normals;
use ptui::material::{
    Conductor, ConductorFresnel, Distribution, Glossy, Material, MaterialKind, Microfacet, Plastic,
    RoughDielectric,
};
use ptui::math::{DVec3, Frame};
use ptui::sampling::{warp, Rng};
use std::sync::Mutex;

pub fn material(kind: MaterialKind, color: f64) -> Material {
    Material {
        kind,
        color: DVec3::splat(color),
        emission: DVec3::ZERO,
        one_sided: false,
    }
}

pub fn ggx(alpha_u: f64, alpha_v: f64) -> Distribution {
    Distribution::new(Microfacet::Ggx, alpha_u, alpha_v)
}

pub fn beckmann(alpha_u: f64, alpha_v: f64) -> Distribution {
    Distribution::new(Microfacet::Beckmann, alpha_u, alpha_v)
}

/// A conductor of colour 1: rough with `d`, smooth with None.
pub fn conductor(d: Option<Distribution>, fresnel: ConductorFresnel) -> Material {
    material(
        match d {
            Some(distribution) => Glossy::Conductor(Conductor {
                distribution,
                fresnel,
            })
            .kind(),
            None => MaterialKind::SmoothConductor(Box::new(fresnel)),
        },
        1.0,
    )
}

/// Gold's complex index (Mitsuba's RGB values), for a conductor whose Fresnel term varies.
pub fn gold() -> ConductorFresnel {
    let (eta, k) = ptui::material::metals::lookup("Au").expect("gold is in the table");
    ConductorFresnel::Complex { eta, k }
}

pub fn rough_glass(d: Distribution, ior: f64) -> Material {
    material(
        Glossy::RoughGlass(RoughDielectric {
            distribution: d,
            ior,
        })
        .kind(),
        1.0,
    )
}

/// Plastic of base colour `color` (grey) under a coat of index `ior`, specular factor 1. A
/// rough coat's tables take 0.2 s (GGX) to 0.5 s (Beckmann) to build, so the tests share each
/// rough plastic they make.
pub fn plastic(ior: f64, color: f64, rough: Option<Distribution>) -> Material {
    type Key = (u64, u64, Distribution);
    static BUILT: Mutex<Vec<(Key, Material)>> = Mutex::new(Vec::new());
    let build = || {
        material(
            Glossy::Plastic(Plastic::new(ior, DVec3::ONE, color, rough)).kind(),
            color,
        )
    };
    let Some(d) = rough else {
        return build();
    };
    let key = (ior.to_bits(), color.to_bits(), d);
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, m)) = built.iter().find(|(k, _)| *k == key) {
        return m.clone();
    }
    let m = build();
    built.push((key, m.clone()));
    m
}

/// The unit direction at `cos` to +z (or to -z with `below`), at azimuth `phi`.
pub fn dir(cos: f64, phi: f64, below: bool) -> DVec3 {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let z = if below { -cos } else { cos };
    DVec3::new(sin * phi.cos(), sin * phi.sin(), z)
}

/// Random geometric normals with shading normals up to 60 degrees off them (as
/// `material::tests::random_normals`), or flat ones one time in four.
pub fn random_normals(rng: &mut Rng) -> Normals {
    let g = warp::uniform_sphere((rng.next_f64(), rng.next_f64()));
    if rng.next_f64() < 0.25 {
        return Normals::flat(g);
    }
    let a = rng.next_f64() * 60f64.to_radians();
    let phi = rng.next_f64() * std::f64::consts::TAU;
    let local = DVec3::new(a.sin() * phi.cos(), a.sin() * phi.sin(), a.cos());
    Normals::new(g, Frame::from_normal(g).to_world(local))
}

/// A random microfacet distribution: GGX or Beckmann, roughness log-uniform in
/// [`lo`, 1], anisotropic half the time.
pub fn random_distribution(rng: &mut Rng, lo: f64) -> Distribution {
    let mut alpha = || lo * (1.0 / lo).powf(rng.next_f64());
    let (au, av) = (alpha(), alpha());
    let kind = if rng.next_f64() < 0.5 {
        Microfacet::Ggx
    } else {
        Microfacet::Beckmann
    };
    if rng.next_f64() < 0.5 {
        Distribution::new(kind, au, au)
    } else {
        Distribution::new(kind, au, av)
    }
}
