//! Measurements over the renderer's components. For now: [`crosscheck`],
//! which casts seeded rays through two accelerators and reports where they
//! disagree.

pub mod crosscheck;
