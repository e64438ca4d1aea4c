use super::Vec3A;

/// A ray `origin + t·dir`. `dir` need not be unit length: rays moved into an
/// instance's object space keep the world-space parameter `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Origin of the ray.
    pub origin: Vec3A,
    /// Direction (unit length for world-space rays built by the integrators).
    pub dir: Vec3A,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    #[inline]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        Self { origin, dir }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + self.dir * t
    }
}
