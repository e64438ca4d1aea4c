//! A small whole-image render per accelerator: the Cornell box at 160×90,
//! 1 spp, with a 10,000-photon caustic pass (mirror, glass, the star mesh,
//! an area light), and the generated torus scene at the same size.
//!
//! `cargo bench --bench render` (under a minute).

mod common;

use caustic::accel;
use caustic::accel::AccelOptions;
use caustic::analysis::bench::default_accels;
use caustic::integrator::{render::render, RenderPlan, RenderSetup};
use caustic::scene::{load_scene, LoadedScene};
use criterion::{criterion_group, criterion_main, Criterion, SamplingMode, Throughput};
use std::hint::black_box;
use std::path::Path;

fn small(mut loaded: LoadedScene) -> LoadedScene {
    let s = &mut loaded.settings;
    s.width = 160;
    s.height = 90;
    s.spp = 1;
    s.photons.count = 10_000;
    loaded
}

fn render_group(c: &mut Criterion, label: &str, loaded: &LoadedScene) {
    let scene = &loaded.scene;
    let plan = RenderPlan::new(scene, &loaded.settings);
    let mut group = c.benchmark_group(format!("render/{label}"));
    group.sampling_mode(SamplingMode::Flat);
    group.throughput(Throughput::Elements((plan.width * plan.height) as u64));
    for kind in default_accels() {
        let accel = accel::build(scene, kind, &AccelOptions::default()).expect("accelerator builds");
        group.bench_function(kind.name(), |b| {
            b.iter(|| black_box(render(scene, accel.as_ref(), &plan, RenderSetup::default())))
        });
    }
    group.finish();
}

fn renders(c: &mut Criterion) {
    let cornell = load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml"))
        .expect("scenes/cornell.toml loads");
    render_group(c, "cornell-160x90", &small(cornell));
    let torus = LoadedScene {
        scene: common::torus_scene(),
        settings: Default::default(),
    };
    render_group(c, "torus-160x90", &small(torus));
}

criterion_group! {
    name = render_benches;
    config = common::quick(4);
    targets = renders
}
criterion_main!(render_benches);
