//! Measurements over the renderer's components: [`crosscheck`], which casts
//! seeded rays through two accelerators and reports where they disagree,
//! [`memory`], the process's peak memory for reports, and [`stress`], the
//! numerical stress cases (`caustic stress`).

pub mod crosscheck;
pub mod memory;
pub mod stress;
