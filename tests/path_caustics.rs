//! The path integrator with photon-mapped caustics (`[photons] caustics =
//! "map"`) and the water's participating medium: the combined estimator
//! against pure path tracing (no light counted twice, none lost), the
//! energy the physically based photons carry, the medium's transmittance,
//! light shafts from the volume map, and determinism.

mod common;

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::integrator::photon::{trace_photons_with, PhotonRules};
use caustic::integrator::plan::{MediumPlan, PhotonPlan};
use caustic::integrator::{render, RenderPlan, RenderSetup};
use caustic::scene::LoadedScene;
use caustic::scene::{parse_scene, CausticsMode, GatherMode, IntegratorKind};
use common::cli::caustic;
use std::path::Path;

fn scene(text: &str) -> LoadedScene {
    parse_scene(text, Path::new("test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

/// Linear RGB pixels of a render, as f64 triples.
fn pixels(scene: &LoadedScene, threads: usize) -> Vec<[f64; 3]> {
    let accel = accel::build(&scene.scene, AccelKind::default_kind(), &AccelOptions::default()).unwrap();
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let out = pool.install(|| render(&scene.scene, accel.as_ref(), &plan, RenderSetup::default()));
    assert_eq!(out.stats.dropped_samples, 0);
    out.film
        .pixels
        .iter()
        .map(|p| [p.x as f64, p.y as f64, p.z as f64])
        .collect()
}

/// Mean of the pixels in rows `y0..y1`, columns `x0..x1` (all channels).
fn region_mean(px: &[[f64; 3]], width: usize, (x0, x1, y0, y1): (usize, usize, usize, usize)) -> f64 {
    let mut sum = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += px[y * width + x].iter().sum::<f64>();
        }
    }
    sum / ((x1 - x0) * (y1 - y0) * 3) as f64
}

/// A glass ball over a diffuse floor under a small area light: its
/// caustic is the ball's focused light on the floor, which pure path
/// tracing finds only by hitting the small light through the glass.
const GLASS: &str = r#"
[render]
width = 40
height = 28
spp = 64
seed = 3
integrator = "path"

[camera]
position = [0.0, 3.2, 4.2]
look_at = [0.0, 0.3, 0.0]
vfov = 40

[photons]
count = 1000000
k = 64
max_radius = 0.08
caustics = "map"

[materials.floor]
diffuse = [0.7, 0.7, 0.7]

[materials.glass]
dielectric = { ior = 1.5 }

[[lights]]
type = "area"
position = [0.6, 4.0, -0.4]
u = [0.3, 0.0, 0.0]
v = [0.0, 0.0, 0.3]
colour = [1.0, 1.0, 1.0]
intensity = 400.0

[[objects]]
type = "quad"
center = [0.0, 0.0, 0.0]
size = [6.0, 6.0]
normal = [0.0, 1.0, 0.0]
material = "floor"

[[objects]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.7
material = "glass"
"#;

/// The map and pure path tracing (at 256 times the samples) converge to the
/// same image: the mean over the image and over the caustic agree within
/// Monte Carlo error. Counting the caustic twice (map and paths) measures
/// +15% over the image and +55% over the caustic at 96×64, so the
/// tolerances (3% and 6%) catch it; forgetting it costs as much.
#[test]
fn map_and_path_caustics_converge_to_the_same_image() {
    let with_map = scene(GLASS);
    let plan = RenderPlan::new(&with_map.scene, &with_map.settings);
    assert!(
        matches!(plan.photons, PhotonPlan::Run { casters: 1, .. }),
        "{:?}",
        plan.photons
    );
    let mut as_paths = with_map.clone();
    as_paths.settings.photons.caustics = CausticsMode::Path;
    as_paths.settings.spp = 16_384;
    assert_eq!(
        RenderPlan::new(&as_paths.scene, &as_paths.settings).photons,
        PhotonPlan::PathTraced
    );
    let (m, p) = (pixels(&with_map, 2), pixels(&as_paths, 2));
    let width = 40;
    let whole = (0, 40, 0, 28);
    // The ball's shadow and the caustic inside it.
    let caustic = (12, 28, 9, 22);
    let ratio = region_mean(&m, width, whole) / region_mean(&p, width, whole);
    let caustic_ratio = region_mean(&m, width, caustic) / region_mean(&p, width, caustic);
    eprintln!("map / path: image {ratio:.4}, caustic {caustic_ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.03, "image mean ratio {ratio}");
    assert!((caustic_ratio - 1.0).abs() < 0.06, "caustic mean ratio {caustic_ratio}");
    // Progressive photon mapping (a new map and a smaller radius per
    // sample index) converges to the same image.
    let mut progressive = with_map.clone();
    progressive.settings.photons.progressive = true;
    progressive.settings.photons.count = 4_000_000;
    assert!(RenderPlan::new(&progressive.scene, &progressive.settings)
        .progressive()
        .is_some());
    let q = pixels(&progressive, 2);
    let ratio = region_mean(&q, width, whole) / region_mean(&p, width, whole);
    let caustic_ratio = region_mean(&q, width, caustic) / region_mean(&p, width, caustic);
    eprintln!("progressive / path: image {ratio:.4}, caustic {caustic_ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.03, "progressive image mean ratio {ratio}");
    assert!(
        (caustic_ratio - 1.0).abs() < 0.06,
        "progressive caustic mean ratio {caustic_ratio}"
    );
}

/// The physically based photons carry the power the casters receive:
/// a clear glass ball (no absorption) inside a closed diffuse box, lit by a
/// point light, sends every photon that reaches it (reflected or refracted,
/// Fresnel choosing) to the box's walls, so the stored power is
/// `I · Ω_ball` with `Ω = 2π(1 − cos θ)`, `sin θ = r / d`; a mirror quad
/// of tint `t` stores `t · I · Ω_quad`.
#[test]
fn photons_carry_the_power_the_casters_receive() {
    // A closed 8×8×8 box around the origin.
    let walls: String = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
        .iter()
        .map(|n| {
            format!(
                "[[objects]]\ntype = \"quad\"\ncenter = [{}, {}, {}]\nsize = [8.2, 8.2]\nnormal = [{}, {}, {}]\nmaterial = \"wall\"\n",
                4 * n[0], 4 * n[1], 4 * n[2], -n[0], -n[1], -n[2]
            )
        })
        .collect();
    let box_scene = |caster: &str| {
        scene(&format!(
            r#"
[render]
integrator = "path"
seed = 11
[camera]
position = [0, 1, 3.5]
look_at = [0, 1, 0]
[photons]
count = 400000
caustics = "map"
[materials.wall]
diffuse = [0.5, 0.5, 0.5]
[materials.glass]
dielectric = {{ ior = 1.5 }}
[materials.mirror]
diffuse = [0, 0, 0]
mirror = {{ reflectivity = 1.0, tint = [0.8, 0.6, 0.4] }}
[[lights]]
type = "point"
position = [0.0, 3.0, 0.0]
colour = [1, 1, 1]
intensity = 10.0
{walls}
{caster}
"#
        ))
    };
    let stored = |s: &LoadedScene| {
        let accel = accel::build(&s.scene, AccelKind::default_kind(), &AccelOptions::default()).unwrap();
        let traced = trace_photons_with(
            &s.scene,
            caustic::integrator::photon::TraceSettings::of(&s.settings),
            accel.as_ref(),
            s.settings.photons.count,
            false,
            PhotonRules::Physical,
            0,
        );
        let mut sum = [0.0f64; 3];
        for r in &traced.records {
            let p = r.power();
            sum[0] += p.x as f64;
            sum[1] += p.y as f64;
            sum[2] += p.z as f64;
        }
        sum
    };
    let pi = std::f64::consts::PI;

    let ball = box_scene("[[objects]]\ntype = \"sphere\"\ncenter = [0, 1, 0]\nradius = 0.8\nmaterial = \"glass\"");
    let (r, d) = (0.8f64, 2.0f64);
    let omega = 2.0 * pi * (1.0 - (1.0 - r * r / (d * d)).sqrt());
    let got = stored(&ball);
    for c in got {
        assert!(
            (c / (10.0 * omega) - 1.0).abs() < 0.01,
            "glass: {got:?} vs {}",
            10.0 * omega
        );
    }

    // A 1×1 mirror at y = 1 facing up, 2 below the light.
    let mirror = box_scene(
        "[[objects]]\ntype = \"quad\"\ncenter = [0, 1, 0]\nsize = [1, 1]\nnormal = [0, 1, 0]\nmaterial = \"mirror\"",
    );
    let h = 2.0f64;
    let omega = 4.0 * (1.0 / (1.0 + 4.0 * h * h)).asin();
    let got = stored(&mirror);
    for (c, t) in got.iter().zip([0.8, 0.6, 0.4]) {
        assert!((c / (10.0 * omega * t) - 1.0).abs() < 0.01, "mirror: {got:?}");
    }
}

/// Water with a flat surface at y = 4, a floor at y = 0, and a light inside
/// the water facing down.
fn water(absorption: f32, scattering: f32, light_in_water: bool, extra: &str) -> String {
    let light_y = if light_in_water { 3.5 } else { 7.0 };
    format!(
        r#"
[render]
width = 24
height = 16
spp = 64
seed = 2
integrator = "path"
max_depth = 64

[camera]
position = [0.0, 2.0, 0.0]
look_at = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
vfov = 6

[photons]
count = 400000
k = 32
max_radius = 0.15
{extra}

[medium]
density = 0.1
absorption = [{absorption}, {absorption}, {absorption}]
scattering = [{scattering}, {scattering}, {scattering}]
g = 0.5

[materials.sand]
diffuse = [0.6, 0.6, 0.6]

[materials.water]
dielectric = {{ ior = 1.33 }}

[[lights]]
type = "area"
position = [0.0, {light_y}, 0.0]
u = [1.0, 0.0, 0.0]
v = [0.0, 0.0, 1.0]
colour = [1, 1, 1]
intensity = 30.0

[[objects]]
type = "water"
center = [0.0, 4.0, 0.0]
size = [40.0, 40.0]
resolution = [8, 8]
material = "water"

[[objects]]
type = "quad"
center = [0.0, 0.0, 0.0]
size = [40.0, 40.0]
normal = [0.0, 1.0, 0.0]
material = "sand"
"#
    )
}

/// A purely absorbing medium multiplies the floor's radiance by the
/// transmittance of both legs: light → floor (the shadow ray, 3.5) and
/// floor → camera (the free flight, 2), `exp(−σa · 5.5)`, as a narrow view
/// of the floor under the light sees it.
#[test]
fn absorbing_water_attenuates_by_the_transmittance_of_both_legs() {
    let clear = scene(&water(0.0, 0.0, true, ""));
    let murky = scene(&water(0.2, 0.0, true, ""));
    assert!(matches!(
        RenderPlan::new(&murky.scene, &murky.settings).medium,
        MediumPlan::Run { .. }
    ));
    let (a, b) = (pixels(&clear, 2), pixels(&murky, 2));
    let mean = |p: &[[f64; 3]]| p.iter().flatten().sum::<f64>() / (p.len() * 3) as f64;
    let ratio = mean(&b) / mean(&a);
    let want = (-0.2f64 * 5.5).exp();
    eprintln!("murky / clear {ratio:.4}, exp(−σa·5.5) = {want:.4}");
    // Light reflected between floor and the surface (total internal
    // reflection sends some back) travels farther: a few per cent lower.
    assert!(
        ratio < want * 1.01 && ratio > want * 0.93,
        "ratio {ratio}, want about {want}"
    );
}

/// Sunlight through the water surface into a scattering medium: the light
/// shafts (L S+ V) and the floor's caustic (L S+ D) come from the maps, the
/// rest from paths; pure path tracing at many more samples agrees, with the
/// floor's estimate interpolated from precomputed irradiance (the default)
/// and gathered at every vertex. The in-scattered light is about a third of
/// the image: leaving the volume map out measures a ratio of 0.64. Sites
/// whose estimate counted their own photon measured +6.8 %.
#[test]
fn volume_and_surface_maps_match_pure_path_tracing_in_water() {
    let mut with_map = scene(&water(0.05, 0.15, false, "caustics = \"map\""));
    with_map.settings.spp = 32;
    let plan = RenderPlan::new(&with_map.scene, &with_map.settings);
    assert!(
        matches!(
            plan.photons,
            PhotonPlan::Run {
                casters: 1,
                gather: GatherMode::Precomputed,
                ..
            }
        ),
        "{:?}",
        plan.photons
    );
    let mut direct = with_map.clone();
    direct.settings.photons.gather = GatherMode::Direct;
    let mut as_paths = with_map.clone();
    as_paths.settings.photons.caustics = CausticsMode::Path;
    as_paths.settings.spp = 8192;
    let p = pixels(&as_paths, 2);
    let mean = |p: &[[f64; 3]]| p.iter().flatten().sum::<f64>() / (p.len() * 3) as f64;
    for (name, map) in [("precomputed", &with_map), ("direct", &direct)] {
        let ratio = mean(&pixels(map, 2)) / mean(&p);
        eprintln!("water, map ({name}) / path: {ratio:.4}");
        assert!((ratio - 1.0).abs() < 0.03, "{name}: mean ratio {ratio}");
    }
}

/// The same image on 1 and 3 threads, and the Whitted integrator ignores
/// the setting (it always uses the map).
#[test]
fn map_caustics_are_deterministic_and_whitted_ignores_the_setting() {
    let mut s = scene(GLASS);
    s.settings.spp = 4;
    s.settings.photons.count = 50_000;
    assert_eq!(pixels(&s, 1), pixels(&s, 3));
    let mut whitted = s.clone();
    whitted.settings.integrator = IntegratorKind::Whitted;
    let mut whitted_path = whitted.clone();
    whitted_path.settings.photons.caustics = CausticsMode::Path;
    assert_eq!(pixels(&whitted, 2), pixels(&whitted_path, 2));
}

#[test]
fn a_bad_caustics_value_names_its_place() {
    let text = GLASS.replace("caustics = \"map\"", "caustics = \"photons\"");
    let err = parse_scene(&text, Path::new("glass.toml")).unwrap_err().to_string();
    assert!(
        err.contains("glass.toml:18:") && err.contains("`path` or `map`"),
        "{err}"
    );
}

/// Photon files hold the Whitted integrator's map: a path render with map
/// caustics refuses one, and `caustic photons` refuses to trace one for it.
#[test]
fn photon_files_are_refused_for_the_path_integrators_maps() {
    let dir = tempfile::tempdir().unwrap();
    let scene_file = dir.path().join("glass.toml");
    std::fs::write(&scene_file, GLASS).unwrap();
    let map = dir.path().join("map.bin");
    let out = caustic(&["photons", scene_file.to_str().unwrap(), "-o", map.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("glass.toml") && err.contains("traced by the render itself"),
        "{err}"
    );
    assert!(!map.exists());
    let png = dir.path().join("out.png");
    let out = caustic(&[
        "render",
        scene_file.to_str().unwrap(),
        "--photon-map",
        map.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--photon-map") && err.contains("traced by the render itself"),
        "{err}"
    );
    assert!(!png.exists());
}

/// A render stopped after some passes and continued from its accumulation
/// (what a checkpoint holds) ends with the uninterrupted image bit for bit,
/// map and water included: the maps are re-traced identically.
#[test]
fn map_caustics_resume_bit_for_bit() {
    use caustic::integrator::{RenderControl, RenderSetup};
    for mut s in [scene(GLASS), scene(&water(0.05, 0.15, false, "caustics = \"map\""))] {
        s.settings.spp = 12;
        s.settings.photons.count = 40_000;
        let accel = accel::build(&s.scene, AccelKind::default_kind(), &AccelOptions::default()).unwrap();
        let plan = RenderPlan::new(&s.scene, &s.settings);
        let full = render(&s.scene, accel.as_ref(), &plan, RenderSetup::default());
        let mut first = RenderControl::to_completion(&|_, _| {});
        first.sample_limit = Some(4);
        let part = render(&s.scene, accel.as_ref(), &plan, RenderSetup::default().control(first));
        assert!(part.accumulation.samples_taken() < full.accumulation.samples_taken());
        let rest = render(
            &s.scene,
            accel.as_ref(),
            &plan,
            RenderSetup::default().continuing(part.accumulation),
        );
        assert_eq!(rest.accumulation, full.accumulation);
    }
}

/// `scenes/shafts.toml`: the volume map puts a shaft of focused light under
/// the floating glass ball. The water column below the ball is brighter than
/// the same rows beside it (1.39 times at 64×36); the Whitted integrator's
/// fog, which has no volume map, shows no such contrast (0.97).
#[test]
fn the_floating_ball_focuses_a_shaft_into_the_water() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/shafts.toml");
    let mut with_shaft = caustic::scene::load_scene(&path).unwrap();
    let s = &mut with_shaft.settings;
    (s.width, s.height, s.spp, s.photons.count) = (64, 36, 4, 2_000_000);
    let px = pixels(&with_shaft, 2);
    let ratio = |px: &[[f64; 3]]| {
        // Rows between the ball and the floor; the column under the ball
        // against columns a quarter of the image to either side.
        let under = region_mean(px, 64, (30, 34, 16, 24));
        let beside = (region_mean(px, 64, (14, 18, 16, 24)) + region_mean(px, 64, (46, 50, 16, 24))) / 2.0;
        under / beside
    };
    let shaft = ratio(&px);
    eprintln!("shaft: under the ball / beside it {shaft:.3}");
    assert!(shaft > 1.15, "no shaft under the ball: {shaft}");
    // The Whitted integrator's fog has no shaft.
    let mut whitted = with_shaft.clone();
    whitted.settings.integrator = IntegratorKind::Whitted;
    let flat = ratio(&pixels(&whitted, 2));
    eprintln!("whitted: {flat:.3}");
    assert!(
        flat < shaft - 0.1,
        "the fog shows the same contrast: {flat} against {shaft}"
    );
}
