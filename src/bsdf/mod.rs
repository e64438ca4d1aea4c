//! Light scattering at surfaces, shared by the camera paths of every
//! integrator and by the photon tracer, so that both see the same surfaces.
//!
//! [`specular`]: perfect reflection, Snell refraction and Fresnel
//! reflectance at smooth interfaces.

pub mod specular;

pub use specular::{fresnel_schlick, reflect, refract, DielectricInterface};
