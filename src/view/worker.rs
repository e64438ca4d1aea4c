//! The viewer's render thread: takes the latest [`ViewRequest`], renders it
//! in passes with the same render core as `caustic render`
//! ([`integrator::render()`] with its cached map), and sends each finished pass back
//! as a [`Frame`]. Rendering never runs on the UI thread.
//!
//! What a request does not need is skipped: the accelerator is rebuilt only
//! when the geometry or the accelerator kind changes, the photon pass only
//! when its inputs change (see [`super::edit::same_photons`]). A new request
//! cancels the running pass at once (each request has its own cancel flag,
//! checked before every pixel) and restarts from an empty accumulation, so
//! no image ever holds samples of two scene versions; frames carry their
//! request's generation and the UI drops stale ones.
//!
//! Denoising ([`RenderWorker::request_denoise`]) also runs on this thread,
//! between two passes (only the newest request is served), so the window
//! never waits for it.

use crate::accel::{self, kdtree::KdTreeAccel, Accel, AccelKind, AccelOptions};
use crate::film::denoise::{self, DenoiseQuality, Guides};
use crate::film::{Accumulation, Film};
use crate::integrator::photon::PhotonMap;
use crate::integrator::plan::PhotonPlan;
use crate::integrator::{self, RenderControl, RenderPlan};
use crate::math::Aabb;
use crate::scene::{Light, LoadedScene, Scene};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The first pass's image is this many times smaller on each side.
pub const PREVIEW_DIVISOR: u32 = 4;

/// One version of the scene to render.
#[derive(Clone)]
pub struct ViewRequest {
    /// Increases with every change; frames carry it.
    pub generation: u64,
    /// The scene and its final settings (the viewer's image size).
    pub scene: Arc<LoadedScene>,
    /// Accelerator.
    pub accel: AccelKind,
    /// How it is built.
    pub accel_options: AccelOptions,
    /// Changes when the geometry changes (another scene file): the
    /// accelerator is rebuilt.
    pub geometry: u64,
    /// Changes when the photon pass's inputs change: it is re-run.
    pub photons: u64,
    /// Start with a cheap pass (a quarter of the resolution, one shadow ray
    /// per area light, no photon gather) before the full passes.
    pub preview: bool,
    /// Set by [`RenderWorker::submit`] when a newer request replaces this one.
    pub cancel: Arc<AtomicBool>,
}

/// One finished pass.
#[derive(Clone)]
pub struct Frame {
    /// The request's generation.
    pub generation: u64,
    /// The linear image (the mean of each pixel's samples).
    pub film: Arc<Film>,
    /// The cheap first pass (smaller than the view).
    pub preview: bool,
    /// Samples per pixel in the image.
    pub spp: u32,
    /// Passes of this request so far (the preview counts).
    pub pass: u32,
    /// Rays per second of this pass, in millions.
    pub mrays_per_second: f64,
    /// Time of this pass.
    pub pass_time: Duration,
    /// Time since the request was submitted.
    pub since_request: Duration,
    /// Every pixel has the target samples.
    pub complete: bool,
    /// Accelerators the render thread has built so far.
    pub accel_builds: u32,
    /// Photon passes the render thread has run so far.
    pub photon_passes: u32,
    /// The albedo and normal images of the pass (for the denoiser; none
    /// for the preview).
    pub guides: Option<Arc<(Film, Film)>>,
}

/// What the worker reports.
pub enum WorkerEvent {
    /// A pass finished.
    Frame(Frame),
    /// The photon map of a request, once traced (or reused).
    Photons {
        /// The request's generation.
        generation: u64,
        /// The map, when the plan runs the photon pass.
        map: Option<Arc<PhotonMap>>,
    },
    /// The KD-tree's node boxes with their depths, for the `k` overlay.
    KdBoxes {
        /// The geometry version they belong to.
        geometry: u64,
        /// Deepest level included.
        depth: u32,
        /// Boxes and depths.
        boxes: NodeBoxes,
    },
    /// A frame denoised (answer to [`RenderWorker::request_denoise`]).
    Denoised {
        /// The frame's generation.
        generation: u64,
        /// The frame's pass.
        pass: u32,
        /// The denoised image.
        film: Arc<Film>,
        /// Time the filter took.
        time: Duration,
    },
    /// What the worker is doing (building the accelerator, tracing photons).
    Status(String),
    /// A request could not be rendered.
    Error(String),
}

