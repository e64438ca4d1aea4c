//! Homogeneous participating media bounded by surfaces (Mitsuba's
//! `<medium type="homogeneous">` with `interior` / `exterior` references),
//! independent of the TOML water's `[medium]` ([`super::medium`]).
//!
//! A medium fills the space between the surfaces that name it. Which medium
//! a ray is in follows Mitsuba's rule (`SurfaceInteraction::target_medium`):
//! a ray leaving a surface of an object with a medium interface travels in
//! the object's interior when it goes against the geometric normal, in its
//! exterior otherwise; `None` is vacuum. Rays crossing surfaces without an
//! interface keep their medium.

use crate::math::Vec3A;

/// How a medium scatters light into a new direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseFunction {
    /// The same in every direction: `1 / 4π`.
    Isotropic,
    /// Henyey–Greenstein (1941) with asymmetry `g` in (−1, 1): `g > 0`
    /// scatters forward.
    HenyeyGreenstein {
        /// Mean cosine of the scattering angle.
        g: f32,
    },
}

impl PhaseFunction {
    /// The Henyey–Greenstein asymmetry that evaluates to this phase function
    /// (0 for the isotropic one, whose value HG with `g = 0` is).
    pub fn asymmetry(self) -> f32 {
        match self {
            PhaseFunction::Isotropic => 0.0,
            PhaseFunction::HenyeyGreenstein { g } => g,
        }
    }
}

/// A homogeneous medium: the same coefficients everywhere.
#[derive(Clone, Debug, PartialEq)]
pub struct HomogeneousMedium {
    /// Name for messages (the file's `id`, or where it is written).
    pub name: String,
    /// Extinction coefficient σt per channel and unit length, Mitsuba's
    /// `scale` already applied (≥ 0).
    pub sigma_t: Vec3A,
    /// Single-scattering albedo σs / σt per channel, in [0, 1].
    pub albedo: Vec3A,
    /// The phase function.
    pub phase: PhaseFunction,
    /// Scattering vertices in this medium sample a light (next-event
    /// estimation); when false (Mitsuba's `sample_emitters` = false) light
    /// is found only by the phase-sampled direction, with full weight.
    pub sample_emitters: bool,
}

impl HomogeneousMedium {
    /// Scattering coefficient σs = albedo · σt.
    pub fn sigma_s(&self) -> Vec3A {
        self.albedo * self.sigma_t
    }
}

/// The media on the two sides of an object's surface (`None`: vacuum).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    /// Index into [`Media::list`] of the medium inside (against the normal).
    pub interior: Option<u32>,
    /// Index of the medium outside (the side the normal points to).
    pub exterior: Option<u32>,
}

impl MediumInterface {
    /// True when crossing the surface may change the medium (Mitsuba's
    /// `is_medium_transition`: either side names a medium).
    pub fn is_transition(&self) -> bool {
        self.interior.is_some() || self.exterior.is_some()
    }

    /// The medium a ray leaving the surface in direction `dir` travels in,
    /// against the geometric normal `ng`: the interior when
    /// `dir · ng ≤ 0`, else the exterior (Mitsuba's `target_medium`).
    pub fn target(&self, dir: Vec3A, ng: Vec3A) -> Option<u32> {
        if dir.dot(ng) > 0.0 {
            self.exterior
        } else {
            self.interior
        }
    }
}

/// How paths treat media and the surfaces rays pass straight through
/// (`null`, a thin dielectric's transmission): as the Mitsuba integrator
/// that reads the scene does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PassThrough {
    /// Mitsuba's `volpath`: media scatter and absorb; crossing a null
    /// surface is not a bounce, and shadow rays pass through it.
    Volumetric,
    /// Mitsuba's `path` and `direct`, and caustic's own scenes: no media;
    /// crossing a null surface (or a blend's hole) is a delta bounce
    /// (Mitsuba's `BSDFFlags::Delta` includes `Null`): it counts toward
    /// `max_depth`, samples no light, and blocks shadow rays, so light
    /// behind it arrives only along the continued path.
    #[default]
    SurfaceBounce,
}

/// The scene's media, which objects bound them, and the camera's.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Media {
    /// Every medium, referenced by index.
    pub list: Vec<HomogeneousMedium>,
    /// Per object (by index in `Scene::objects`), its interface; empty when
    /// no object has one.
    pub interfaces: Vec<MediumInterface>,
    /// The medium the camera's rays start in.
    pub camera: Option<u32>,
    /// How paths cross null surfaces (and whether media count).
    pub pass_through: PassThrough,
}

impl Media {
    /// True when the scene has no medium: rays travel in vacuum.
    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// The interface of object `object` (vacuum on both sides when it has none).
    pub fn interface(&self, object: u32) -> MediumInterface {
        self.interfaces.get(object as usize).copied().unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_medium_is_interior_against_the_normal() {
        let i = MediumInterface {
            interior: Some(3),
            exterior: None,
        };
        let n = Vec3A::Y;
        assert_eq!(i.target(-Vec3A::Y, n), Some(3));
        assert_eq!(i.target(Vec3A::new(0.2, 0.5, 0.0), n), None);
        assert!(i.is_transition());
        assert!(!MediumInterface::default().is_transition());
        let media = Media::default();
        assert_eq!(media.interface(7), MediumInterface::default());
    }
}
