//! Film.
