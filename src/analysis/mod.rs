//! Measurements over the renderer's components: [`crosscheck`], which casts
//! seeded rays through two accelerators and reports where they disagree, and
//! [`memory`], the process's peak memory for reports.

pub mod crosscheck;
pub mod memory;
