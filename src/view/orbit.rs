//! The viewer's camera: an orbit around a target point, as in modelling
//! tools (drag to orbit, shift-drag or right-drag to pan, wheel to zoom).

use crate::math::Vec3A;
use crate::scene::Camera;

/// Closest the pitch gets to the poles (radians), so that the view
/// direction never lines up with the up vector.
const MAX_PITCH: f32 = 1.55;

/// An orbit camera: the eye at `distance` from `target`, in the direction
/// given by `yaw` (about `up`) and `pitch` (above the plane orthogonal to
/// `up`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// Point looked at and orbited around.
    pub target: Vec3A,
    /// World up (unit).
    pub up: Vec3A,
    /// Angle about `up`, radians.
    pub yaw: f32,
    /// Angle above the horizontal plane, radians.
    pub pitch: f32,
    /// Eye-to-target distance.
    pub distance: f32,
    /// Vertical field of view, degrees.
    pub vfov_deg: f32,
}

impl Orbit {
    /// The orbit that puts the eye at `eye` looking at `target`.
    /// `None` when the eye is on the target or up is degenerate.
    pub fn looking_at(eye: Vec3A, target: Vec3A, up: Vec3A, vfov_deg: f32) -> Option<Self> {
        let up = up.try_normalize()?;
        let offset = eye - target;
        let distance = offset.length();
        if !(distance > 0.0 && distance.is_finite()) {
            return None;
        }
        let (e1, e2) = horizontal_basis(up);
        let d = offset / distance;
        let pitch = d.dot(up).clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH);
        let yaw = d.dot(e2).atan2(d.dot(e1));
        Some(Self {
            target,
            up,
            yaw,
            pitch,
            distance,
            vfov_deg,
        })
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3A {
        let (e1, e2) = horizontal_basis(self.up);
        let (sp, cp) = self.pitch.sin_cos();
        let (sy, cy) = self.yaw.sin_cos();
        self.target + (e1 * (cp * cy) + e2 * (cp * sy) + self.up * sp) * self.distance
    }

    /// The scene camera for this orbit.
    pub fn camera(&self) -> Option<Camera> {
        Camera::new(self.eye(), self.target, self.up, self.vfov_deg)
    }

    /// Half height of an orthographic camera on this orbit: that of the
    /// frustum at the target, so that zooming scales the image.
    pub fn orthographic_half_height(&self) -> f32 {
        self.distance * (self.vfov_deg.to_radians() * 0.5).tan()
    }

    /// Turns the eye around the target by a drag of `(dx, dy)` pixels in a
    /// view `height` pixels tall (a full-height drag turns by 180°).
    pub fn rotate(&mut self, dx: f32, dy: f32, height: f32) {
        let k = std::f32::consts::PI / height.max(1.0);
        self.yaw -= dx * k;
        self.pitch = (self.pitch + dy * k).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target and the eye together so that the point under the
    /// cursor follows a drag of `(dx, dy)` pixels.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let Some(cam) = self.camera() else { return };
        let world_per_pixel = 2.0 * self.distance * (self.vfov_deg.to_radians() * 0.5).tan() / height.max(1.0);
        self.target += (cam.right * -dx + cam.up * dy) * world_per_pixel;
    }

    /// Moves the eye toward the target (`steps > 0`) or away, by 10 % a step.
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * 0.9f32.powf(steps)).clamp(1e-4, 1e6);
    }
}

/// Two unit vectors that span the plane orthogonal to `up`.
fn horizontal_basis(up: Vec3A) -> (Vec3A, Vec3A) {
    let helper = if up.z.abs() < 0.9 { Vec3A::Z } else { Vec3A::X };
    let e1 = helper.cross(up).normalize();
    let e2 = up.cross(e1);
    (e1, e2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3A, b: Vec3A) -> bool {
        (a - b).length() < 1e-4 * (1.0 + b.length())
    }

    #[test]
    fn looking_at_reproduces_the_eye() {
        for eye in [
            Vec3A::new(0.0, 1.0, 5.0),
            Vec3A::new(-3.0, 2.0, 0.5),
            Vec3A::new(1.0, -2.0, -4.0),
        ] {
            let target = Vec3A::new(0.2, 0.5, -0.3);
            let o = Orbit::looking_at(eye, target, Vec3A::Y, 40.0).unwrap();
            assert!(close(o.eye(), eye), "{:?} vs {eye:?}", o.eye());
            let cam = o.camera().unwrap();
            assert!(close(cam.forward, (target - eye).normalize()));
        }
        assert!(Orbit::looking_at(Vec3A::ONE, Vec3A::ONE, Vec3A::Y, 40.0).is_none());
    }

    #[test]
    fn rotate_keeps_distance_and_pan_keeps_direction() {
        let mut o = Orbit::looking_at(Vec3A::new(0.0, 1.0, 5.0), Vec3A::ZERO, Vec3A::Y, 40.0).unwrap();
        let d = o.distance;
        let before = o.eye();
        o.rotate(120.0, 40.0, 540.0);
        assert!((o.eye().distance(o.target) - d).abs() < 1e-4);
        assert!(!close(o.eye(), before));
        let forward = o.camera().unwrap().forward;
        o.pan(30.0, -10.0, 540.0);
        assert!(close(o.camera().unwrap().forward, forward));
        assert!(o.target.length() > 0.0);
        // Pitch never reaches the pole.
        o.rotate(0.0, 1e5, 540.0);
        assert!(o.camera().is_some());
        o.zoom(3.0);
        assert!((o.distance - d * 0.729).abs() < 1e-3);
    }
}
