//! Camera mode (`v`): the camera orbits its look-at point, dollies towards it, pans with it and
//! widens or narrows its field of view. Each move is a change of the scene file's `[camera]`
//! keys (the ones the move changed, in the form the file gives them: `look_at` or
//! `direction`), so the scene is rebuilt, validated and written back like any edit.
//!
//! A camera given by `direction` has no look-at point: it orbits the point it looks at at the
//! focus distance (by default the first surface its centre ray hits).

use crate::math::DVec3;
use crate::scene::edit::{number, vector, KeyPath, SceneDoc};
use crate::scene::DEFAULT_VFOV;
use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
use toml_edit::Value;

/// Degrees of orbit per key press.
pub const ORBIT_STEP: f64 = 5.0;
/// Distance to the look-at point kept per dolly step towards it.
pub const DOLLY_STEP: f64 = 0.9;
/// Fraction of the distance to the look-at point the camera pans per key press.
pub const PAN_STEP: f64 = 0.05;
/// Field of view factor per `[` / `]` press.
pub const FOV_STEP: f64 = 1.1;
/// The camera stays this many degrees off the poles (straight above or below the look-at
/// point), where yaw about the up vector would spin it in place.
const POLE_MARGIN: f64 = 5.0;
const FOV_RANGE: (f64, f64) = (1.0, 170.0);

/// One camera move.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Move {
    /// Degrees right (yaw about the up vector) and up (pitch towards the up pole).
    Orbit(f64, f64),
    /// Distance to the look-at point times this factor.
    Dolly(f64),
    /// Camera and look-at point moved right and up by these fractions of their distance.
    Pan(f64, f64),
    /// Field of view times this factor.
    Fov(f64),
}

/// Degrees of orbit per cell a mouse drag moves across (twice that per row: cells are about
/// twice as tall as wide).
pub const DRAG_STEP: f64 = 1.0;

/// The move a key makes in camera mode: arrows (and h j k l) orbit, Shift+arrows (and H J K
/// L) pan, `+`/`-` dolly towards and away from the look-at point, `[`/`]` narrow and widen the
/// field of view.
pub fn key_move(key: &KeyEvent) -> Option<Move> {
    let shift = key.modifiers.contains(KeyModifiers::SHIFT);
    let (o, p) = (ORBIT_STEP, PAN_STEP);
    Some(match key.code {
        KeyCode::Left if shift => Move::Pan(-p, 0.0),
        KeyCode::Right if shift => Move::Pan(p, 0.0),
        KeyCode::Up if shift => Move::Pan(0.0, p),
        KeyCode::Down if shift => Move::Pan(0.0, -p),
        KeyCode::Char('H') => Move::Pan(-p, 0.0),
        KeyCode::Char('L') => Move::Pan(p, 0.0),
        KeyCode::Char('K') => Move::Pan(0.0, p),
        KeyCode::Char('J') => Move::Pan(0.0, -p),
        KeyCode::Left | KeyCode::Char('h') => Move::Orbit(-o, 0.0),
        KeyCode::Right | KeyCode::Char('l') => Move::Orbit(o, 0.0),
        KeyCode::Up | KeyCode::Char('k') => Move::Orbit(0.0, o),
        KeyCode::Down | KeyCode::Char('j') => Move::Orbit(0.0, -o),
        KeyCode::Char('+') | KeyCode::Char('=') => Move::Dolly(DOLLY_STEP),
        KeyCode::Char('-') => Move::Dolly(1.0 / DOLLY_STEP),
        KeyCode::Char('[') => Move::Fov(1.0 / FOV_STEP),
        KeyCode::Char(']') => Move::Fov(FOV_STEP),
        _ => return None,
    })
}

/// The camera as the moves see it: where it is, the point it turns about, the world's up and
/// the field of view, and which keys the moves have changed.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    pub position: DVec3,
    pub pivot: DVec3,
    pub up: DVec3,
    pub vfov: f64,
    /// The file aims the camera with `look_at` (else `direction`).
    pub look_at: bool,
    moved: bool,
    aimed: bool,
    zoomed: bool,
}

