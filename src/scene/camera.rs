//! Pinhole camera.

use crate::math::{Ray, Vec3A};

/// A pinhole camera looking from `position` towards `look_at`.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: Vec3A,
    /// Unit viewing direction.
    pub forward: Vec3A,
    /// Unit right vector (image +x).
    pub right: Vec3A,
    /// Unit up vector (image −y).
    pub up: Vec3A,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

impl Camera {
    /// Builds a camera; `None` when `look_at == position` or `up` is parallel
    /// to the viewing direction.
    pub fn new(position: Vec3A, look_at: Vec3A, up: Vec3A, vfov_deg: f32) -> Option<Self> {
        let forward = (look_at - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
            return None;
        }
        Some(Self {
            position,
            forward,
            right,
            up,
            vfov_deg,
        })
    }

    /// Ray through film position `(x, y)` in pixels (origin top-left, y down)
    /// of a `width × height` image.
    #[inline]
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        let tan_half = (self.vfov_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let sx = (2.0 * x / width as f32 - 1.0) * tan_half * aspect;
        let sy = (1.0 - 2.0 * y / height as f32) * tan_half;
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.position, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_forward_and_corners_are_symmetric() {
        let c = Camera::new(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 90.0).unwrap();
        let r = c.ray(50.0, 50.0, 100, 100);
        assert!((r.dir - -Vec3A::Z).length() < 1e-6);
        let tl = c.ray(0.0, 0.0, 100, 100).dir;
        assert!(tl.x < 0.0 && tl.y > 0.0);
        // 90° vertical fov: the top edge is at 45°.
        let top = c.ray(50.0, 0.0, 100, 100).dir;
        assert!((top.y - top.z.abs()).abs() < 1e-5);
        assert!(Camera::new(Vec3A::ZERO, Vec3A::Y, Vec3A::Y, 60.0).is_none());
    }
}
