//! Integrators: the render plan, the photon pass (caustics), fog, the
//! Whitted integrator, the path tracer and its light sampling, the progressive deterministic render loop and the
//! debug overlays.

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
pub mod volpath;
pub mod whitted;

pub use plan::RenderPlan;
pub use render::{
    photon_map_from, planned_photons, render, render_progressive, render_with_control, render_with_photons,
    render_with_traced, CheckpointHook, RenderControl, RenderOutput, RenderStats,
};
pub use whitted::{RayCounts, Whitted};
