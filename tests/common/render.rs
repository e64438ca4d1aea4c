//! A scene rendered in memory, the way most integration tests need it: the
//! accelerator built, the plan made from the scene's own settings, every
//! pass run, the film returned.

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::film::Film;
use caustic::integrator::{render, RenderPlan, RenderSetup};
use caustic::scene::LoadedScene;

/// `scene` rendered with accelerator `kind` at its own settings.
pub fn film(scene: &LoadedScene, kind: AccelKind) -> Film {
    let accel = accel::build(&scene.scene, kind, &AccelOptions::default()).unwrap();
    render(
        &scene.scene,
        accel.as_ref(),
        &RenderPlan::new(&scene.scene, &scene.settings),
        RenderSetup::default(),
    )
    .film
}
