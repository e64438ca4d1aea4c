//! Helpers shared by the integration tests: the command-line runner
//! ([`cli`]), scenes built in code and the test scene files ([`scenes`]),
//! and the image metrics ([`metrics`]). Each test binary uses its own part.
#![allow(dead_code)]

pub mod cli;
pub mod images;
pub mod metrics;
pub mod mitsuba;
pub mod same;
pub mod scenes;
