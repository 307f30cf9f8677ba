//! What lights the scene from infinity: the old constant `background`, or the `[environment]`
//! table's constant colour or map (read from a file or generated), checked field by field.

use super::description::SceneDesc;
use super::load::BuildOptions;
use super::SceneError;
use crate::light::environment::{EnvMap, Environment};
use crate::math::DVec3;
use std::path::PathBuf;

/// What lights the scene from infinity.
pub(super) struct Sky {
    pub background: DVec3,
    pub environment: Option<Environment>,
    /// For the build report.
    pub text: String,
}

/// The sky from `background` or the `[environment]` table; `emitters`: whether the scene has
/// emitters for the map's light samples to share with.
pub(super) fn build_sky(
    desc: &SceneDesc,
    src: &str,
    file: &str,
    options: &BuildOptions,
    emitters: bool,
) -> Result<Sky, SceneError> {
    let err =
        |span, field: &str, msg: String| SceneError::at(file, src, span, Some(field.into()), msg);
    let constant = |c: DVec3| Sky {
        background: c,
        environment: None,
        text: if c == DVec3::ZERO {
            "black".into()
        } else {
            format!(
                "constant [{}, {}, {}] (found by BSDF sampling)",
                c.x, c.y, c.z
            )
        },
    };
    let Some(table) = &desc.environment else {
        // The old key: the same value, the same code path.
        return Ok(constant(
            desc.background
                .map_or(DVec3::ZERO, |c| DVec3::from_array(c.0)),
        ));
    };
    let span = Some(table.span());
    if desc.background.is_some() {
        return Err(err(
            span,
            "environment",
            "give either `background` or an [environment] table, not both".into(),
        ));
    }
    let e = table.get_ref();
    let intensity = e.intensity.map_or(1.0, |i| i.0);
    let map = match (&e.map, &e.color) {
        (Some(map), Some(_)) => {
            return Err(err(
                Some(map.span()),
                "environment.map",
                "give either `map` or `color`, not both".into(),
            ))
        }
        (None, None) => {
            return Err(err(
                span,
                "environment",
                "the table needs `map` (an EXR or HDR file, or \"builtin:sky\") or `color`".into(),
            ))
        }
        (None, Some(color)) => {
            if e.rotate.is_some() {
                return Err(err(
                    span,
                    "environment.rotate",
                    "`rotate` turns a `map`; a constant `color` has nothing to turn".into(),
                ));
            }
            return Ok(constant(DVec3::from_array(color.get_ref().0) * intensity));
        }
        (Some(map), None) => map,
    };
    let name = map.get_ref();
    let texels = if name == BUILTIN_SKY {
        EnvMap::builtin_sky()
    } else {
        let full = match &options.base_dir {
            Some(base) => base.join(name),
            None => PathBuf::from(name),
        };
        EnvMap::read(&full).map_err(|msg| err(Some(map.span()), "environment.map", msg))?
    };
    let rotate = e.rotate.map_or(DVec3::ZERO, |r| DVec3::from_array(r.0));
    let environment = Environment::new(&texels, intensity, rotate);
    let text = match &environment {
        Some(_) => format!(
            "map {name} ({}x{}), importance-sampled{}",
            texels.width,
            texels.height,
            if emitters {
                " in half of the light samples, MIS with BSDF sampling"
            } else {
                ", MIS with BSDF sampling"
            }
        ),
        None => format!("map {name} is black (no light)"),
    };
    Ok(Sky {
        background: DVec3::ZERO,
        environment,
        text,
    })
}

/// `map` naming the generated sky instead of a file.
pub const BUILTIN_SKY: &str = "builtin:sky";
