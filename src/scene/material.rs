//! Surface materials: a Phong or Blinn-Phong surface, optionally mixed with a
//! mirror reflection, or a dielectric (glass, water).

use crate::math::Vec3A;

/// Which specular lobe the local model uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingModel {
    /// `(R·V)^n` (Phong 1975).
    Phong,
    /// `(N·H)^n` with the half vector (Blinn 1977).
    BlinnPhong,
}

/// Perfect mirror reflection mixed with the surface colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    /// Fraction of the result taken from the reflected ray, in [0, 1].
    pub reflectivity: f32,
    /// Colour filter on the reflected light.
    pub tint: Vec3A,
}

/// Which Fresnel formula a dielectric uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FresnelModel {
    /// The exact unpolarised reflectance.
    Exact,
    /// Schlick's approximation (the original report's).
    Schlick,
}

/// Dielectric interface (glass, water): Fresnel-weighted reflection and
/// refraction, smooth or rough.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Index of refraction of the inside (the outside is 1).
    pub ior: f32,
    /// Colour filter on transmitted light.
    pub tint: Vec3A,
    /// GGX roughness `alpha` (0: smooth). The Whitted integrator treats
    /// every dielectric as smooth.
    pub roughness: f32,
    /// Fresnel formula; `None`: each integrator's own (Whitted: Schlick,
    /// as in the original report; path: exact).
    pub fresnel: Option<FresnelModel>,
}

impl Dielectric {
    /// A smooth dielectric of index `ior` with a colour filter.
    pub fn smooth(ior: f32, tint: Vec3A) -> Self {
        Self {
            ior,
            tint,
            roughness: 0.0,
            fresnel: None,
        }
    }
}

/// A metal: complex index of refraction `eta + i k` per channel, smooth or
/// rough.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Real part of the index.
    pub eta: Vec3A,
    /// Extinction coefficient.
    pub k: Vec3A,
    /// GGX roughness `alpha` (0: a perfect mirror).
    pub roughness: f32,
}

/// A smooth clear coating over the diffuse albedo (plastic, varnish).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coating {
    /// Index of refraction of the coating.
    pub ior: f32,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name in the scene file.
    pub name: String,
    /// Specular lobe.
    pub model: ShadingModel,
    /// Ambient reflectance (multiplies the scene's ambient light).
    pub ambient: Vec3A,
    /// Diffuse albedo in [0, 1] (Lambertian BRDF `diffuse / π`).
    pub diffuse: Vec3A,
    /// Specular reflectance of the highlight lobe.
    pub specular: Vec3A,
    /// Phong exponent.
    pub shininess: f32,
    /// Optional mirror component.
    pub mirror: Option<Mirror>,
    /// Optional dielectric: the surface then reflects and refracts.
    pub dielectric: Option<Dielectric>,
    /// Optional metal: the surface is then a (rough) conductor.
    pub conductor: Option<Conductor>,
    /// Optional clear coating over the diffuse albedo.
    pub coating: Option<Coating>,
}

impl Material {
    /// A plain diffuse material (used by tests and generated scenes).
    pub fn diffuse(name: &str, albedo: Vec3A) -> Self {
        Self {
            name: name.into(),
            model: ShadingModel::BlinnPhong,
            ambient: albedo,
            diffuse: albedo,
            specular: Vec3A::ZERO,
            shininess: 1.0,
            mirror: None,
            dielectric: None,
            conductor: None,
            coating: None,
        }
    }

    /// True when rays continue through this surface (mirror or dielectric):
    /// such objects cast caustics and need secondary rays.
    pub fn is_specular(&self) -> bool {
        self.dielectric.is_some()
            || self.mirror.is_some_and(|m| m.reflectivity > 0.0)
            || self.conductor.is_some_and(|c| c.roughness == 0.0)
    }

    /// True when the Whitted integrator follows a reflected or refracted ray
    /// from this surface (specular materials and clear coatings).
    pub fn spawns_secondary(&self) -> bool {
        self.is_specular() || self.coating.is_some()
    }

    /// True when the surface has a diffuse part that receives direct light
    /// and photons.
    pub fn is_diffuse(&self) -> bool {
        self.dielectric.is_none()
            && self.conductor.is_none()
            && self.diffuse.max_element() > 0.0
            && self.mirror.is_none_or(|m| m.reflectivity < 1.0)
    }
}
