//! caustic: a CPU renderer. Whitted ray tracing with Phong / Blinn-Phong
//! shading, soft shadows, Fresnel refraction and photon-mapped caustics, over
//! two interchangeable two-level accelerators (Intel Embree 4 and an in-house
//! SAH KD-tree).
//!
//! Data flows one way: scene file → [`scene::desc`] (serde) → [`scene::Scene`]
//! (validated, immutable) → [`accel::build`] → [`integrator`] fills a
//! [`film::Film`] → tone mapping → PNG / EXR.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod accel;
pub mod analysis;
pub mod bsdf;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod io;
pub mod job;
pub mod limits;
pub mod math;
pub mod memory;
pub mod scene;
pub mod texture;
pub mod view;