enum Command {
    Render(Box<ViewRequest>, Instant),
    KdBoxes {
        geometry: u64,
        scene: Arc<LoadedScene>,
        depth: u32,
    },
    Denoise(Box<Frame>),
    Quit,
}

/// The render thread and its channels.
pub struct RenderWorker {
    commands: Sender<Command>,
    events: Receiver<WorkerEvent>,
    current: Option<Arc<AtomicBool>>,
    thread: Option<JoinHandle<()>>,
}

impl RenderWorker {
    /// Starts the thread; `wake` is called after every event (the window's
    /// repaint request).
    pub fn spawn(wake: impl Fn() + Send + 'static) -> Self {
        let (commands, command_rx) = mpsc::channel();
        let (event_tx, events) = mpsc::channel();
        let thread = std::thread::Builder::new()
            .name("caustic-view-render".into())
            .spawn(move || {
                let mut state = WorkerState::default();
                state.run(command_rx, &|e| {
                    // The UI may be gone; nothing to report to then.
                    let _ = event_tx.send(e);
                    wake();
                });
            })
            .expect("spawn the render thread");
        Self {
            commands,
            events,
            current: None,
            thread: Some(thread),
        }
    }

    /// Replaces the running request with `request` (cancelling it at once).
    pub fn submit(&mut self, request: ViewRequest) {
        if let Some(c) = self.current.replace(request.cancel.clone()) {
            c.store(true, Ordering::Relaxed);
        }
        let _ = self.commands.send(Command::Render(Box::new(request), Instant::now()));
    }

    /// Asks for the KD-tree boxes of `scene` down to `depth` (built on the
    /// render thread; answered with [`WorkerEvent::KdBoxes`]).
    pub fn request_kd_boxes(&self, geometry: u64, scene: Arc<LoadedScene>, depth: u32) {
        let _ = self.commands.send(Command::KdBoxes { geometry, scene, depth });
    }

    /// Asks for `frame` denoised (answered with [`WorkerEvent::Denoised`],
    /// or an error; only the newest request waiting is served).
    pub fn request_denoise(&self, frame: Frame) {
        let _ = self.commands.send(Command::Denoise(Box::new(frame)));
    }

    /// The events that arrived since the last call.
    pub fn poll(&self) -> Vec<WorkerEvent> {
        self.events.try_iter().collect()
    }

    /// Waits up to `timeout` for the next event.
    pub fn wait(&self, timeout: Duration) -> Option<WorkerEvent> {
        self.events.recv_timeout(timeout).ok()
    }
}

