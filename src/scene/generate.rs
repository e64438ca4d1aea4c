//! Procedural meshes.
