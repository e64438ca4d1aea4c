//! The window (egui through eframe's glow renderer): the control panel of
//! the original report beside the progressive image. Every frame the panel
//! edits [`ViewerCore::edit`] and [`ViewerCore::sync`] sends a new request
//! when something changed; the render thread does the rest.

use super::overlay::{composite, debug_layer, display_rgba};
use super::{EditableScene, ViewerCore, DEFAULT_SIZE};
use crate::accel::{AccelKind, AccelOptions};
use crate::film::{self, Film, OutputSettings, ToneMap};
use crate::math::Vec3A;
use crate::scene::{Camera, IntegratorKind, Light, Mirror, ShadingModel};
use eframe::egui;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver};
use std::sync::Arc;

/// Deepest KD-tree level the box view offers.
pub const MAX_BOX_DEPTH: u32 = 24;

/// How `caustic view` starts.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// Scene file.
    pub scene: PathBuf,
    /// How it is read (`-D`, a glTF model's `--camera`).
    pub load: crate::scene::LoadOptions,
    /// Accelerator.
    pub accel: AccelKind,
    /// Image size.
    pub size: (u32, u32),
    /// How accelerators are built.
    pub accel_options: AccelOptions,
    /// Target samples per pixel instead of the scene's.
    pub spp: Option<u32>,
}

/// The debug views and the display settings (not part of the scene).
#[derive(Clone, Debug, PartialEq)]
pub struct DisplayState {
    /// `p`: the photon cloud over the image.
    pub show_photons: bool,
    /// `k`: the KD-tree's boxes over the image.
    pub show_boxes: bool,
    /// Deepest box level drawn.
    pub box_depth: u32,
    /// Tone curve and exposure of the display.
    pub output: OutputSettings,
}

/// The key of the cached debug layer: redrawn when any of it changes.
#[derive(PartialEq)]
struct LayerKey {
    camera: Camera,
    size: (u32, u32),
    photons: usize,
    boxes: Option<(u32, usize)>,
}

/// What the shown texture was made from: generation, pass, denoised pass,
/// display settings, photon and box views, box depth.
type ShownKey = (u64, u32, Option<u32>, OutputSettings, bool, bool, u32);

/// The viewer application: the core, the display state, and the texture.
pub struct ViewerApp {
    /// Scene, render thread and frames.
    pub core: ViewerCore,
    /// Debug views and tone mapping.
    pub display: DisplayState,
    /// What the last save or load said.
    pub message: String,
    /// Where the image was drawn in the last frame (points).
    pub image_rect: Option<egui::Rect>,
    texture: Option<egui::TextureHandle>,
    shown: Option<ShownKey>,
    layer: Option<(LayerKey, Film)>,
    loading: Option<Receiver<Result<EditableScene, String>>>,
    open_path: String,
    image_path: String,
    scene_path: String,
}

impl ViewerApp {
    /// A viewer of `edit`; `wake` asks the window for a repaint.
    pub fn new(
        edit: EditableScene,
        size: (u32, u32),
        accel: AccelKind,
        accel_options: AccelOptions,
        wake: impl Fn() + Send + 'static,
    ) -> Self {
        let output = edit.settings.output;
        let (image_path, scene_path) = default_paths(&edit.path);
        let open_path = edit.path.display().to_string();
        let mut core = ViewerCore::new(edit, size, accel, wake);
        core.accel_options = accel_options;
        core.sync();
        Self {
            core,
            display: DisplayState {
                show_photons: false,
                show_boxes: false,
                box_depth: 6,
                output,
            },
            message: String::new(),
            image_rect: None,
            texture: None,
            shown: None,
            layer: None,
            loading: None,
            open_path,
            image_path,
            scene_path,
        }
    }

