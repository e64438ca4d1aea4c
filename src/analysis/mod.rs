//! Measurements over the renderer's components: [`crosscheck`], which casts
//! seeded rays through two accelerators and reports where they disagree,
//! [`converge`], run time against error over increasing budgets (with its
//! log-log [`plot`]), and [`memory`], the process's peak memory for reports.

pub mod converge;
pub mod crosscheck;
pub mod memory;
pub mod plot;
