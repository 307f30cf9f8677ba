//! The scene's camera from its `[camera]` table: position and orientation, field of view, and
//! the thin lens's aperture and focus (which needs the built accelerator to find the surface the
//! centre ray hits).

use super::description::SceneDesc;
use super::SceneError;
use crate::accel::Accel;
use crate::camera::Camera;
use crate::geometry::Primitive;
use crate::math::{DVec3, Ray};

/// Default vertical field of view, degrees.
pub const DEFAULT_VFOV: f64 = 40.0;

pub(super) fn build_camera(desc: &SceneDesc, src: &str, file: &str) -> Result<Camera, SceneError> {
    let c = &desc.camera;
    let position = c.position.map_or(DVec3::ZERO, |p| DVec3::from_array(p.0));
    let forward = match (&c.direction, &c.look_at) {
        (Some(_), Some(look_at)) => {
            return Err(SceneError::at(
                file,
                src,
                Some(look_at.span()),
                Some("camera.look_at".into()),
                "give either `direction` or `look_at`, not both",
            ))
        }
        (Some(d), None) => DVec3::from_array(d.get_ref().0),
        (None, Some(target)) => {
            let d = DVec3::from_array(target.get_ref().0) - position;
            // Not just d == 0: a difference so small its square underflows cannot be normalised.
            if d.try_normalize().is_none() {
                return Err(SceneError::at(
                    file,
                    src,
                    Some(target.span()),
                    Some("camera.look_at".into()),
                    "the camera looks at its own position",
                ));
            }
            d
        }
        (None, None) => -DVec3::Z,
    };
    let up =
        c.up.as_ref()
            .map_or(DVec3::Y, |u| DVec3::from_array(u.get_ref().0));
    let sin = forward.normalize().cross(up.normalize()).length();
    if sin < 1e-6 {
        let span =
            c.up.as_ref()
                .map(|u| u.span())
                .or_else(|| c.direction.as_ref().map(|d| d.span()))
                .or_else(|| c.look_at.as_ref().map(|d| d.span()));
        return Err(SceneError::at(
            file,
            src,
            span,
            Some("camera.up".into()),
            "the up vector is parallel to the view direction",
        ));
    }
    let vfov = c.vfov.map_or(DEFAULT_VFOV, |f| f.0);
    let near = c.near.map_or(0.0, |n| n.0);
    Ok(Camera::new(position, forward, up, vfov, near))
}

/// The camera with its lens: `aperture`, and the focus plane at `focus_distance`, through
/// `focus_on`, or by default at the first surface the centre ray hits (the scene's centre if it
/// hits nothing), so a lens without a focus setting is sharp where the camera looks.
pub(super) fn focus_camera(
    camera: Camera,
    desc: &SceneDesc,
    accel: &Accel,
    prims: &[Primitive],
    src: &str,
    file: &str,
) -> Result<Camera, SceneError> {
    let c = &desc.camera;
    let aperture = c.aperture.map_or(0.0, |a| a.0);
    let focus = match (&c.focus_distance, &c.focus_on) {
        (Some(_), Some(on)) => {
            return Err(SceneError::at(
                file,
                src,
                Some(on.span()),
                Some("camera.focus_on".into()),
                "give either `focus_distance` or `focus_on`, not both",
            ))
        }
        (Some(f), None) => f.get_ref().0,
        (None, Some(on)) => {
            let z = (DVec3::from_array(on.get_ref().0) - camera.position).dot(camera.forward);
            if z.is_nan() || z <= 0.0 {
                return Err(SceneError::at(
                    file,
                    src,
                    Some(on.span()),
                    Some("camera.focus_on".into()),
                    format!(
                        "the point is not in front of the camera (distance {z:e} along the view)"
                    ),
                ));
            }
            z
        }
        (None, None) => default_focus(&camera, accel, prims),
    };
    Ok(camera.with_lens(aperture, focus))
}

/// Distance along the view to the first surface the centre ray hits (from `near` on); the scene's centre if it
/// hits nothing in front of the camera; 1 for an empty scene.
pub fn default_focus(camera: &Camera, accel: &Accel, prims: &[Primitive]) -> f64 {
    // The centre ray starts `near` along the view like every camera ray (smallpt's starts
    // past its front wall).
    let ray = Ray::new(
        camera.position + camera.forward * camera.near,
        camera.forward,
    );
    if let Some(hit) = accel.intersect(prims, &ray, f64::INFINITY) {
        return camera.near + hit.t;
    }
    let bounds = prims
        .iter()
        .map(|p| p.shape.bounds())
        .reduce(|a, b| a.union(b));
    bounds
        .map(|b| (b.centroid() - camera.position).dot(camera.forward))
        .filter(|z| *z > 0.0 && z.is_finite())
        .unwrap_or(1.0)
}