    /// One frame of the UI: input, panel, image; then the changes are sent
    /// to the render thread.
    pub fn ui(&mut self, ctx: &egui::Context) {
        self.core.poll();
        self.poll_loading(ctx);
        if !ctx.wants_keyboard_input() {
            ctx.input(|i| {
                if i.key_pressed(egui::Key::P) {
                    self.display.show_photons = !self.display.show_photons;
                }
                if i.key_pressed(egui::Key::K) {
                    self.display.show_boxes = !self.display.show_boxes;
                }
            });
        }
        egui::SidePanel::left("panel")
            .resizable(true)
            .default_width(330.0)
            .show(ctx, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.panel(ui));
            });
        egui::CentralPanel::default().show(ctx, |ui| self.image(ui));
        if self.display.show_boxes {
            self.core.want_kd_boxes(self.display.box_depth);
        }
        self.core.sync();
        // Progress text changes while passes run.
        ctx.request_repaint_after(std::time::Duration::from_millis(250));
    }

    fn poll_loading(&mut self, ctx: &egui::Context) {
        let Some(rx) = &self.loading else { return };
        match rx.try_recv() {
            Ok(Ok(edit)) => {
                (self.image_path, self.scene_path) = default_paths(&edit.path);
                self.message = format!("opened {}", edit.path.display());
                ctx.send_viewport_cmd(egui::ViewportCommand::Title(window_title(&edit.path)));
                self.display.output = edit.settings.output;
                self.core.replace_scene(edit);
                self.layer = None;
                self.loading = None;
            }
            Ok(Err(e)) => {
                self.message = e;
                self.loading = None;
            }
            Err(mpsc::TryRecvError::Empty) => {}
            Err(mpsc::TryRecvError::Disconnected) => self.loading = None,
        }
    }

    /// Loads `path` on a background thread (the window stays responsive).
    pub fn open(&mut self, path: PathBuf) {
        let (tx, rx) = mpsc::channel();
        self.message = format!("loading {}", path.display());
        std::thread::spawn(move || {
            let _ = tx.send(EditableScene::open(&path).map_err(|e| e.to_string()));
        });
        self.loading = Some(rx);
    }

    fn panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("caustic");
        self.status(ui);
        ui.separator();
        self.scene_files(ui);
        egui::CollapsingHeader::new("Render")
            .default_open(true)
            .show(ui, |ui| self.render_settings(ui));
        egui::CollapsingHeader::new("Camera")
            .default_open(true)
            .show(ui, |ui| self.camera(ui));
        egui::CollapsingHeader::new("Debug views")
            .default_open(true)
            .show(ui, |ui| {
                ui.checkbox(&mut self.display.show_photons, "photon cloud (p)");
                ui.checkbox(&mut self.display.show_boxes, "KD-tree boxes (k)");
                ui.add(egui::Slider::new(&mut self.display.box_depth, 0..=MAX_BOX_DEPTH).text("box depth"));
            });
        egui::CollapsingHeader::new("Lights")
            .default_open(true)
            .show(ui, |ui| self.lights(ui));
        egui::CollapsingHeader::new("Materials")
            .default_open(false)
            .show(ui, |ui| self.materials(ui));
        egui::CollapsingHeader::new("Save")
            .default_open(true)
            .show(ui, |ui| self.save(ui));
        if !self.message.is_empty() {
            ui.label(&self.message);
        }
    }

    fn status(&self, ui: &mut egui::Ui) {
        match &self.core.frame {
            Some(f) => {
                ui.label(format!(
                    "pass {}  ·  {} spp{}  ·  {:.1} Mrays/s",
                    f.pass,
                    f.spp,
                    if f.preview { " (preview)" } else { "" },
                    f.mrays_per_second
                ));
                ui.label(format!("elapsed {:.2} s", f.since_request.as_secs_f64()));
                if let Some((g, pass, _, time)) = self.core.denoised.as_ref().filter(|_| self.core.denoise) {
                    if *g == f.generation {
                        ui.label(format!("denoised pass {pass} in {:.0} ms", time.as_secs_f64() * 1e3));
                    }
                }
            }
            None => {
                ui.label("rendering…");
            }
        }
        if let Some(l) = self.core.last_latency {
            ui.label(format!("last change to image: {:.0} ms", l.as_secs_f64() * 1e3));
        }
        if !self.core.status.is_empty() {
            ui.label(&self.core.status);
        }
    }

    fn scene_files(&mut self, ui: &mut egui::Ui) {
        let current = self.core.edit.path.clone();
        let name = |p: &Path| {
            p.file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
        };
        let mut chosen = None;
        egui::ComboBox::from_label("scene")
            .selected_text(name(&current))
            .show_ui(ui, |ui| {
                // Listed only while the menu is open, not every frame.
                for f in scene_files_beside(&current) {
                    if ui.selectable_label(f == current, name(&f)).clicked() && f != current {
                        chosen = Some(f);
                    }
                }
            });
        ui.horizontal(|ui| {
            ui.text_edit_singleline(&mut self.open_path);
            if ui.button("open").clicked() {
                chosen = Some(PathBuf::from(self.open_path.trim()));
            }
        });
        if let Some(p) = chosen {
            self.open(p);
        }
    }

    fn render_settings(&mut self, ui: &mut egui::Ui) {
        let s = &mut self.core.edit.settings;
        egui::ComboBox::from_label("integrator")
            .selected_text(match s.integrator {
                IntegratorKind::Whitted => "Whitted",
                IntegratorKind::Path => "path tracing",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut s.integrator, IntegratorKind::Whitted, "Whitted");
                ui.selectable_value(&mut s.integrator, IntegratorKind::Path, "path tracing");
            });
        let mut kinds = vec![AccelKind::KdTree];
        if cfg!(feature = "embree") {
            kinds.insert(0, AccelKind::Embree);
        }
        egui::ComboBox::from_label("accelerator")
            .selected_text(accel_label(self.core.accel))
            .show_ui(ui, |ui| {
                for k in kinds {
                    ui.selectable_value(&mut self.core.accel, k, accel_label(k));
                }
            });
        ui.add(
            egui::Slider::new(&mut s.spp, 1..=crate::limits::MAX_SPP.min(65_536))
                .logarithmic(true)
                .text("target spp"),
        );
        let mut depth = s
            .max_depth
            .unwrap_or(if s.integrator == IntegratorKind::Path { 64 } else { 8 });
        if ui
            .add(egui::Slider::new(&mut depth, 0..=64).text("max depth"))
            .changed()
        {
            s.max_depth = Some(depth);
        }
        ui.add(
            egui::Slider::new(&mut s.photons.count, 0..=100_000_000)
                .logarithmic(true)
                .text("photons"),
        );
        ui.checkbox(&mut self.core.preview, "fast preview pass after a change");
        ui.add_enabled_ui(film::denoise::available(), |ui| {
            ui.checkbox(&mut self.core.denoise, "denoise (Open Image Denoise)")
                .on_disabled_hover_text("this build lacks the `denoise` feature");
        });
        ui.horizontal(|ui| {
            ui.radio_value(&mut self.display.output.tone_map, ToneMap::Aces, "ACES");
            ui.radio_value(&mut self.display.output.tone_map, ToneMap::Clamp, "clamp");
        });
        ui.add(egui::Slider::new(&mut self.display.output.exposure, -8.0..=8.0).text("exposure (stops)"));
    }

    fn camera(&mut self, ui: &mut egui::Ui) {
        let o = &mut self.core.edit.orbit;
        ui.label("drag: orbit · right/shift-drag: pan · wheel: zoom");
        ui.add(egui::Slider::new(&mut o.vfov_deg, 5.0..=120.0).text("field of view"));
        ui.horizontal(|ui| {
            if ui.button("reset camera").clicked() {
                self.core.edit.orbit = self.core.edit.initial_orbit;
            }
            if ui.button("write camera to scene file").clicked() {
                self.message = match self.core.edit.save_camera() {
                    Ok(()) => format!("camera written to {}", self.core.edit.path.display()),
                    Err(e) => e.to_string(),
                };
            }
        });
    }

    fn lights(&mut self, ui: &mut egui::Ui) {
        let edit = &mut self.core.edit;
        for (i, (light, l)) in edit.scene.lights.iter().zip(edit.lights.iter_mut()).enumerate() {
            let kind = light.kind_name();
            egui::CollapsingHeader::new(format!("light {i} ({kind})"))
                .default_open(i == 0)
                .show(ui, |ui| {
                    if light.position().is_some() {
                        vec3_drag(ui, "position", &mut l.position, 0.01);
                    }
                    colour_edit(ui, "colour", &mut l.colour);
                    ui.add(
                        egui::Slider::new(&mut l.intensity, 0.0..=1000.0)
                            .logarithmic(true)
                            .text("intensity"),
                    );
                    if matches!(light, Light::Area(_)) {
                        ui.add(
                            egui::Slider::new(&mut l.samples, 1..=crate::scene::load::MAX_AREA_LIGHT_SAMPLES)
                                .logarithmic(true)
                                .text("shadow samples"),
                        );
                    }
                });
        }
    }

    fn materials(&mut self, ui: &mut egui::Ui) {
        for m in &mut self.core.edit.scene.materials {
            egui::CollapsingHeader::new(m.name.clone()).show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.radio_value(&mut m.model, ShadingModel::Phong, "Phong");
                    ui.radio_value(&mut m.model, ShadingModel::BlinnPhong, "Blinn-Phong");
                });
                // The ambient reflectance follows the diffuse one unless the
                // scene set it apart (the loader's default).
                let ambient_follows = m.ambient == m.diffuse;
                colour_edit(ui, "diffuse", &mut m.diffuse);
                if ambient_follows {
                    m.ambient = m.diffuse;
                }
                colour_edit(ui, "specular", &mut m.specular);
                ui.add(
                    egui::Slider::new(&mut m.shininess, 1.0..=2000.0)
                        .logarithmic(true)
                        .text("shininess"),
                );
                let mut reflectivity = m.mirror.map_or(0.0, |r| r.reflectivity);
                if ui
                    .add(egui::Slider::new(&mut reflectivity, 0.0..=1.0).text("mirror reflectivity"))
                    .changed()
                {
                    m.mirror = (reflectivity > 0.0).then(|| Mirror {
                        reflectivity,
                        tint: m.mirror.map_or(Vec3A::ONE, |r| r.tint),
                    });
                }
                if let Some(mirror) = &mut m.mirror {
                    colour_edit(ui, "mirror tint", &mut mirror.tint);
                }
                if let Some(d) = &mut m.dielectric {
                    ui.add(egui::Slider::new(&mut d.ior, 1.0..=3.0).text("IOR"));
                    colour_edit(ui, "glass tint", &mut d.tint);
                }
            });
        }
    }

    fn save(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label("image");
            ui.text_edit_singleline(&mut self.image_path);
        });
        ui.horizontal(|ui| {
            if ui.button("save PNG").clicked() {
                self.message = self.save_image(false);
            }
            if ui.button("save EXR").clicked() {
                self.message = self.save_image(true);
            }
        });
        ui.horizontal(|ui| {
            ui.label("scene");
            ui.text_edit_singleline(&mut self.scene_path);
        });
        if ui.button("save scene").clicked() {
            let p = PathBuf::from(self.scene_path.trim());
            self.message = match self.core.edit.save(&p) {
                Ok(()) => format!("scene saved to {}", p.display()),
                Err(e) => e.to_string(),
            };
        }
    }

    /// Writes the current image as shown (denoised when denoising is on;
    /// without debug layers); returns the message.
    pub fn save_image(&self, exr: bool) -> String {
        let (Some(f), Some(shown)) = (&self.core.frame, self.core.shown_film()) else {
            return "no image yet".into();
        };
        let mut p = PathBuf::from(self.image_path.trim());
        p.set_extension(if exr { "exr" } else { "png" });
        let r = if exr {
            film::write_exr(&p, shown)
        } else {
            film::write_png(&p, shown, &self.display.output)
        };
        match r {
            Ok(()) => format!("{} spp image saved to {}", f.spp, p.display()),
            Err(e) => e.to_string(),
        }
    }

    fn image(&mut self, ui: &mut egui::Ui) {
        let (w, h) = self.core.size;
        self.update_texture(ui.ctx());
        let avail = ui.available_size();
        let scale = (avail.x / w as f32).min(avail.y / h as f32).clamp(0.05, 1.0);
        let size = egui::vec2(w as f32 * scale, h as f32 * scale);
        let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
        self.image_rect = Some(rect);
        if let Some(t) = &self.texture {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            ui.painter().image(t.id(), rect, uv, egui::Color32::WHITE);
        }
        let delta = response.drag_delta() / scale;
        let (dx, dy) = (delta.x, delta.y);
        let orbit = &mut self.core.edit.orbit;
        let shift = ui.input(|i| i.modifiers.shift);
        if response.dragged_by(egui::PointerButton::Primary) && !shift {
            orbit.rotate(dx, dy, h as f32);
        } else if response.dragged_by(egui::PointerButton::Secondary)
            || response.dragged_by(egui::PointerButton::Middle)
            || (response.dragged_by(egui::PointerButton::Primary) && shift)
        {
            orbit.pan(dx, dy, h as f32);
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                orbit.zoom(scroll / 50.0);
            }
        }
    }

    /// Uploads the newest frame (tone-mapped, debug layers on top) when it,
    /// the display settings or the debug views changed.
    fn update_texture(&mut self, ctx: &egui::Context) {
        let Some(frame) = &self.core.frame else { return };
        let d = &self.display;
        let denoised_pass = self
            .core
            .denoised
            .as_ref()
            .filter(|x| self.core.denoise && x.0 == frame.generation)
            .map(|x| x.1);
        let key = (
            frame.generation,
            frame.pass,
            denoised_pass,
            d.output,
            d.show_photons,
            d.show_boxes,
            d.box_depth,
        );
        let layer_changed = self.refresh_layer();
        if self.shown.as_ref() == Some(&key) && !layer_changed && self.texture.is_some() {
            return;
        }
        let Some(film) = self.core.shown_film() else { return };
        let (w, h) = self.core.size;
        let mut rgba = display_rgba(film, &self.display.output, w, h);
        if let Some((_, layer)) = &self.layer {
            composite(&mut rgba, layer);
        }
        let image = egui::ColorImage::from_rgba_unmultiplied([w as usize, h as usize], &rgba);
        match &mut self.texture {
            Some(t) => t.set(image, egui::TextureOptions::NEAREST),
            None => self.texture = Some(ctx.load_texture("render", image, egui::TextureOptions::NEAREST)),
        }
        self.shown = Some(key);
    }

    /// Redraws the debug layer when the camera or the views changed;
    /// returns whether it changed.
    fn refresh_layer(&mut self) -> bool {
        let d = &self.display;
        let photons = d.show_photons.then(|| self.core.photon_map.clone()).flatten();
        let boxes = if d.show_boxes { self.core.kd_boxes.clone() } else { None };
        if photons.is_none() && boxes.is_none() {
            return self.layer.take().is_some();
        }
        let cam = &self.core.edit.scene.camera;
        let key = LayerKey {
            camera: cam.clone(),
            size: self.core.size,
            photons: photons.as_ref().map_or(0, |m| Arc::as_ptr(m) as usize),
            boxes: boxes.as_ref().map(|(_, b)| (d.box_depth, Arc::as_ptr(b) as usize)),
        };
        if self.layer.as_ref().is_some_and(|(k, _)| *k == key) {
            return false;
        }
        let (w, h) = self.core.size;
        let film = debug_layer(
            cam,
            w,
            h,
            photons.as_deref(),
            boxes.as_ref().map(|(_, b)| (b.as_slice(), d.box_depth)),
        );
        self.layer = Some((key, film));
        true
    }
}

