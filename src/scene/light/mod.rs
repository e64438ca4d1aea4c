//! Light sources, physically based so that direct light and photon power
//! agree: the kinds a scene lists ([`Light`]: point, spot, directional,
//! rectangle, environment) and the surfaces whose material emits. Every
//! integrator reaches both through one interface, [`Emitter`]
//! (`sample_li`, `pdf_li`, `le`, photon emission and `power`), one module
//! per kind.

mod emitter;
mod environment;
mod shape;
mod spot;

pub use emitter::{bounding_sphere, EmissionOrigin, Emitter, LightSample};
pub use environment::EnvironmentMap;
pub use shape::ShapeEmitter;
pub use spot::{SpotFalloff, SpotLight};

use crate::math::{Vec2, Vec3A};
use std::sync::Arc;

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
    /// A point light whose intensity falls off inside a cone (Mitsuba's `spot`).
    Spot(SpotLight),
    /// Light arriving along one direction from infinitely far (a sun):
    /// irradiance `irradiance` (W/m² per channel) on a surface facing it.
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3A,
        /// Colour × intensity: the irradiance perpendicular to `direction`.
        irradiance: Vec3A,
    },
    /// One-sided rectangle emitting radiance `radiance` from the side of
    /// `normal = normalize(u × v)`.
    Area(AreaLight),
    /// Radiance arriving from every direction, infinitely far: constant,
    /// or a latitude-longitude image times `radiance`.
    Environment {
        /// Colour × intensity (W/m²/sr per channel); the map's scale.
        radiance: Vec3A,
        /// The image, when the environment is not constant.
        map: Option<Arc<EnvironmentMap>>,
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
    /// The radiance an environment light sends from direction `dir`.
    #[inline]
    pub fn environment_radiance(radiance: Vec3A, map: &Option<Arc<EnvironmentMap>>, dir: Vec3A) -> Vec3A {
        match map {
            None => radiance,
            Some(m) => radiance * m.eval(dir),
        }
    }

    /// The photon pass emits from this light (every kind but the
    /// environment, which lights the scene without photons).
    pub fn emits_photons(&self) -> bool {
        !matches!(self, Light::Environment { .. })
    }

    /// The kind's name, as `[[lights]] type` spells it.
    pub fn kind_name(&self) -> &'static str {
        match self {
            Light::Point { .. } => "point",
            Light::Spot(_) => "spot",
            Light::Directional { .. } => "directional",
            Light::Area(_) => "area",
            Light::Environment { .. } => "environment",
        }
    }

    /// Where the light is, for the kinds that have a position.
    pub fn position(&self) -> Option<Vec3A> {
        match self {
            Light::Point { position, .. } => Some(*position),
            Light::Spot(s) => Some(s.position),
            Light::Area(a) => Some(a.center),
            Light::Directional { .. } | Light::Environment { .. } => None,
        }
    }

    /// True for a light no ray can hit (point, spot, directional): only
    /// light sampling finds it.
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point { .. } | Light::Spot(_) | Light::Directional { .. })
    }
}
