//! `caustic view`: the window, or its latency benchmark.

use crate::args::ViewArgs;
use crate::{bad_input, Failure};
use caustic::view::{latency, DEFAULT_SIZE};

pub fn run_view(args: ViewArgs) -> Result<(), Failure> {
    // A bad scene is refused before any window opens.
    let load_options = caustic::job::Overrides {
        defines: args.defines.defines.clone(),
        camera: args.camera.clone(),
        allow_outside_files: args.allow_outside_files,
        ..Default::default()
    }
    .load_options();
    let mut settings = caustic::scene::load_scene_options(&args.scene, &load_options)
        .map_err(bad_input)?
        .settings;
    args.accel.apply(&mut settings);
    let size = (
        args.width.unwrap_or(DEFAULT_SIZE.0),
        args.height.unwrap_or(DEFAULT_SIZE.1),
    );
    caustic::limits::check_image_limits(size.0, size.1, args.spp.unwrap_or(1))
        .map_err(|e| bad_input(anyhow::anyhow!("--width/--height: {e}")))?;
    let kind = args.accel.kind();
    if let Some(n) = args.latency_bench {
        let report = latency::measure(&args.scene, size, kind, n.max(1)).map_err(bad_input)?;
        print_latency(&report);
        let json = serde_json::to_string_pretty(&report)?;
        match &args.json {
            Some(p) => {
                std::fs::write(p, json + "\n").map_err(|e| bad_input(anyhow::anyhow!("{}: {e}", p.display())))?
            }
            None => println!("{json}"),
        }
        return Ok(());
    }
    open_window(&args, &settings, size, kind, load_options)
}

fn print_latency(r: &latency::LatencyReport) {
    eprintln!("{} at {}×{} with {}", r.scene, r.width, r.height, r.accel);
    eprintln!("  scene read: {:.0} ms", r.load_ms);
    eprintln!(
        "  first image (preview) after the first request: {:.0} ms",
        r.first_image_ms
    );
    eprintln!(
        "  first full-resolution image after the first request: {:.0} ms",
        r.startup_ms
    );
    let row = |what: &str, m: &latency::Millis| {
        eprintln!(
            "  {what:<32} median {:7.1} ms  (min {:.1}, max {:.1})",
            m.median, m.min, m.max
        );
    };
    row("camera move → first image", &r.camera_first_image);
    row("camera move → first full pass", &r.camera_first_full);
    row("material edit → first image", &r.material_first_image);
    row("material edit → first full pass", &r.material_first_full);
    eprintln!("  photon passes re-run by those edits: {}", r.photon_reruns);
    for p in &r.passes {
        eprintln!(
            "  pass to {:>3} spp: {:7.1} ms ({:.1} fps, {:.1} Mrays/s)",
            p.spp,
            p.ms,
            1e3 / p.ms.max(1e-9),
            p.mrays_per_second
        );
    }
}

#[cfg(feature = "viewer")]
fn open_window(
    args: &ViewArgs,
    settings: &caustic::scene::RenderSettings,
    size: (u32, u32),
    accel: caustic::accel::AccelKind,
    load: caustic::scene::LoadOptions,
) -> Result<(), Failure> {
    caustic::view::app::run(caustic::view::app::ViewOptions {
        scene: args.scene.clone(),
        load,
        accel,
        size,
        accel_options: args.accel.options(settings),
        spp: args.spp,
    })
    .map_err(|e| Failure::from(anyhow::anyhow!(e)))
}

#[cfg(not(feature = "viewer"))]
fn open_window(
    _: &ViewArgs,
    _: &caustic::scene::RenderSettings,
    _: (u32, u32),
    _: caustic::accel::AccelKind,
    _: caustic::scene::LoadOptions,
) -> Result<(), Failure> {
    Err(bad_input(anyhow::anyhow!(
        "this caustic was built without the `viewer` feature (the window); \
         build it with `cargo build --release --features viewer`"
    )))
}
