//! Integrators: the render plan, the Whitted integrator and the tiled,
//! deterministic render loop.

pub mod plan;
pub mod render;
pub mod whitted;

pub use plan::RenderPlan;
pub use render::{render, RenderOutput, RenderStats};
pub use whitted::{RayCounts, Whitted};
