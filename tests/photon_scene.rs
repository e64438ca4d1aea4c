//! The scene-file side of caustics: `[photons]`, `[medium]`, `type = "water"`,
//! their errors, and the shipped underwater scene.

use caustic::integrator::plan::{FogPlan, PhotonPlan};
use caustic::integrator::RenderPlan;
use caustic::scene::{load_scene, parse_scene, Shape};
use std::path::Path;

const HEAD: &str = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n[materials.m]\n";

fn error(text: &str) -> String {
    parse_scene(text, Path::new("t.toml")).unwrap_err().to_string()
}

#[test]
fn underwater_scene_loads_with_water_fog_and_photons() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/underwater.toml");
    let scene = load_scene(&path).unwrap();
    let water = scene.scene.objects.iter().find(|o| o.name == "water").unwrap();
    let Shape::Mesh { mesh, smooth, .. } = &water.shape else {
        panic!("water is a mesh")
    };
    assert!(smooth);
    assert_eq!(scene.scene.meshes[*mesh as usize].triangles.len(), 384 * 384 * 2);
    let medium = scene.scene.water_medium.as_ref().unwrap();
    assert_eq!(medium.region.max.y, 4.5);
    assert_eq!(medium.region.min.y, 0.0);
    let plan = RenderPlan::new(&scene.scene, &scene.settings);
    assert!(matches!(plan.photons, PhotonPlan::Run { casters: 3, .. }), "{plan}");
    assert!(matches!(plan.fog, FogPlan::Run { .. }));
    let text = plan.to_string();
    assert!(text.contains("fog: ran"), "{text}");
    assert!(text.contains("emission restricted to 3 specular caster(s)"), "{text}");
}

#[test]
fn photon_and_medium_keys_are_read() {
    let text = format!(
        "{HEAD}[photons]\ncount = 1234\nk = 10\nmax_radius = 0.5\ncone_k = 2\n\
         [[objects]]\ntype = \"water\"\nmaterial = \"m\"\ncenter = [0, 2, 0]\nsize = [4, 6]\n\
         resolution = [8, 4]\nwaves = [{{ amplitude = 0.1, wavelength = 2, direction = [1, 1], phase = 90 }}]\n\
         [medium]\ndensity = 0.3\ncolor = [0.1, 0.2, 0.3]\n"
    );
    let scene = parse_scene(&text, Path::new("t.toml")).unwrap();
    let p = &scene.settings.photons;
    assert_eq!((p.count, p.k, p.max_radius, p.cone_k), (1234, 10, Some(0.5), 2.0));
    let m = scene.scene.water_medium.as_ref().unwrap();
    assert_eq!(m.density, 0.3);
    assert_eq!(m.region.max.y, 2.0);
    assert_eq!(scene.scene.meshes[0].triangles.len(), 8 * 4 * 2);
    // The first crest (phase 90°) at the origin: height = amplitude.
    let water_y = scene.scene.meshes[0]
        .positions
        .iter()
        .find(|v| v.x == 0.0 && v.z == 0.0)
        .unwrap()
        .y;
    assert!((water_y - 2.1).abs() < 1e-5, "{water_y}");
}

#[test]
fn bad_photon_medium_and_water_values_are_errors() {
    let cases = [
        (format!("{HEAD}[photons]\ncount = -1\n"), "t.toml:6:9: photon `count` = -1 must be ≥ 0"),
        (format!("{HEAD}[photons]\ncount = 5000000000\n"), "t.toml:6:9: 5000000000 photons: at most"),
        (format!("{HEAD}[photons]\nk = 0\n"), "photon `k` = 0 must be in 1..="),
        (format!("{HEAD}[photons]\ncone_k = 0.5\n"), "`cone_k` = 0.5 must be ≥ 1"),
        (format!("{HEAD}[photons]\nmax_radius = 0\n"), "`max_radius` = 0 must be > 0"),
        (format!("{HEAD}[medium]\ndensity = 1\n"), "the scene needs an object of `type = \"water\"`"),
        (
            format!("{HEAD}[[objects]]\ntype = \"water\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nresolution = [1.5, 2]\n"),
            "both must be integers in 1..=4096",
        ),
        (
            format!("{HEAD}[[objects]]\ntype = \"water\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nresolution = [100000, 2]\n"),
            "both must be integers in 1..=4096",
        ),
        (
            format!("{HEAD}[[objects]]\ntype = \"water\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nwaves = [{{ amplitude = 1, wavelength = 0, direction = [1, 0] }}]\n"),
            "`wavelength` = 0 must be > 0",
        ),
        (
            format!("{HEAD}[[objects]]\ntype = \"water\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nwaves = [{{ amplitude = 1, wavelength = 1, direction = [0, 0] }}]\n"),
            "wave `direction` is the zero vector",
        ),
        (
            format!("{HEAD}[[objects]]\ntype = \"water\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nradius = 2\n"),
            "`radius` does not apply to a water surface",
        ),
        (
            format!("{HEAD}[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nradius = 1\nwaves = []\n"),
            "`waves` does not apply to a sphere",
        ),
    ];
    for (text, expected) in cases {
        let e = error(&text);
        assert!(e.contains(expected), "expected `{expected}` in: {e}");
        assert!(e.starts_with("t.toml:"), "{e}");
    }
}

#[test]
fn gather_mode_is_read_and_checked() {
    use caustic::scene::GatherMode;
    let scene = |mode: &str| format!("{HEAD}[photons]\ngather = \"{mode}\"\n");
    let direct = parse_scene(&scene("direct"), Path::new("t.toml")).unwrap();
    assert_eq!(direct.settings.photons.gather, GatherMode::Direct);
    let pre = parse_scene(&scene("precomputed"), Path::new("t.toml")).unwrap();
    assert_eq!(pre.settings.photons.gather, GatherMode::Precomputed);
    let e = error(&scene("fast"));
    assert!(e.contains("t.toml:6:") && e.contains("fast"), "{e}");
}
