//! `caustic view`: the interactive renderer. An editable scene
//! ([`edit`]), an orbit camera ([`orbit`]), a render thread running the
//! same render core as `caustic render` ([`worker`]), the state that ties
//! them together without any windowing ([`ViewerCore`], testable headless),
//! the interaction latency benchmark ([`latency`]) and, with the `viewer`
//! feature, the egui window (`app`).

#[cfg(feature = "viewer")]
pub mod app;
pub mod edit;
pub mod latency;
pub mod orbit;
pub mod overlay;
pub mod worker;

pub use edit::{same_photons, EditableScene, LightEdit};
pub use orbit::Orbit;
pub use worker::{Frame, NodeBoxes, RenderWorker, ViewRequest, WorkerEvent};

use crate::accel::{AccelKind, AccelOptions};
use crate::film::Film;
use crate::integrator::photon::PhotonMap;
use crate::scene::LoadedScene;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// With denoising on, the image is denoised after this many passes (and
/// after the last one).
pub const DENOISE_EVERY_PASSES: u32 = 4;

/// The viewer's default image size.
pub const DEFAULT_SIZE: (u32, u32) = (960, 540);

/// The viewer without its window: the scene being edited, the render
/// thread, and what it sent back. The window's panel edits
/// [`ViewerCore::edit`] and calls [`ViewerCore::sync`] once per frame.
pub struct ViewerCore {
    /// The scene being edited.
    pub edit: EditableScene,
    /// Accelerator of the next request.
    pub accel: AccelKind,
    /// How accelerators are built.
    pub accel_options: AccelOptions,
    /// Image size.
    pub size: (u32, u32),
    /// Start each change with a cheap preview pass.
    pub preview: bool,
    /// The newest frame of the current generation.
    pub frame: Option<Frame>,
    /// The current scene's photon map (for the `p` overlay).
    pub photon_map: Option<Arc<PhotonMap>>,
    /// KD-tree boxes of the current geometry, with the depth asked for.
    pub kd_boxes: Option<(u32, NodeBoxes)>,
    /// What the render thread is doing, or its last error.
    pub status: String,
    /// Show the image denoised (Open Image Denoise, on the render thread
    /// every [`DENOISE_EVERY_PASSES`] passes and at the last).
    pub denoise: bool,
    /// The newest denoised frame: generation, pass, image, filter time.
    pub denoised: Option<(u64, u32, Arc<Film>, Duration)>,
    denoise_asked: Option<(u64, u32)>,
    /// Time from the last change to its first image.
    pub last_latency: Option<Duration>,
    worker: RenderWorker,
    generation: u64,
    geometry: u64,
    photons: u64,
    submitted: Option<(Arc<LoadedScene>, AccelKind)>,
    changed_at: Option<Instant>,
    kd_asked: Option<u32>,
}

impl ViewerCore {
    /// A viewer of `edit` at `size`; `wake` is called from the render
    /// thread when it has something new (the window's repaint request).
    pub fn new(edit: EditableScene, size: (u32, u32), accel: AccelKind, wake: impl Fn() + Send + 'static) -> Self {
        let mut core = Self {
            edit,
            accel,
            accel_options: AccelOptions::default(),
            size,
            preview: true,
            frame: None,
            photon_map: None,
            kd_boxes: None,
            status: String::new(),
            denoise: false,
            denoised: None,
            denoise_asked: None,
            last_latency: None,
            worker: RenderWorker::spawn(wake),
            generation: 0,
            geometry: 0,
            photons: 0,
            submitted: None,
            changed_at: None,
            kd_asked: None,
        };
        core.prepare_scene();
        core
    }

    fn prepare_scene(&mut self) {
        let s = &mut self.edit.settings;
        (s.width, s.height) = self.size;
        self.edit.apply();
    }

    /// Replaces the scene (another file): the accelerator and the photon
    /// map are rebuilt.
    pub fn replace_scene(&mut self, edit: EditableScene) {
        self.edit = edit;
        self.geometry += 1;
        self.kd_boxes = None;
        self.kd_asked = None;
        self.photon_map = None;
        self.prepare_scene();
    }

    /// Counts the photon passes asked for (their inputs changed).
    pub fn photon_version(&self) -> u64 {
        self.photons
    }

    /// The generation of the newest request.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The scene the newest request renders.
    pub fn submitted_scene(&self) -> Option<&Arc<LoadedScene>> {
        self.submitted.as_ref().map(|(s, _)| s)
    }

    /// Applies the edits and, when the scene or the accelerator differ from
    /// the last request, sends a new one (cancelling the running pass).
    /// Returns whether it did.
    pub fn sync(&mut self) -> bool {
        self.prepare_scene();
        let edited = self.edit.snapshot();
        let unchanged = self
            .submitted
            .as_ref()
            .is_some_and(|(s, a)| *a == self.accel && scenes_equal(s, &edited));
        if unchanged {
            return false;
        }
        let same_map = self
            .submitted
            .as_ref()
            .is_some_and(|(s, a)| *a == self.accel && same_photons(s, &edited));
        if !same_map {
            self.photons += 1;
        }
        self.generation += 1;
        let scene = Arc::new(edited);
        self.submitted = Some((scene.clone(), self.accel));
        self.changed_at = Some(Instant::now());
        self.worker.submit(ViewRequest {
            generation: self.generation,
            scene,
            accel: self.accel,
            accel_options: self.accel_options.clone(),
            geometry: self.geometry,
            photons: self.photons,
            preview: self.preview,
            cancel: Arc::new(AtomicBool::new(false)),
        });
        true
    }