impl Drop for RenderWorker {
    fn drop(&mut self) {
        if let Some(c) = &self.current {
            c.store(true, Ordering::Relaxed);
        }
        let _ = self.commands.send(Command::Quit);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// What a photon map was traced for: geometry version, accelerator,
/// photon-input version.
type PhotonKey = (u64, AccelKind, u64);

/// KD-tree node boxes with their depths.
pub type NodeBoxes = Arc<Vec<(Aabb, u32)>>;

#[derive(Default)]
struct WorkerState {
    /// (geometry version, kind) and the accelerator built for them.
    accel: Option<((u64, AccelKind), Box<dyn Accel>)>,
    /// (geometry, kind, photon version) and the map traced for them.
    photons: Option<(PhotonKey, Option<Arc<PhotonMap>>)>,
    /// The KD-tree of a geometry version, for the box overlay.
    kdtree: Option<(u64, KdTreeAccel)>,
    /// Commands received and not yet served.
    queue: VecDeque<Command>,
    accel_builds: u32,
    photon_passes: u32,
}

/// The sample count a pass brings every pixel to: 1 first, then doubling
/// up to 16 more per pass (the render core's own pass sizes).
fn next_target(level: u32, spp: u32) -> u32 {
    if level == 0 {
        1.min(spp)
    } else {
        level
            .saturating_add(level.min(integrator::render::MAX_PASS_SAMPLES))
            .min(spp)
    }
}

/// The cheap first pass's scene: smaller image, one shadow ray per area
/// light (the photon gather is left out by the caller).
fn preview_scene(loaded: &LoadedScene) -> LoadedScene {
    let mut s = loaded.clone();
    s.settings.width = (loaded.settings.width / PREVIEW_DIVISOR).max(1);
    s.settings.height = (loaded.settings.height / PREVIEW_DIVISOR).max(1);
    s.settings.noise_threshold = None;
    for light in &mut s.scene.lights {
        if let Light::Area(a) = light {
            a.samples = 1;
        }
    }
    s
}

impl WorkerState {
    fn run(&mut self, commands: Receiver<Command>, send: &dyn Fn(WorkerEvent)) {
        loop {
            if self.queue.is_empty() {
                match commands.recv() {
                    Ok(c) => self.queue.push_back(c),
                    Err(_) => return,
                }
            }
            self.queue.extend(commands.try_iter());
            if self.queue.iter().any(|c| matches!(c, Command::Quit)) {
                return;
            }
            self.serve_box_requests(send);
            // Only the newest render request matters (the others are
            // cancelled already).
            let Some(Command::Render(request, submitted)) = self.queue.pop_back() else {
                continue;
            };
            self.queue.clear();
            self.render(&request, submitted, &commands, send);
        }
    }

    /// Answers the box requests and the newest denoise request waiting.
    fn serve_box_requests(&mut self, send: &dyn Fn(WorkerEvent)) {
        let mut rest = VecDeque::new();
        let mut denoise = None;
        while let Some(c) = self.queue.pop_front() {
            match c {
                Command::KdBoxes { geometry, scene, depth } => self.kd_boxes(geometry, &scene.scene, depth, send),
                Command::Denoise(frame) => denoise = Some(frame),
                other => rest.push_back(other),
            }
        }
        self.queue = rest;
        if let Some(frame) = denoise {
            denoise_frame(&frame, send);
        }
    }

    fn kd_boxes(&mut self, geometry: u64, scene: &Scene, depth: u32, send: &dyn Fn(WorkerEvent)) {
        if self.kdtree.as_ref().is_none_or(|(g, _)| *g != geometry) {
            send(WorkerEvent::Status("building the KD-tree for the box view".into()));
            self.kdtree = Some((geometry, KdTreeAccel::build(scene, &AccelOptions::default())));
        }
        let (_, tree) = self.kdtree.as_ref().expect("built above");
        send(WorkerEvent::KdBoxes {
            geometry,
            depth,
            boxes: Arc::new(tree.node_boxes(depth)),
        });
    }

    /// Renders `request` pass after pass until it is complete or replaced
    /// (box requests are answered between passes).
    fn render(
        &mut self,
        request: &ViewRequest,
        submitted: Instant,
        commands: &Receiver<Command>,
        send: &dyn Fn(WorkerEvent),
    ) {
        let cancelled = || request.cancel.load(Ordering::Relaxed);
        let LoadedScene { scene, settings } = &*request.scene;
        let key = (request.geometry, request.accel);
        if self.accel.as_ref().is_none_or(|(k, _)| *k != key) {
            self.accel = None;
            send(WorkerEvent::Status(format!(
                "building the {} accelerator",
                request.accel.name()
            )));
            match accel::build(scene, request.accel, &request.accel_options) {
                Ok(a) => {
                    self.accel = Some((key, a));
                    self.accel_builds += 1;
                }
                Err(e) => {
                    send(WorkerEvent::Error(e.to_string()));
                    return;
                }
            }
        }
        let mut pass = 0;
        if request.preview && !cancelled() {
            let accel = &*self.accel.as_ref().expect("built above").1;
            let preview = preview_scene(&request.scene);
            let mut plan = RenderPlan::new(&preview.scene, &preview.settings);
            plan.photons = PhotonPlan::CountZero;
            let start = Accumulation::new(plan.width, plan.height);
            if let Some((mut frame, _)) =
                run_pass(&preview.scene, accel, &plan, None, start, 1, request, submitted, pass)
            {
                pass += 1;
                (frame.accel_builds, frame.photon_passes) = (self.accel_builds, self.photon_passes);
                send(WorkerEvent::Frame(frame));
            }
        }
        let mut plan = RenderPlan::new(scene, settings);
        plan.keep_photon_positions = true;
        // The denoise toggle may be switched on at any pass.
        plan.aovs = true;
        let photon_key = (request.geometry, request.accel, request.photons);
        if self.photons.as_ref().is_none_or(|(k, _)| *k != photon_key) {
            if cancelled() {
                return;
            }
            if matches!(plan.photons, PhotonPlan::Run { .. }) {
                send(WorkerEvent::Status("tracing photons".into()));
            }
            // The photon pass is not cancellable; it runs once per change
            // of its inputs.
            let accel = &*self.accel.as_ref().expect("built above").1;
            let map = integrator::render::photon_pass_for(scene, accel, &plan).map(|(m, _)| Arc::new(m));
            self.photons = Some((photon_key, map));
            self.photon_passes += 1;
        }
        let map = self.photons.as_ref().expect("traced above").1.clone();
        send(WorkerEvent::Photons {
            generation: request.generation,
            map: map.clone(),
        });
        let mut acc = Accumulation::new(plan.width, plan.height);
        let mut level = 0;
        loop {
            self.queue.extend(commands.try_iter());
            self.serve_box_requests(send);
            if cancelled() || !self.queue.is_empty() {
                return;
            }
            let target = next_target(level, plan.spp.max(1));
            let accel = &*self.accel.as_ref().expect("built above").1;
            let Some((mut frame, next)) = run_pass(
                scene,
                accel,
                &plan,
                map.as_deref(),
                acc,
                target,
                request,
                submitted,
                pass,
            ) else {
                return;
            };
            pass += 1;
            (frame.accel_builds, frame.photon_passes) = (self.accel_builds, self.photon_passes);
            let complete = frame.complete;
            send(WorkerEvent::Frame(frame));
            if complete {
                return;
            }
            acc = next;
            level = target;
        }
    }
}

/// Renders one pass to `target` samples per pixel; `None` when cancelled.
#[allow(clippy::too_many_arguments)]
fn run_pass(
    scene: &Scene,
    accel: &dyn Accel,
    plan: &RenderPlan,
    map: Option<&PhotonMap>,
    start: Accumulation,
    target: u32,
    request: &ViewRequest,
    submitted: Instant,
    pass: u32,
) -> Option<(Frame, Accumulation)> {
    let control = RenderControl {
        cancel: Some(&request.cancel),
        sample_limit: Some(target),
        checkpoint: None,
        deadline: None,
        progress: &|_, _| {},
    };
    let setup = integrator::RenderSetup::default()
        .continuing(start)
        .photons(integrator::PhotonInput::Map(map))
        .control(control);
    let out = integrator::render(scene, accel, plan, setup);
    if request.cancel.load(Ordering::Relaxed) {
        return None;
    }
    let frame = Frame {
        generation: request.generation,
        film: Arc::new(out.film),
        preview: plan.width != request.scene.settings.width || plan.height != request.scene.settings.height,
        spp: out.accumulation.taken_range().0,
        pass: pass + 1,
        mrays_per_second: out.stats.mrays_per_second(),
        pass_time: out.stats.wall_time,
        since_request: submitted.elapsed(),
        complete: out.complete,
        accel_builds: 0,
        photon_passes: 0,
        guides: None,
    };
    let frame = Frame {
        guides: (!frame.preview).then(|| {
            let acc = &out.accumulation;
            Arc::new((acc.albedo_film(), acc.normal_film()))
        }),
        ..frame
    };
    Some((frame, out.accumulation))
}

/// Denoises `frame` (fast quality: a preview) and sends the result.
fn denoise_frame(frame: &Frame, send: &dyn Fn(WorkerEvent)) {
    let guides = frame
        .guides
        .as_deref()
        .map(|(albedo, normal)| Guides { albedo, normal });
    match denoise::denoise(&frame.film, guides, DenoiseQuality::Fast) {
        Ok((film, stats)) => send(WorkerEvent::Denoised {
            generation: frame.generation,
            pass: frame.pass,
            film: Arc::new(film),
            time: stats.time,
        }),
        Err(e) => send(WorkerEvent::Error(e.to_string())),
    }
}