impl eframe::App for ViewerApp {
    fn update(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        self.ui(ctx);
    }
}

fn accel_label(k: AccelKind) -> &'static str {
    match k {
        AccelKind::Embree => "Embree",
        AccelKind::KdTree => "KD-tree",
        AccelKind::Brute => "brute force",
    }
}

fn vec3_drag(ui: &mut egui::Ui, label: &str, v: &mut Vec3A, speed: f64) {
    ui.horizontal(|ui| {
        ui.label(label);
        ui.add(egui::DragValue::new(&mut v.x).speed(speed).prefix("x "));
        ui.add(egui::DragValue::new(&mut v.y).speed(speed).prefix("y "));
        ui.add(egui::DragValue::new(&mut v.z).speed(speed).prefix("z "));
    });
}

fn colour_edit(ui: &mut egui::Ui, label: &str, c: &mut Vec3A) {
    ui.horizontal(|ui| {
        let mut rgb = c.to_array();
        if ui.color_edit_button_rgb(&mut rgb).changed() {
            *c = Vec3A::from_array(rgb);
        }
        ui.label(label);
    });
}

/// The `.toml` files in the folder of `scene`, sorted.
fn scene_files_beside(scene: &Path) -> Vec<PathBuf> {
    let dir = scene.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map(|r| {
            r.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "toml"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// `caustic — <scene file>`.
pub fn window_title(scene: &Path) -> String {
    format!("caustic — {}", scene.display())
}

/// Default save paths beside the working directory: `<stem>-view.png` and
/// `<stem>-edited.toml`.
fn default_paths(scene: &Path) -> (String, String) {
    let stem = scene
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let dir = scene.parent().unwrap_or(Path::new(""));
    (
        format!("{stem}-view.png"),
        dir.join(format!("{stem}-edited.toml")).display().to_string(),
    )
}

/// Opens the window and runs until it is closed.
pub fn run(options: ViewOptions) -> Result<(), String> {
    let mut edit = EditableScene::open_with(&options.scene, &options.load).map_err(|e| e.to_string())?;
    if let Some(n) = options.spp {
        edit.settings.spp = n.max(1);
    }
    let (w, h) = options.size;
    let title = window_title(&options.scene);
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title.clone())
            .with_inner_size([w.max(320) as f32 + 356.0, (h as f32 + 16.0).max(720.0)]),
        renderer: eframe::Renderer::Glow,
        ..Default::default()
    };
    let size = if options.size == (0, 0) {
        DEFAULT_SIZE
    } else {
        options.size
    };
    let accel_options = options.accel_options.clone();
    eframe::run_native(
        &title,
        native,
        Box::new(move |cc| {
            let ctx = cc.egui_ctx.clone();
            Ok(Box::new(ViewerApp::new(
                edit,
                size,
                options.accel,
                accel_options,
                move || ctx.request_repaint(),
            )))
        }),
    )
    .map_err(|e| format!("cannot open the window: {e}"))
}
