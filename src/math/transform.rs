use super::{Aabb, Affine3A, Mat3A, Ray, Vec3, Vec3A};

/// An affine object-to-world transform with its inverse and normal matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Object space to world space.
    pub to_world: Affine3A,
    /// World space to object space.
    pub to_object: Affine3A,
    /// Inverse transpose of the linear part: maps object normals to world.
    pub normal_to_world: Mat3A,
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform {
        to_world: Affine3A::IDENTITY,
        to_object: Affine3A::IDENTITY,
        normal_to_world: Mat3A::IDENTITY,
    };

    /// From an invertible affine matrix; `None` when it is singular or not finite.
    pub fn from_affine(m: Affine3A) -> Option<Self> {
        let det = m.matrix3.determinant();
        if !det.is_finite() || det.abs() < 1e-30 || !m.translation.is_finite() {
            return None;
        }
        let inv = m.inverse();
        Some(Self {
            to_world: m,
            to_object: inv,
            normal_to_world: inv.matrix3.transpose(),
        })
    }

    /// Scale, then rotate about x, y, z (degrees, in that order), then translate.
    pub fn from_srt(scale: Vec3, rotate_deg: Vec3, translate: Vec3) -> Option<Self> {
        let r = glam::Quat::from_euler(
            glam::EulerRot::ZYX,
            rotate_deg.z.to_radians(),
            rotate_deg.y.to_radians(),
            rotate_deg.x.to_radians(),
        );
        Self::from_affine(Affine3A::from_scale_rotation_translation(scale, r, translate))
    }

    /// True for the identity (lets the hot paths skip the matrix products).
    pub fn is_identity(&self) -> bool {
        self.to_world == Affine3A::IDENTITY
    }

    /// Object-space vector (a tangent, an edge) to world.
    #[inline]
    pub fn vector(&self, v: Vec3A) -> Vec3A {
        self.to_world.transform_vector3a(v)
    }

    /// Object-space point to world.
    #[inline]
    pub fn point(&self, p: Vec3A) -> Vec3A {
        self.to_world.transform_point3a(p)
    }

    /// Object-space normal to world (not normalised).
    #[inline]
    pub fn normal(&self, n: Vec3A) -> Vec3A {
        self.normal_to_world * n
    }

    /// World ray to object space; `t` keeps its meaning (the direction is not renormalised).
    #[inline]
    pub fn ray_to_object(&self, r: &Ray) -> Ray {
        Ray::new(
            self.to_object.transform_point3a(r.origin),
            self.to_object.transform_vector3a(r.dir),
        )
    }

    /// World bounds of an object-space box.
    pub fn bounds(&self, b: &Aabb) -> Aabb {
        b.transformed(&self.to_world)
    }

    /// Absolute error bound of `point(p)` given an object-space error `err`
    /// (pbrt-v4 §6.8.5: γ(3)(|M||p| + |t|) plus the propagated error).
    pub fn point_error(&self, p: Vec3A, err: Vec3A) -> Vec3A {
        let m = self.to_world.matrix3;
        let abs = Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        let g3 = super::gamma(3);
        (abs * err) * (1.0 + g3) + (abs * p.abs() + self.to_world.translation.abs()) * g3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srt_round_trips() {
        let t = Transform::from_srt(Vec3::splat(2.0), Vec3::new(0.0, 90.0, 0.0), Vec3::new(1.0, 2.0, 3.0)).unwrap();
        let p = Vec3A::new(1.0, 0.0, 0.0);
        let w = t.point(p);
        // Scale 2, rotate +90° about y: x → −z, then translate.
        assert!((w - Vec3A::new(1.0, 2.0, 1.0)).length() < 1e-5, "{w}");
        assert!((t.to_object.transform_point3a(w) - p).length() < 1e-5);
        assert!(Transform::from_srt(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO).is_none());
    }
}
