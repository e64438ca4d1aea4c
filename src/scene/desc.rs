//! The scene file format (serde structs).
