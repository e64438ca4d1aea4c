//! Smooth (delta) scattering: the mirror direction, Snell refraction with
//! total internal reflection, Schlick's Fresnel approximation, and the
//! dielectric interface that camera paths and photons share.

pub use super::fresnel::fresnel_schlick;
use crate::math::Vec3A;
use crate::scene::{Dielectric, FresnelModel, SurfaceInteraction};

/// Mirror direction of `d` about the unit normal `n`: `d − 2(d·n)n`.
#[inline]
pub fn reflect(d: Vec3A, n: Vec3A) -> Vec3A {
    d - n * (2.0 * d.dot(n))
}

/// Snell refraction of the unit direction `d` through a surface with unit
/// normal `n` facing the incident side (`d·n ≤ 0`), with `eta = n1/n2`.
/// Returns the refracted unit direction and `(cos θi, cos θt)`, or `None` on
/// total internal reflection (`sin² θt = eta² (1 − cos² θi) ≥ 1`).
#[inline]
pub fn refract(d: Vec3A, n: Vec3A, eta: f32) -> Option<(Vec3A, f32, f32)> {
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let t = d * eta + n * (eta * cos_i - cos_t);
    Some((t.normalize(), cos_i, cos_t))
}

/// Fresnel reflectance from medium `n1` into `n2` with the formula `model`,
/// given the cosines of the incident and transmitted directions (no total
/// internal reflection: the caller handles it).
#[inline]
pub fn fresnel(model: FresnelModel, n1: f32, n2: f32, cos_i: f32, cos_t: f32) -> f32 {
    match model {
        FresnelModel::Schlick => fresnel_schlick(n1, n2, cos_i, cos_t),
        FresnelModel::Exact => super::fresnel::dielectric(cos_i, n2 / n1).0,
    }
}

/// The directions leaving a smooth dielectric interface, shared by camera
/// paths and photons so that both see the same glass.
#[derive(Clone, Copy, Debug)]
pub struct DielectricInterface {
    /// IOR on the incident side.
    pub n1: f32,
    /// IOR on the transmitted side.
    pub n2: f32,
    /// Mirror direction.
    pub reflected: Vec3A,
    /// Refracted direction with `cos θi`, `cos θt`; `None` under total internal reflection.
    pub refracted: Option<(Vec3A, f32, f32)>,
    /// A thin sheet: the "refracted" direction is the incident one, and
    /// [`reflectance`](Self::reflectance) sums the light the sheet's two
    /// faces reflect.
    pub thin: bool,
}

impl DielectricInterface {
    /// The interface of the dielectric material `d` hit by direction `dir`
    /// at `si`: [`at`](Self::at), or for a thin sheet the mirror direction
    /// and the unbent transmission.
    pub fn of(dir: Vec3A, si: &SurfaceInteraction, d: &Dielectric) -> Self {
        if !d.thin {
            return Self::at(dir, si, d.ior);
        }
        let facing = if dir.dot(si.ng) < 0.0 { 1.0 } else { -1.0 };
        let (ng, ns) = (si.ng * facing, si.ns * facing);
        let mut reflected = reflect(dir, ns);
        if reflected.dot(ng) <= 0.0 {
            reflected = reflect(dir, ng);
        }
        let cos_i = (-dir.dot(ns)).clamp(0.0, 1.0);
        let (_, cos_t) = super::fresnel::dielectric(cos_i, d.ior);
        Self {
            n1: 1.0,
            n2: d.ior,
            reflected,
            refracted: Some((dir, cos_i, cos_t.abs())),
            thin: true,
        }
    }

    /// The fraction of the light reflected, from the cosines that come with
    /// [`refracted`](Self::refracted) (for a sheet, the series of its two
    /// faces' reflections, [`thin_sheet_reflectance`](super::dielectric::thin_sheet_reflectance)).
    pub fn reflectance(&self, model: FresnelModel, cos_i: f32, cos_t: f32) -> f32 {
        let r = fresnel(model, self.n1, self.n2, cos_i, cos_t);
        if self.thin {
            super::dielectric::sheet_series(r)
        } else {
            r
        }
    }

