//! Measurements over the renderer's components: [`crosscheck`], which casts
//! seeded rays through two accelerators and reports where they disagree,
//! [`rays`], seeded ray
//! sets and their timed queries, [`mod@bench`], `caustic bench`, [`converge`],
//! run time against error over increasing budgets (with its log-log
//! [`plot`]), and [`stress`], the numerical stress cases (`caustic stress`).

pub mod bench;
pub mod converge;
pub mod crosscheck;
pub mod plot;
pub mod rays;
pub mod stress;
