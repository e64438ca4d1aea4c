//! `caustic photons`: trace a scene's caustic photons once into a file that
//! every shard of a render loads (`--photon-map`) instead of tracing them
//! again, and the check that such a file belongs to a render.

use super::fingerprint::photon_fingerprint;
use super::{JobError, Overrides};
use crate::accel::{self, AccelKind, AccelOptions};
use crate::film;
use crate::integrator::photon::{read_photons, trace_photons, write_photons, PhotonRules, TracedPhotons};
use crate::integrator::{planned_photons, RenderPlan};
use crate::scene::{self, LoadedScene, RenderSettings, Scene};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// What to trace and where to.
#[derive(Clone, Debug)]
pub struct PhotonsRequest {
    /// Scene file.
    pub scene: PathBuf,
    /// Values replacing the scene file's (photons, seed, triangle test…;
    /// the image size and samples do not change the photons).
    pub overrides: Overrides,
    /// Accelerator (`None`: the default); renders loading the file must use
    /// the same one.
    pub accel: Option<AccelKind>,
    /// How the accelerator is built.
    pub accel_options: AccelOptions,
    /// The photon file.
    pub output: PathBuf,
}

/// What `caustic photons` did.
#[derive(Clone, Debug)]
pub struct PhotonsReport {
    /// Photons emitted.
    pub emitted: u64,
    /// Photons stored.
    pub stored: u64,
    /// Rays traced.
    pub rays: u64,
    /// Wall time of the trace.
    pub trace_time: Duration,
    /// Wall time of writing the file.
    pub write_time: Duration,
    /// Size of the file.
    pub bytes: u64,
}

/// Traces the photons of `request`'s scene (on the current rayon pool) and
/// writes them to its output atomically.
pub fn trace_to_file(request: &PhotonsRequest) -> Result<PhotonsReport, JobError> {
    let mut loaded = scene::load_scene_options(&request.scene, &request.overrides.load_options())?;
    request.overrides.apply(&mut loaded, &request.scene)?;
    let LoadedScene { scene, settings } = loaded;
    let accel_kind = request.accel.unwrap_or_else(AccelKind::default_kind);
    let options = AccelOptions {
        triangle_test: settings.triangle_test,
        ..request.accel_options.clone()
    };
    let plan = RenderPlan::new(&scene, &settings);
    if plan.progressive().is_some() {
        return Err(JobError::Invalid(format!(
            "{}: progressive photon mapping ([photons] progressive = true) traces a new map for every sample \
             index during the render: there is no one map to save",
            request.scene.display()
        )));
    }
    if plan.photon_rules == PhotonRules::Physical {
        return Err(JobError::Invalid(format!(
            "{}: photon files hold the Whitted integrator's caustic map; the path integrator's maps \
             ([photons] caustics = \"map\") are traced by the render itself",
            request.scene.display()
        )));
    }
    let Some(count) = planned_photons(&plan) else {
        return Err(JobError::Invalid(format!(
            "{}: this scene's render runs no photon pass (no mirror or glass object, --photons 0, \
             or path tracing): there are no photons to trace",
            request.scene.display()
        )));
    };
    film::check_writable(&request.output)?;
    let accel = accel::build(&scene, accel_kind, &options)?;
    let traced = trace_photons(&scene, plan.photon_trace(), accel.as_ref(), count, true);
    let fingerprint = photon_fingerprint(&scene, &settings, accel_kind, &options.fingerprint_text(accel_kind));
    let begin = Instant::now();
    write_photons(&request.output, &traced, &fingerprint)?;
    let bytes = std::fs::metadata(&request.output).map(|m| m.len()).unwrap_or(0);
    Ok(PhotonsReport {
        emitted: traced.emitted,
        stored: traced.positions.len() as u64,
        rays: traced.rays,
        trace_time: traced.trace_time,
        write_time: begin.elapsed(),
        bytes,
    })
}

/// Reads the photon file `path` for a render of `scene` with `accel`,
/// refusing it unless it holds this render's photons (same fingerprint)
/// and the render runs a photon pass.
pub fn load_for(
    path: &Path,
    scene: &Scene,
    settings: &RenderSettings,
    accel: AccelKind,
    options: &AccelOptions,
) -> Result<TracedPhotons, JobError> {
    let plan = RenderPlan::new(scene, settings);
    if plan.progressive().is_some() {
        return Err(JobError::Invalid(format!(
            "--photon-map {}: progressive photon mapping ([photons] progressive = true, or \
             --progressive-photons) traces a new map for every sample index; it cannot use a photon file",
            path.display()
        )));
    }
    if plan.photon_rules == PhotonRules::Physical {
        return Err(JobError::Invalid(format!(
            "--photon-map {}: photon files hold the Whitted integrator's caustic map; the path \
             integrator's maps ([photons] caustics = \"map\") are traced by the render itself",
            path.display()
        )));
    }
    let Some(planned) = planned_photons(&plan) else {
        return Err(JobError::Invalid(format!(
            "--photon-map {}: this render runs no photon pass (no mirror or glass object, --photons 0, \
             or path tracing)",
            path.display()
        )));
    };
    let (traced, fingerprint) = read_photons(path).map_err(|e| JobError::Invalid(e.to_string()))?;
    if fingerprint != photon_fingerprint(scene, settings, accel, &options.fingerprint_text(accel))
        || traced.emitted != planned
    {
        return Err(JobError::Invalid(format!(
            "{}: photons of another scene or other settings ({} photons in the file, {} here; or the seed, \
             the scene, a mesh or the accelerator differ); trace them again with caustic photons",
            path.display(),
            traced.emitted,
            settings.photons.count
        )));
    }
    Ok(traced)
}