/// A vector key of the doc's `[camera]`.
fn doc_vector(doc: &SceneDoc, key: &str) -> Option<DVec3> {
    let a = doc.get(&KeyPath::table("camera", key))?.as_array()?;
    let v: Vec<f64> = a.iter().filter_map(value_number).collect();
    (v.len() == 3).then(|| DVec3::new(v[0], v[1], v[2]))
}

/// A number value (integer or float).
pub fn value_number(v: &Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

impl Rig {
    /// The camera of `doc`'s `[camera]` table (the loader's defaults where it says nothing); a
    /// `direction` camera turns about the point `distance` ahead of it.
    pub fn from_doc(doc: &SceneDoc, distance: f64) -> Rig {
        let position = doc_vector(doc, "position").unwrap_or(DVec3::ZERO);
        let up = doc_vector(doc, "up")
            .and_then(DVec3::try_normalize)
            .unwrap_or(DVec3::Y);
        let vfov = doc
            .get(&KeyPath::table("camera", "vfov"))
            .and_then(value_number)
            .unwrap_or(DEFAULT_VFOV);
        let (pivot, look_at) = match doc_vector(doc, "look_at") {
            Some(target) => (target, true),
            None => {
                let d = doc_vector(doc, "direction")
                    .and_then(DVec3::try_normalize)
                    .unwrap_or(DVec3::NEG_Z);
                let distance = if distance.is_finite() && distance > 0.0 {
                    distance
                } else {
                    1.0
                };
                (position + d * distance, false)
            }
        };
        Rig {
            position,
            pivot,
            up,
            vfov,
            look_at,
            moved: false,
            aimed: false,
            zoomed: false,
        }
    }

    /// The unit view direction.
    pub fn forward(&self) -> DVec3 {
        (self.pivot - self.position).normalize_or(DVec3::NEG_Z)
    }

    /// The camera's right, perpendicular to the view and the up vector.
    fn right(&self) -> DVec3 {
        self.forward().cross(self.up).normalize_or(DVec3::X)
    }

    pub fn apply(&mut self, m: Move) {
        match m {
            Move::Orbit(yaw, pitch) => self.orbit(yaw, pitch),
            Move::Dolly(f) => {
                self.position = self.pivot + (self.position - self.pivot) * f;
                self.moved = true;
            }
            Move::Pan(dx, dy) => {
                let r = (self.pivot - self.position).length();
                let right = self.right();
                let up = right.cross(self.forward());
                let shift = (right * dx + up * dy) * r;
                self.position += shift;
                self.pivot += shift;
                self.moved = true;
                // A direction is unchanged by a pan; a look-at point moves with the camera.
                self.aimed |= self.look_at;
            }
            Move::Fov(f) => {
                self.vfov = (self.vfov * f).clamp(FOV_RANGE.0, FOV_RANGE.1);
                self.zoomed = true;
            }
        }
    }

    /// Turn the camera about the pivot: `yaw` degrees about the up vector (positive: the
    /// camera moves right), `pitch` degrees towards the up pole, staying clear of the poles.
    fn orbit(&mut self, yaw: f64, pitch: f64) {
        let o = self.position - self.pivot;
        let r = o.length();
        if r == 0.0 || !r.is_finite() {
            return;
        }
        let u = self.up;
        let h = o - u * o.dot(u);
        // Straight above or below: the camera's own right stands in for the horizontal.
        let e1 = h.try_normalize().unwrap_or_else(|| u.cross(self.right()));
        let e2 = u.cross(e1);
        let (s, c) = yaw.to_radians().sin_cos();
        let e1 = e1 * c + e2 * s;
        let theta = (o.dot(u) / r).clamp(-1.0, 1.0).acos().to_degrees();
        let theta = (theta - pitch).clamp(POLE_MARGIN, 180.0 - POLE_MARGIN);
        let (st, ct) = theta.to_radians().sin_cos();
        self.position = self.pivot + (e1 * st + u * ct) * r;
        self.moved = true;
        self.aimed |= !self.look_at;
    }

    /// The `[camera]` keys the moves changed, with their new values.
    pub fn sets(&self) -> Vec<(KeyPath, Option<Value>)> {
        let key = |k: &str| KeyPath::table("camera", k);
        let mut sets = Vec::new();
        if self.moved {
            sets.push((key("position"), Some(vector(self.position.to_array()))));
        }
        if self.aimed {
            let (k, v) = if self.look_at {
                ("look_at", self.pivot)
            } else {
                ("direction", self.forward())
            };
            sets.push((key(k), Some(vector(v.to_array()))));
        }
        if self.zoomed {
            sets.push((key("vfov"), Some(number(self.vfov))));
        }
        sets
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(camera: &str) -> SceneDoc {
        SceneDoc::from_text("t.toml", None, format!("[camera]\n{camera}\n")).unwrap()
    }

    fn close(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-9
    }

    #[test]
    fn orbit_keeps_the_distance_and_the_look_at_point() {
        let mut rig = Rig::from_doc(&doc("position = [0, 0, 10]\nlook_at = [0, 0, 0]"), 1.0);
        rig.apply(Move::Orbit(90.0, 0.0));
        // A quarter turn to the right, seen from +z looking at the origin: to +x.
        assert!(
            close(rig.position, DVec3::new(10.0, 0.0, 0.0)),
            "{:?}",
            rig.position
        );
        rig.apply(Move::Orbit(0.0, 30.0));
        assert!((rig.position.length() - 10.0).abs() < 1e-9);
        assert!((rig.position.y - 5.0).abs() < 1e-9, "{:?}", rig.position);
        // Pitch stops short of the pole.
        rig.apply(Move::Orbit(0.0, 120.0));
        let theta = rig.position.normalize().y.acos().to_degrees();
        assert!((theta - POLE_MARGIN).abs() < 1e-9, "{theta}");
        let keys: Vec<String> = rig.sets().iter().map(|(k, _)| k.to_string()).collect();
        assert_eq!(keys, vec!["camera.position"]);
    }

    #[test]
    fn a_direction_camera_turns_about_the_point_ahead_and_writes_its_direction() {
        let mut rig = Rig::from_doc(
            &doc("position = [50, 52, 295.6]\ndirection = [0, 0, -2]"),
            100.0,
        );
        assert!(close(rig.pivot, DVec3::new(50.0, 52.0, 195.6)));
        rig.apply(Move::Dolly(DOLLY_STEP));
        assert!(close(rig.position, DVec3::new(50.0, 52.0, 285.6)));
        let keys: Vec<String> = rig.sets().iter().map(|(k, _)| k.to_string()).collect();
        assert_eq!(keys, vec!["camera.position"], "a dolly keeps the direction");
        rig.apply(Move::Orbit(-ORBIT_STEP, 0.0));
        let sets = rig.sets();
        assert_eq!(sets[1].0.to_string(), "camera.direction");
        // Moved left: it now looks a little to the right (+x: right of -z with +y up).
        assert!(rig.forward().x > 0.0 && rig.position.x < 50.0);
        rig.apply(Move::Fov(FOV_STEP));
        assert_eq!(rig.sets()[2].1.as_ref().unwrap().to_string(), "44");
    }

    #[test]
    fn pan_moves_camera_and_target_together() {
        let mut rig = Rig::from_doc(
            &doc("position = [0, 0, 10]\nlook_at = [0, 0, 0]\nup = [0, 2, 0]"),
            1.0,
        );
        rig.apply(Move::Pan(PAN_STEP, 0.0));
        assert!(close(rig.position, DVec3::new(0.5, 0.0, 10.0)));
        assert!(close(rig.pivot, DVec3::new(0.5, 0.0, 0.0)));
        rig.apply(Move::Pan(0.0, -PAN_STEP));
        assert!(close(rig.pivot, DVec3::new(0.5, -0.5, 0.0)));
        let keys: Vec<String> = rig.sets().iter().map(|(k, _)| k.to_string()).collect();
        assert_eq!(keys, vec!["camera.position", "camera.look_at"]);
        // The field of view stays in range.
        for _ in 0..100 {
            rig.apply(Move::Fov(FOV_STEP));
        }
        assert_eq!(rig.vfov, FOV_RANGE.1);
    }
}