    /// Asks for the KD-tree boxes down to `depth` unless they are there or
    /// asked for already.
    pub fn want_kd_boxes(&mut self, depth: u32) {
        let have = self.kd_boxes.as_ref().is_some_and(|(d, _)| *d == depth);
        if !have && self.kd_asked != Some(depth) {
            self.kd_asked = Some(depth);
            // Any version of the current geometry will do: the last request's.
            let scene = match &self.submitted {
                Some((s, _)) => s.clone(),
                None => Arc::new(self.edit.snapshot()),
            };
            self.worker.request_kd_boxes(self.geometry, scene, depth);
        }
    }

    /// Takes what the render thread sent; returns whether the image changed.
    /// Frames of older generations are dropped.
    pub fn poll(&mut self) -> bool {
        let events = self.worker.poll();
        self.take(events)
    }

    /// Like [`Self::poll`], waiting up to `timeout` for the first event.
    pub fn wait(&mut self, timeout: Duration) -> bool {
        let mut events: Vec<WorkerEvent> = self.worker.wait(timeout).into_iter().collect();
        events.extend(self.worker.poll());
        self.take(events)
    }

    fn take(&mut self, events: Vec<WorkerEvent>) -> bool {
        let mut new_image = false;
        for e in events {
            match e {
                WorkerEvent::Frame(f) if f.generation == self.generation => {
                    if let Some(t) = self.changed_at.take() {
                        self.last_latency = Some(t.elapsed());
                    }
                    self.status.clear();
                    self.frame = Some(f);
                    new_image = true;
                }
                WorkerEvent::Frame(_) => {}
                WorkerEvent::Photons { generation, map } if generation == self.generation => self.photon_map = map,
                WorkerEvent::Photons { .. } => {}
                WorkerEvent::KdBoxes { geometry, depth, boxes } if geometry == self.geometry => {
                    self.status.clear();
                    self.kd_boxes = Some((depth, boxes));
                }
                WorkerEvent::KdBoxes { .. } => {}
                WorkerEvent::Denoised {
                    generation,
                    pass,
                    film,
                    time,
                } if generation == self.generation => {
                    self.denoised = Some((generation, pass, film, time));
                    new_image |= self.denoise;
                }
                WorkerEvent::Denoised { .. } => {}
                WorkerEvent::Status(s) => self.status = s,
                WorkerEvent::Error(e) => self.status = format!("error: {e}"),
            }
        }
        self.ask_denoise();
        new_image
    }

    /// With denoising on, asks the render thread to denoise the current
    /// frame once [`DENOISE_EVERY_PASSES`] passes have gone by since the
    /// last one asked for (at once for a new scene version, and for the
    /// last pass).
    fn ask_denoise(&mut self) {
        let Some(f) = self
            .frame
            .as_ref()
            .filter(|f| f.generation == self.generation && f.guides.is_some())
        else {
            return;
        };
        if !self.denoise || !crate::film::denoise::available() {
            return;
        }
        let due = match self.denoise_asked {
            Some((g, p)) if g == f.generation => f.pass >= p + DENOISE_EVERY_PASSES || (f.complete && f.pass != p),
            _ => true,
        };
        if due {
            self.denoise_asked = Some((f.generation, f.pass));
            self.worker.request_denoise(f.clone());
        }
    }

    /// The image to show: the newest denoised one of the current scene
    /// version when denoising is on and there is one, else the newest frame.
    pub fn shown_film(&self) -> Option<&Arc<Film>> {
        let denoised = self
            .denoised
            .as_ref()
            .filter(|d| self.denoise && d.0 == self.generation)
            .map(|d| &d.2);
        denoised.or(self.frame.as_ref().map(|f| &f.film))
    }

    /// Waits until the current generation's image has `spp` samples per
    /// pixel (or is complete), up to `timeout`; for tests and benchmarks.
    pub fn wait_for_spp(&mut self, spp: u32, timeout: Duration) -> bool {
        let end = Instant::now() + timeout;
        loop {
            let done = self
                .frame
                .as_ref()
                .is_some_and(|f| f.generation == self.generation && !f.preview && (f.spp >= spp || f.complete));
            if done {
                return true;
            }
            let now = Instant::now();
            if now >= end {
                return false;
            }
            self.wait(end - now);
        }
    }
}

/// Scene equality as far as rendering goes (meshes are shared, compared by
/// identity).
fn scenes_equal(a: &LoadedScene, b: &LoadedScene) -> bool {
    let settings_equal = a.settings == b.settings;
    let (a, b) = (&a.scene, &b.scene);
    settings_equal
        && a.ambient == b.ambient
        && a.water_medium == b.water_medium
        && a.media == b.media
        && a.camera == b.camera
        && a.materials == b.materials
        && a.lights == b.lights
        && a.objects == b.objects
        && a.meshes.len() == b.meshes.len()
        && a.meshes.iter().zip(&b.meshes).all(|(x, y)| Arc::ptr_eq(x, y))
}
