//! Long renders: stopping on Ctrl-C and resuming from a checkpoint.
//!
//! - [`Interrupt`] turns SIGINT / SIGTERM into a cancel flag the render loop
//!   polls before each pixel (`RenderControl::cancel`); a second signal ends
//!   the process at once (exit 128 + signal number), for when the clean stop
//!   itself hangs (a full disk, a photon pass that is not interruptible).
//! - [`fingerprint`] identifies everything that changes the samples, so a
//!   checkpoint is only ever resumed by the same render.
//!
//! What a resume relies on: the film is a pure function of (scene, settings,
//! accelerator, seed) per pixel and sample index (see `integrator::render`),
//! and the photon pass is deterministic for any thread count, so it is
//! simply re-run on resume rather than stored (a 10M-photon map would weigh
//! hundreds of MiB; re-tracing it costs seconds).

use crate::accel::AccelKind;
use crate::scene::{RenderSettings, Scene};
use sha2::{Digest, Sha256};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// The signals that stop a render cleanly.
#[cfg(unix)]
const STOP_SIGNALS: [i32; 2] = [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM];
#[cfg(not(unix))]
const STOP_SIGNALS: [i32; 1] = [signal_hook::consts::SIGINT];

/// A process-wide stop request from SIGINT (Ctrl-C) or SIGTERM.
#[derive(Clone, Debug)]
pub struct Interrupt {
    stop: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
}

impl Interrupt {
    /// Installs the handlers. The first signal sets the flag (and records
    /// which signal it was); a second one, with the flag already set, exits
    /// the process immediately with status 128 + signal number.
    pub fn install() -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let signal = Arc::new(AtomicUsize::new(0));
        for sig in STOP_SIGNALS {
            // Order matters (signal-hook's documented double Ctrl-C pattern):
            // the conditional exit must run before the flag is set, so the
            // first signal only arms it.
            signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&stop))?;
            signal_hook::flag::register_usize(sig, Arc::clone(&signal), sig as usize)?;
            signal_hook::flag::register(sig, Arc::clone(&stop))?;
        }
        Ok(Self { stop, signal })
    }

    /// The cancel flag to hand to `RenderControl::cancel`.
    pub fn flag(&self) -> &AtomicBool {
        &self.stop
    }

    /// Whether a stop was requested.
    pub fn requested(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }

    /// Name of the signal received, if any.
    pub fn signal_name(&self) -> Option<&'static str> {
        match self.signal.load(Ordering::SeqCst) {
            0 => None,
            s => Some(signal_hook::low_level::signal_name(s as i32).unwrap_or("a signal")),
        }
    }

    /// Conventional exit status after a stop: 128 + signal number (130 for
    /// SIGINT).
    pub fn exit_code(&self) -> u8 {
        match self.signal.load(Ordering::SeqCst) {
            0 => 130,
            s => (128 + s).min(255) as u8,
        }
    }
}

/// Hex SHA-256 of everything that decides the samples: the scene (camera,
/// materials, lights, objects, mesh geometry), the render settings except
/// the display-only tone map and exposure, the accelerator and its options
/// (`accel_options`: e.g. Embree's build quality; hits can differ in the
/// last bits between backends), the checkpoint format and the crate
/// version. Thread count is not included: it never changes the image.
pub fn fingerprint(scene: &Scene, accel: AccelKind, accel_options: &str) -> String {
    let mut h = Sha256::new();
    let mut field = |name: &str, bytes: &[u8]| {
        // Length-prefixed so that no two field sequences hash alike.
        h.update((name.len() as u64).to_le_bytes());
        h.update(name.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    field("format", crate::film::checkpoint::CHECKPOINT_FORMAT.as_bytes());
    field("version", env!("CARGO_PKG_VERSION").as_bytes());
    // Debug output of f32 is the shortest text that round-trips, so it
    // identifies values exactly.
    let settings = RenderSettings {
        tone_map: crate::scene::ToneMap::Aces,
        exposure: 0.0,
        ..scene.settings.clone()
    };
    field("settings", format!("{settings:?}").as_bytes());
    field("camera", format!("{:?}", scene.camera).as_bytes());
    field("materials", format!("{:?}", scene.materials).as_bytes());
    field("lights", format!("{:?}", scene.lights).as_bytes());
    field("objects", format!("{:?}", scene.objects).as_bytes());
    for mesh in &scene.meshes {
        // Geometry only: moving or renaming the mesh file does not matter.
        let floats = mesh.positions.iter().chain(&mesh.normals).flat_map(|v| v.to_array());
        let bytes: Vec<u8> = floats.flat_map(f32::to_le_bytes).collect();
        field("mesh vertices", &bytes);
        let bytes: Vec<u8> = mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        field("mesh triangles", &bytes);
    }
    field("accel", format!("{accel:?} {accel_options}").as_bytes());
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/shadow.toml");
        crate::scene::load_scene(&path).unwrap()
    }

    #[test]
    fn fingerprint_sees_what_changes_samples_only() {
        let base = fingerprint(&scene(), AccelKind::KdTree, "");
        assert_eq!(base.len(), 64);
        assert_eq!(base, fingerprint(&scene(), AccelKind::KdTree, ""));
        // Display-only settings do not matter.
        let mut s = scene();
        s.settings.exposure = 2.0;
        s.settings.tone_map = crate::scene::ToneMap::Clamp;
        assert_eq!(base, fingerprint(&s, AccelKind::KdTree, ""));
        // Everything else does.
        let mut s = scene();
        s.settings.seed += 1;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.settings.spp += 1;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.materials[0].diffuse.x += 1.0e-6;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        assert_ne!(base, fingerprint(&scene(), AccelKind::Brute, ""));
        assert_ne!(base, fingerprint(&scene(), AccelKind::KdTree, "robust"));
    }
}
