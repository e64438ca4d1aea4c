//! Integrators: the render plan, the photon pass (caustics), fog, the
//! [`Integrator`] interface (one pixel sample's radiance) and its Whitted,
//! path and volumetric path tracers, light sampling, the progressive
//! deterministic render loop ([`render()`], the one way in) and the debug
//! overlays.

pub mod aov;
pub mod debug;
pub mod fog;
pub mod lights;
pub mod lint;
pub mod medium;
pub mod path;
pub mod photon;
pub mod plan;
pub mod render;
pub mod sample;
pub mod volpath;
pub mod whitted;

pub use plan::RenderPlan;
pub use render::{
    photon_map_from, planned_photons, render, CheckpointHook, PhotonInput, RenderControl, RenderOutput, RenderSetup,
    RenderStats,
};
pub use sample::{Integrator, RayCounts, SampleContext};
pub use whitted::Whitted;