    /// The interface hit by direction `dir` at `si` (inside IOR `ior`, outside 1).
    ///
    /// Entering or leaving is decided by the GEOMETRIC normal (outward for
    /// closed shapes): an interpolated normal can face the wrong way near
    /// silhouettes. Leaving flips the normals and the IOR ratio. Both
    /// directions use the shading normal unless that would send them to the
    /// wrong side of the geometric surface.
    pub fn at(dir: Vec3A, si: &SurfaceInteraction, ior: f32) -> Self {
        let entering = dir.dot(si.ng) < 0.0;
        let (ng, ns, n1, n2) = if entering {
            (si.ng, si.ns, 1.0, ior)
        } else {
            (-si.ng, -si.ns, ior, 1.0)
        };
        let eta = n1 / n2;
        let mut n = ns;
        let mut refracted = refract(dir, ns, eta);
        if matches!(refracted, Some((t, _, _)) if t.dot(ng) >= 0.0) {
            n = ng;
            refracted = refract(dir, ng, eta);
        }
        let mut reflected = reflect(dir, n);
        if reflected.dot(ng) <= 0.0 {
            reflected = reflect(dir, ng);
        }
        Self {
            n1,
            n2,
            reflected,
            refracted,
            thin: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_is_r0() {
        for (n1, n2) in [(1.0f32, 1.5f32), (1.5, 1.0), (1.0, 1.33), (2.4, 1.0)] {
            let expected = ((n1 - n2) / (n1 + n2)).powi(2);
            assert!((fresnel_schlick(n1, n2, 1.0, 1.0) - expected).abs() < 1e-7);
            // The refract() path gives cos θt = 1 at normal incidence.
            let (_, ci, ct) = refract(-Vec3A::Z, Vec3A::Z, n1 / n2).unwrap();
            assert!((fresnel_schlick(n1, n2, ci, ct) - expected).abs() < 1e-6);
        }
        assert!((fresnel_schlick(1.0, 1.5, 1.0, 1.0) - 0.04).abs() < 1e-6);
        // Grazing incidence from the lighter side reflects everything.
        assert!((fresnel_schlick(1.0, 1.5, 0.0, 0.7) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle_only() {
        let (n1, n2) = (1.5f32, 1.0f32);
        let critical = (n2 / n1).asin();
        let n = Vec3A::Z;
        let dir = |theta: f32| Vec3A::new(theta.sin(), 0.0, -theta.cos());
        assert!(refract(dir(critical + 0.01), n, n1 / n2).is_none());
        assert!(refract(dir(1.5), n, n1 / n2).is_none());
        let (t, _, _) = refract(dir(critical - 0.01), n, n1 / n2).expect("below the critical angle");
        assert!(t.z < 0.0);
        // Approaching the critical angle from below, Schlick with cos θt
        // rises toward 1, i.e. it is continuous with TIR.
        let r_at = |theta: f32| {
            let (_, ci, ct) = refract(dir(theta), n, n1 / n2).unwrap();
            fresnel_schlick(n1, n2, ci, ct)
        };
        assert!(r_at(critical - 0.1) < r_at(critical - 0.01));
        assert!(r_at(critical - 0.01) < r_at(critical - 0.0005));
        assert!(r_at(critical - 0.0005) > 0.8, "{}", r_at(critical - 0.0005));
        // From the lighter side there is no TIR even at grazing angles.
        assert!(refract(dir(1.55), n, n2 / n1).is_some());
    }

    #[test]
    fn snell_law_holds() {
        let n = Vec3A::Z;
        for (theta_i, n1, n2) in [
            (0.3f32, 1.0f32, 1.5f32),
            (0.7, 1.0, 1.33),
            (0.5, 1.5, 1.0),
            (1.2, 1.0, 2.4),
        ] {
            let d = Vec3A::new(theta_i.sin(), 0.0, -theta_i.cos());
            let (t, _, _) = refract(d, n, n1 / n2).unwrap();
            assert!((t.length() - 1.0).abs() < 1e-5);
            // Transmitted to the other side, in the plane of incidence,
            // with n1 sin θi = n2 sin θt.
            assert!(t.z < 0.0 && t.y.abs() < 1e-6 && t.x > 0.0);
            let sin_t = (t.x * t.x + t.y * t.y).sqrt();
            assert!((n1 * theta_i.sin() - n2 * sin_t).abs() < 1e-5, "{theta_i} {n1} {n2}");
        }
        // Reflection keeps the angle.
        let d = Vec3A::new(0.6, 0.0, -0.8);
        assert!((reflect(d, n) - Vec3A::new(0.6, 0.0, 0.8)).length() < 1e-6);
    }
}
