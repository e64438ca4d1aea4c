//! Helpers shared by the integration tests: the command-line runner
//! ([`cli`]), scenes built in code and the test scene files ([`scenes`]),
//! the image metrics ([`metrics`]), and a scene rendered in memory
//! ([`render`]). Each test binary uses its own part.
#![allow(dead_code)]

pub mod cli;
pub mod images;
pub mod metrics;
pub mod mitsuba;
pub mod render;
pub mod same;
pub mod scenes;
