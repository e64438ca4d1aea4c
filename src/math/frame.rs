use super::Vec3A;

/// Orthonormal frame around a unit normal (Duff et al. 2017, "Building an
/// Orthonormal Basis, Revisited"): branch-free and continuous except at one sign flip.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3A,
    /// Second tangent.
    pub t: Vec3A,
    /// Normal.
    pub n: Vec3A,
}

impl Frame {
    /// Frame whose `n` axis is the unit vector `n`.
    pub fn from_normal(n: Vec3A) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3A::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// Frame whose `n` axis is the unit vector `n` and whose `s` axis is
    /// `tangent` made orthogonal to it (Gram–Schmidt, Mitsuba's shading
    /// frame from `∂p/∂u`); [`from_normal`](Self::from_normal) when the
    /// tangent is zero or along `n`.
    pub fn from_normal_tangent(n: Vec3A, tangent: Vec3A) -> Self {
        let s = tangent - n * n.dot(tangent);
        let len2 = s.length_squared();
        let usable = len2.is_finite() && len2 > 1e-12 * tangent.length_squared().max(f32::MIN_POSITIVE);
        if !usable {
            return Self::from_normal(n);
        }
        let s = s / len2.sqrt();
        Self { s, t: n.cross(s), n }
    }

    /// World coordinates to local (`n` becomes +z).
    #[inline]
    pub fn to_local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local coordinates to world.
    #[inline]
    pub fn to_world(&self, v: Vec3A) -> Vec3A {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal() {
        for n in [Vec3A::Z, -Vec3A::Z, Vec3A::X, Vec3A::new(0.3, -0.5, 0.8).normalize()] {
            let f = Frame::from_normal(n);
            assert!(f.s.dot(f.t).abs() < 1e-6 && f.s.dot(f.n).abs() < 1e-6);
            assert!((f.s.length() - 1.0).abs() < 1e-6 && (f.t.length() - 1.0).abs() < 1e-6);
            assert!((f.to_world(Vec3A::Z) - n).length() < 1e-6);
        }
    }
}
