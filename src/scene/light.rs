//! Light sources, physically based so that direct light and photon power agree.

use crate::math::{Vec2, Vec3A};

/// A light.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light: radiant intensity `intensity` (W/sr per channel);
    /// irradiance at distance r falls off as cos θ / r².
    Point {
        /// Position.
        position: Vec3A,
        /// Colour × intensity.
        intensity: Vec3A,
    },
    /// One-sided rectangle emitting radiance `radiance` from the side of
    /// `normal = normalize(u × v)`.
    Area(AreaLight),
    /// Constant radiance arriving from every direction, infinitely far.
    Environment {
        /// Colour × intensity (W/m²/sr per channel).
        radiance: Vec3A,
    },
}

/// Rectangular area light centred on `center` with edges `u` and `v`.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    /// Centre of the rectangle.
    pub center: Vec3A,
    /// First edge (full length).
    pub u: Vec3A,
    /// Second edge (full length).
    pub v: Vec3A,
    /// Unit emitting normal, `normalize(u × v)`.
    pub normal: Vec3A,
    /// Emitted radiance: colour × intensity (W/m²/sr per channel).
    pub radiance: Vec3A,
    /// Shadow rays per shading point (the original report used 32).
    pub samples: u32,
}

impl AreaLight {
    /// Builds the light; `None` if the edges are degenerate.
    pub fn new(center: Vec3A, u: Vec3A, v: Vec3A, radiance: Vec3A, samples: u32) -> Option<Self> {
        let normal = u.cross(v).try_normalize()?;
        Some(Self {
            center,
            u,
            v,
            normal,
            radiance,
            samples: samples.max(1),
        })
    }

    /// Point on the rectangle for `s ∈ [0,1)²`.
    #[inline]
    pub fn point(&self, s: Vec2) -> Vec3A {
        self.center + self.u * (s.x - 0.5) + self.v * (s.y - 0.5)
    }

    /// Area of the rectangle.
    pub fn area(&self) -> f32 {
        self.u.cross(self.v).length()
    }

    /// Total emitted power `π · A · L` (cosine-weighted hemisphere).
    pub fn power(&self) -> Vec3A {
        self.radiance * (std::f32::consts::PI * self.area())
    }
}

impl Light {
    /// Total emitted power (W per channel) of a point or area light. An
    /// environment's power depends on the scene it surrounds: 0 here (see
    /// `integrator::lights` for the power used to sample it).
    pub fn power(&self) -> Vec3A {
        match self {
            Light::Point { intensity, .. } => *intensity * (4.0 * std::f32::consts::PI),
            Light::Area(a) => a.power(),
            Light::Environment { .. } => Vec3A::ZERO,
        }
    }

    /// The photon pass emits from this light (point and area lights; an
    /// environment lights the scene without photons).
    pub fn emits_photons(&self) -> bool {
        !matches!(self, Light::Environment { .. })
    }
}
