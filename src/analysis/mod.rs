//! Measurements over the renderer's components: [`crosscheck`], which casts
//! seeded rays through two accelerators and reports where they disagree,
//! [`memory`], the process's peak memory for reports, [`rays`], seeded ray
//! sets and their timed queries, and [`bench`], `caustic bench`.

pub mod bench;
pub mod crosscheck;
pub mod memory;
pub mod rays;
