//! caustic: a CPU renderer. Whitted ray tracing (Phong / Blinn-Phong,
//! soft shadows, Fresnel refraction) with photon-mapped caustics, and
//! physically based path tracing (next-event estimation with MIS,
//! microfacet metals, glass and plastic, a homogeneous medium), with
//! progressive photon mapping, Sobol and adaptive sampling and Open Image
//! Denoise, over interchangeable two-level accelerators: Intel Embree 4 and
//! an in-house SAH KD-tree (and a brute-force oracle).
//!
//! Data flows one way: scene file → [`scene::desc`] (serde) → [`scene::Scene`]
//! (validated) → [`accel::build`] → [`integrator`] fills a [`film::Film`] →
//! tone mapping → PNG / EXR. ARCHITECTURE.md gives the layers.
//!
//! # Rendering a scene
//!
//! Parse a scene (or [`scene::load_scene`] a file), build an accelerator,
//! render, write:
//!
//! ```
//! use caustic::accel::{self, AccelKind, AccelOptions};
//! use caustic::film;
//! use caustic::integrator::{self, RenderPlan};
//! use std::path::Path;
//!
//! let text = r#"
//!     render = { width = 32, height = 24, spp = 2 }
//!     camera = { position = [0, 1.5, 4], look_at = [0, 0.5, 0] }
//!     materials.white = {}
//!     lights = [{ type = "point", position = [2, 4, 3], intensity = 20 }]
//!     objects = [{ type = "sphere", center = [0, 0.5, 0], radius = 0.5, material = "white" }]
//! "#;
//! let caustic::scene::LoadedScene { scene, settings } = caustic::scene::parse_scene(text, Path::new("first.toml"))?;
//! let accel = accel::build(&scene, AccelKind::KdTree, &AccelOptions::default())?;
//! let plan = RenderPlan::new(&scene, &settings);
//! let out = integrator::render(&scene, accel.as_ref(), &plan, integrator::RenderSetup::default());
//! assert!(out.complete);
//! assert!(out.film.mean().x > 0.0, "the lit sphere shows");
//!
//! let dir = tempfile::tempdir()?;
//! film::write_png(&dir.path().join("first.png"), &out.film, &settings.output)?;
//! film::write_exr(&dir.path().join("first.exr"), &out.film)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! [`job::RenderJob`] does the same from a file with what `caustic render`
//! adds: overrides, checkpoints and resume, shards, denoising, atomic
//! outputs.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod accel;
pub mod analysis;
pub mod bsdf;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod io;
pub mod job;
pub mod limits;
pub mod math;
pub mod memory;
pub mod scene;
pub mod texture;
pub mod view;
