//! The viewer without a window: its frames are the batch render core's
//! images, a change cancels the running pass without mixing scene versions,
//! and camera or diffuse-material edits skip the accelerator build and the
//! photon pass. With the `viewer` feature, headless interaction tests of the
//! panel (egui_kittest): a slider, the `p`/`k` keys and a camera drag.

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::film::Accumulation;
use caustic::integrator::{self, PhotonInput, RenderControl, RenderPlan, RenderSetup};
use caustic::math::Vec3A;
use caustic::scene::LoadedScene;
use caustic::view::{EditableScene, ViewerCore};
use std::path::Path;
use std::time::Duration;

const TIMEOUT: Duration = Duration::from_secs(300);

fn cornell() -> EditableScene {
    let mut e = EditableScene::open(Path::new("scenes/cornell.toml")).unwrap();
    e.settings.spp = 8;
    e.settings.photons.count = 20_000;
    e
}

/// The batch render core's image of `scene` after `spp` samples (the
/// plan's target stays the scene's, as in the viewer's passes).
fn batch_image(scene: &LoadedScene, spp: u32) -> Vec<caustic::math::Vec3> {
    let accel = accel::build(&scene.scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let map = integrator::render::photon_pass_for(&scene.scene, &*accel, &plan).map(|(m, _)| m);
    let control = RenderControl {
        sample_limit: Some(spp),
        ..RenderControl::to_completion(&|_, _| {})
    };
    let start = Accumulation::new(plan.width, plan.height);
    integrator::render(
        &scene.scene,
        &*accel,
        &plan,
        RenderSetup::default()
            .continuing(start)
            .photons(PhotonInput::Map(map.as_ref()))
            .control(control),
    )
    .film
    .pixels
}

#[test]
fn frames_are_the_batch_render_of_the_same_samples() {
    let mut core = ViewerCore::new(cornell(), (48, 27), AccelKind::KdTree, || {});
    assert!(core.sync());
    assert!(!core.sync(), "nothing changed: no new request");
    assert!(core.wait_for_spp(4, TIMEOUT));
    let f = core.frame.clone().unwrap();
    assert!(!f.preview && f.spp >= 4);
    let expected = batch_image(core.submitted_scene().unwrap(), f.spp);
    assert!(
        f.film.pixels == expected,
        "the viewer's image differs from the render core's"
    );
    assert!(f.film.mean().max_element() > 0.0);
}

#[cfg(feature = "denoise")]
#[test]
fn the_denoise_toggle_shows_a_denoised_image_without_stopping_the_render() {
    let mut core = ViewerCore::new(cornell(), (48, 27), AccelKind::KdTree, || {});
    core.sync();
    assert!(core.wait_for_spp(8, TIMEOUT), "the render completes");
    assert!(core.denoised.is_none(), "nothing is denoised while the toggle is off");
    core.denoise = true;
    let end = std::time::Instant::now() + TIMEOUT;
    while core.denoised.is_none() && std::time::Instant::now() < end {
        core.wait(Duration::from_millis(200));
    }
    let frame = core.frame.clone().unwrap();
    let (generation, pass, film, _) = core.denoised.clone().expect("a denoised image arrives");
    assert_eq!(
        (generation, pass),
        (frame.generation, frame.pass),
        "the last pass is denoised"
    );
    assert_eq!((film.width, film.height), (48, 27));
    assert!(film.pixels != frame.film.pixels && film.mean().max_element() > 0.0);
    assert!(std::sync::Arc::ptr_eq(core.shown_film().unwrap(), &film));
    core.denoise = false;
    assert!(std::sync::Arc::ptr_eq(core.shown_film().unwrap(), &frame.film));
    // A change renders again: the old denoised image is not shown for it.
    core.denoise = true;
    core.edit.orbit.zoom(1.0);
    assert!(core.sync());
    assert!(core.shown_film().is_none_or(|f| !std::sync::Arc::ptr_eq(f, &film)));
}

#[test]
fn a_change_restarts_refinement_without_mixing_versions() {
    let mut core = ViewerCore::new(cornell(), (48, 27), AccelKind::KdTree, || {});
    core.sync();
    assert!(core.wait_for_spp(2, TIMEOUT));
    let first = core.frame.clone().unwrap();
    let (builds, photon_passes) = (first.accel_builds, first.photon_passes);
    assert_eq!((builds, photon_passes), (1, 1));

    // A camera move and a diffuse edit, at once, while passes run.
    core.edit.orbit.rotate(30.0, 5.0, 27.0);
    let white = core
        .edit
        .scene
        .materials
        .iter()
        .position(|m| m.name == "white")
        .unwrap();
    core.edit.scene.materials[white].diffuse = Vec3A::new(0.3, 0.6, 0.9);
    assert!(core.sync());
    let generation = core.generation();
    assert!(core.wait_for_spp(8, TIMEOUT));
    let f = core.frame.clone().unwrap();
    assert_eq!(f.generation, generation);
    // Neither the accelerator nor the photon map was rebuilt.
    assert_eq!((f.accel_builds, f.photon_passes), (1, 1));
    // Every sample of the image is of the new version: it is exactly the
    // render core's image of the new scene.
    let expected = batch_image(core.submitted_scene().unwrap(), f.spp);
    assert!(f.film.pixels == expected, "samples of two versions in one image");

    // A light edit re-runs the photon pass, not the accelerator build.
    core.edit.lights[0].intensity *= 0.5;
    core.sync();
    assert!(core.wait_for_spp(1, TIMEOUT));
    let f = core.frame.clone().unwrap();
    assert_eq!((f.accel_builds, f.photon_passes), (1, 2));

    // Switching the accelerator rebuilds it.
    core.accel = AccelKind::Brute;
    core.sync();
    assert!(core.wait_for_spp(1, TIMEOUT));
    assert_eq!(core.frame.as_ref().unwrap().accel_builds, 2);
}

#[test]
fn the_first_image_after_a_change_is_a_cheap_preview() {
    let mut core = ViewerCore::new(cornell(), (64, 36), AccelKind::KdTree, || {});
    core.sync();
    assert!(core.wait_for_spp(1, TIMEOUT));
    core.edit.orbit.zoom(1.0);
    core.sync();
    let generation = core.generation();
    let mut saw_preview = false;
    while !core.wait_for_spp(1, Duration::from_millis(1)) {
        if let Some(f) = &core.frame {
            if f.generation == generation && f.preview {
                saw_preview = true;
                assert_eq!((f.film.width, f.film.height), (16, 9));
            }
        }
    }
    assert!(saw_preview, "no preview pass before the full pass");
}

#[test]
fn saved_scene_renders_what_the_viewer_shows() {
    let dir = tempfile::tempdir().unwrap();
    let mut e = cornell();
    e.orbit.rotate(-40.0, 10.0, 540.0);
    e.lights[0].intensity = 2.5;
    e.scene.materials[0].diffuse = Vec3A::new(0.2, 0.4, 0.6);
    e.apply();
    let out = dir.path().join("edited.toml");
    e.save(&out).unwrap();
    let again = caustic::scene::load_scene(&out).unwrap();
    assert_eq!(again.scene.lights, e.scene.lights);
    assert_eq!(again.scene.materials, e.scene.materials);
    assert_eq!(again.settings.spp, 8);
    assert!((again.scene.camera.position - e.scene.camera.position).length() < 1e-5);
    assert!((again.scene.camera.forward - e.scene.camera.forward).length() < 1e-5);
    // `caustic render` of the saved file gives the viewer's image exactly.
    let mut again = again;
    let mut shown = e.snapshot();
    for s in [&mut again.settings, &mut shown.settings] {
        (s.width, s.height) = (40, 24);
    }
    assert_eq!(again.scene.camera, shown.scene.camera);
    assert!(
        batch_image(&again, 2) == batch_image(&shown, 2),
        "the saved scene renders differently"
    );
}

#[cfg(feature = "viewer")]
mod window {
    use super::*;
    use caustic::view::app::ViewerApp;
    use eframe::egui;
    use egui_kittest::kittest::Queryable;
    use egui_kittest::Harness;
    use std::time::Instant;

    fn harness() -> Harness<'static, ViewerApp> {
        let app = ViewerApp::new(cornell(), (64, 36), AccelKind::KdTree, AccelOptions::default(), || {});
        Harness::builder()
            .with_size(egui::vec2(900.0, 700.0))
            .build_state(|ctx, app: &mut ViewerApp| app.ui(ctx), app)
    }

    /// Steps the UI until `done` holds (the render thread works meanwhile).
    fn step_until(h: &mut Harness<'static, ViewerApp>, done: impl Fn(&ViewerApp) -> bool) {
        let end = Instant::now() + TIMEOUT;
        while !done(h.state()) {
            assert!(Instant::now() < end, "timed out");
            h.step();
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    fn full_frame(app: &ViewerApp) -> bool {
        app.core
            .frame
            .as_ref()
            .is_some_and(|f| f.generation == app.core.generation() && !f.preview)
    }

    #[test]
    fn a_slider_changes_the_scene_the_next_pass_renders() {
        let mut h = harness();
        step_until(&mut h, full_frame);
        let before = h.state().core.submitted_scene().unwrap().scene.lights[0].clone();
        let generation = h.state().core.generation();
        h.get_by_role_and_label(egui::accesskit::Role::Slider, "intensity")
            .focus();
        h.step();
        h.key_press(egui::Key::ArrowRight);
        h.step();
        let app = h.state();
        assert!(app.core.generation() > generation, "no new request");
        let after = &app.core.submitted_scene().unwrap().scene.lights[0];
        assert_ne!(*after, before, "the slider did not reach the scene");
        step_until(&mut h, full_frame);
    }

    #[test]
    fn p_and_k_toggle_the_debug_views() {
        let mut h = harness();
        step_until(&mut h, |a| full_frame(a) && a.core.photon_map.is_some());
        assert!(!h.state().display.show_photons);
        h.key_press(egui::Key::P);
        h.step();
        assert!(h.state().display.show_photons);
        h.key_press(egui::Key::K);
        h.step();
        assert!(h.state().display.show_boxes);
        step_until(&mut h, |a| a.core.kd_boxes.is_some());
        h.step();
        h.key_press(egui::Key::P);
        h.key_press(egui::Key::K);
        h.step();
        assert!(!h.state().display.show_photons && !h.state().display.show_boxes);
        // The checkboxes show the same state.
        h.get_by_label("photon cloud (p)").click();
        h.step();
        assert!(h.state().display.show_photons);
    }

    #[test]
    fn a_drag_on_the_image_moves_the_camera() {
        let mut h = harness();
        step_until(&mut h, full_frame);
        let before = h.state().core.edit.orbit;
        let start = h.state().image_rect.expect("the image is shown").center();
        let input = h.input_mut();
        input.events.push(egui::Event::PointerMoved(start));
        input.events.push(egui::Event::PointerButton {
            pos: start,
            button: egui::PointerButton::Primary,
            pressed: true,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
        for i in 1..=5 {
            let p = start + egui::vec2(8.0 * i as f32, 2.0 * i as f32);
            h.input_mut().events.push(egui::Event::PointerMoved(p));
            h.step();
        }
        let end = start + egui::vec2(40.0, 10.0);
        h.input_mut().events.push(egui::Event::PointerButton {
            pos: end,
            button: egui::PointerButton::Primary,
            pressed: false,
            modifiers: egui::Modifiers::NONE,
        });
        h.step();
        let after = h.state().core.edit.orbit;
        assert!(after.yaw != before.yaw, "the drag did not orbit the camera");
        assert_eq!(after.distance, before.distance);
        let cam = &h.state().core.submitted_scene().unwrap().scene.camera;
        assert_eq!(*cam, after.camera().unwrap());
    }
}

/// The viewer opens a glTF model with the camera the command line names
/// (`caustic view --camera`), as `caustic render` does.
#[test]
fn the_viewer_opens_the_camera_the_command_line_names() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/nodes.gltf");
    let first = EditableScene::open(&path).unwrap();
    assert_eq!(first.scene.camera.projection, caustic::scene::Projection::Perspective);
    let options = caustic::scene::LoadOptions {
        gltf: caustic::scene::gltf::GltfOptions {
            camera: Some("ortho".parse().unwrap()),
            ..Default::default()
        },
        ..Default::default()
    };
    let chosen = EditableScene::open_with(&path, &options).unwrap();
    assert!(
        matches!(
            chosen.scene.camera.projection,
            caustic::scene::Projection::Orthographic { .. }
        ),
        "{:?}",
        chosen.scene.camera.projection
    );
}
