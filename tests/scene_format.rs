//! The scene format: every documented key parses into the validated scene,
//! defaults are the documented ones, and the shipped test scenes load.

use caustic::accel::TriangleTest;
use caustic::math::Vec3A;
use caustic::scene::LoadedScene;
use caustic::scene::{load_scene, parse_scene, Light, SampleSharing, SceneError, ShadingModel, Shape, ToneMap};
use std::path::Path;

fn parse(text: &str) -> LoadedScene {
    parse_scene(text, Path::new("test.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Vec3A, b: Vec3A) -> bool {
    (a - b).length() < 1e-5
}

const EVERY_KEY: &str = r#"
[render]
width = 320
height = 200
spp = 9
max_depth = 6
seed = 1234567890123
tone_map = "clamp"
exposure = -1.5
ambient = [0.1, 0.2, 0.3]
triangle_test = "moller-trumbore"
sharing = "split"

[camera]
position = [1, 2, 3]
look_at = [1, 2, -7]
up = [0, 1, 0]
vfov = 30.5

[materials.shiny]
model = "phong"
ambient = [0.1, 0.1, 0.1]
diffuse = [0.5, 0.4, 0.3]
specular = [0.9, 0.9, 0.9]
shininess = 120
mirror = { reflectivity = 0.25, tint = [1.0, 0.9, 0.8] }

[materials.glass]
model = "blinn-phong"
diffuse = [0, 0, 0]

[materials.glass.dielectric]
ior = 1.33
tint = [0.9, 1.0, 1.0]

[[lights]]
type = "point"
position = [0, 5, 0]
colour = [1.0, 0.5, 0.25]
intensity = 8

[[lights]]
type = "area"
position = [0, 4, 0]
u = [2, 0, 0]
v = [0, 0, 1]
color = [1, 1, 1]
intensity = 3
samples = 48

[[objects]]
name = "ball"
type = "sphere"
center = [0, 1, -2]
radius = 1.5
material = "glass"

[[objects]]
type = "quad"
corner = [-1, 0, 1]
u = [2, 0, 0]
v = [0, 0, -2]
material = "shiny"

[[objects]]
name = "floor"
type = "quad"
center = [0, 0, 0]
size = [4, 2]
normal = [0, 1, 0]
material = "shiny"

[[objects]]
name = "wall"
type = "quad"
center = [0, 1, -5]
size = [6, 2]
normal = [1, 0, 0]
up = [0, 0, 1]
material = "shiny"

[[objects]]
name = "tilted"
type = "quad"
center = [3, 3, 3]
size = [1, 3]
rotate = [-90, 0, 0]
material = "shiny"
"#;

#[test]
fn every_documented_key_is_parsed() {
    let s = parse(EVERY_KEY);
    let r = &s.settings;
    assert_eq!(
        (r.width, r.height, r.spp, r.max_depth, r.seed),
        (320, 200, 9, Some(6), 1234567890123)
    );
    assert_eq!(r.output.tone_map, ToneMap::Clamp);
    assert_eq!(r.output.exposure, -1.5);
    assert!(close(s.scene.ambient, Vec3A::new(0.1, 0.2, 0.3)));
    assert_eq!(r.triangle_test, TriangleTest::MollerTrumbore);
    assert_eq!(r.sharing, SampleSharing::Split);

    assert!(close(s.scene.camera.position, Vec3A::new(1.0, 2.0, 3.0)));
    assert!(close(s.scene.camera.forward, -Vec3A::Z));
    assert!(close(s.scene.camera.up, Vec3A::Y));
    assert_eq!(s.scene.camera.fov_deg, 30.5);

    // Materials are indexed in name order.
    let names: Vec<_> = s.scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["glass", "shiny"]);
    let shiny = &s.scene.materials[1];
    assert_eq!(shiny.model, ShadingModel::Phong);
    assert!(close(shiny.ambient, Vec3A::splat(0.1)));
    assert!(close(shiny.diffuse, Vec3A::new(0.5, 0.4, 0.3)));
    assert!(close(shiny.specular, Vec3A::splat(0.9)));
    assert_eq!(shiny.shininess, 120.0);
    let m = shiny.mirror.unwrap();
    assert_eq!(m.reflectivity, 0.25);
    assert!(close(m.tint, Vec3A::new(1.0, 0.9, 0.8)));
    assert!(shiny.dielectric.is_none());
    let glass = &s.scene.materials[0];
    assert_eq!(glass.model, ShadingModel::BlinnPhong);
    let d = glass.dielectric.unwrap();
    assert_eq!(d.ior, 1.33);
    assert!(close(d.tint, Vec3A::new(0.9, 1.0, 1.0)));
    let flags = caustic::bsdf::whitted_flags(glass);
    assert!(
        flags.contains(caustic::bsdf::LobeFlags::CASTS_CAUSTICS) && !flags.contains(caustic::bsdf::LobeFlags::DIFFUSE)
    );

    match &s.scene.lights[0] {
        Light::Point { position, intensity } => {
            assert!(close(*position, Vec3A::new(0.0, 5.0, 0.0)));
            assert!(close(*intensity, Vec3A::new(8.0, 4.0, 2.0)));
        }
        l => panic!("{l:?}"),
    }
    match &s.scene.lights[1] {
        Light::Area(a) => {
            assert!(close(a.center, Vec3A::new(0.0, 4.0, 0.0)));
            assert!(close(a.u, Vec3A::new(2.0, 0.0, 0.0)) && close(a.v, Vec3A::Z));
            // Emits toward u × v: down.
            assert!(close(a.normal, -Vec3A::Y));
            assert!(close(a.radiance, Vec3A::splat(3.0)));
            assert_eq!(a.samples, 48);
        }
        l => panic!("{l:?}"),
    }

    assert_eq!(s.scene.objects.len(), 5);
    assert_eq!(s.scene.objects[0].name, "ball");
    assert_eq!(s.scene.objects[0].material, 0);
    match &s.scene.objects[0].shape {
        Shape::Sphere(sp) => {
            assert!(close(sp.center, Vec3A::new(0.0, 1.0, -2.0)));
            assert_eq!(sp.radius, 1.5);
        }
        o => panic!("{o:?}"),
    }
    // Unnamed objects get `type#index`.
    assert_eq!(s.scene.objects[1].name, "quad#1");
    assert_eq!(s.scene.objects[1].material, 1);
    let quad = |i: usize| match &s.scene.objects[i].shape {
        Shape::Quad(q) => *q,
        o => panic!("{o:?}"),
    };
    let q = quad(1);
    assert!(close(q.corner, Vec3A::new(-1.0, 0.0, 1.0)));
    assert!(close(q.normal, Vec3A::Y));
    // Floor: width along +x, height along −z (the default `up` for a quad
    // facing ±y), centred on `center`.
    let q = quad(2);
    assert!(close(q.u, Vec3A::new(4.0, 0.0, 0.0)), "{q:?}");
    assert!(close(q.v, Vec3A::new(0.0, 0.0, -2.0)), "{q:?}");
    assert!(close(q.normal, Vec3A::Y));
    assert!(close(q.corner + (q.u + q.v) * 0.5, Vec3A::ZERO));
    // Wall facing +x with its height along +z.
    let q = quad(3);
    assert!(close(q.normal, Vec3A::X));
    assert!(close(q.v, Vec3A::new(0.0, 0.0, 2.0)));
    assert!(close(q.u, Vec3A::new(0.0, 6.0, 0.0)), "{q:?}");
    // rotate = [-90, 0, 0] turns the canonical +z-facing quad to face +y;
    // its height (canonical +y) then runs along −z.
    let q = quad(4);
    assert!(close(q.normal, Vec3A::Y), "{q:?}");
    assert!(close(q.u, Vec3A::X), "{q:?}");
    assert!(close(q.v, Vec3A::new(0.0, 0.0, -3.0)), "{q:?}");
    assert!(close(q.corner + (q.u + q.v) * 0.5, Vec3A::splat(3.0)));
    assert!(s.scene.meshes.is_empty());
}

#[test]
fn defaults_are_the_documented_ones() {
    let s = parse(
        r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]

[materials.plain]

[[lights]]
type = "point"
position = [0, 5, 0]

[[lights]]
type = "area"
position = [0, 4, 0]
u = [1, 0, 0]
v = [0, 0, 1]
"#,
    );
    let r = &s.settings;
    assert_eq!((r.width, r.height, r.spp, r.max_depth, r.seed), (640, 480, 1, None, 0));
    assert_eq!(r.output.tone_map, ToneMap::Aces);
    assert_eq!(r.output.exposure, 0.0);
    assert_eq!(s.scene.ambient, Vec3A::ZERO);
    assert_eq!(r.triangle_test, TriangleTest::Watertight);
    assert_eq!(r.sharing, SampleSharing::Spread);
    assert_eq!(s.scene.camera.fov_deg, 45.0);
    assert!(close(s.scene.camera.up, Vec3A::Y));
    let m = &s.scene.materials[0];
    assert_eq!(m.model, ShadingModel::BlinnPhong);
    assert!(close(m.diffuse, Vec3A::splat(0.8)));
    assert!(close(m.ambient, m.diffuse), "ambient defaults to diffuse");
    assert_eq!(m.specular, Vec3A::ZERO);
    assert_eq!(m.shininess, 32.0);
    assert!(m.mirror.is_none() && m.dielectric.is_none());
    assert_eq!(
        s.scene.lights[0],
        Light::Point {
            position: Vec3A::new(0.0, 5.0, 0.0),
            intensity: Vec3A::ONE
        }
    );
    match &s.scene.lights[1] {
        Light::Area(a) => {
            // The original report's 32 shadow rays.
            assert_eq!(a.samples, 32);
            assert_eq!(a.radiance, Vec3A::ONE);
        }
        l => panic!("{l:?}"),
    }
    assert!(s.scene.objects.is_empty());
}

#[test]
fn sub_table_defaults_and_numbers_as_integers() {
    let s = parse(
        r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
[materials.m.mirror]
[materials.g.dielectric]
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 2
material = "m"
"#,
    );
    let g = &s.scene.materials[0];
    assert_eq!(g.dielectric.unwrap().ior, 1.5);
    assert_eq!(g.dielectric.unwrap().tint, Vec3A::ONE);
    let m = &s.scene.materials[1];
    assert_eq!(m.mirror.unwrap().reflectivity, 1.0);
    assert_eq!(m.mirror.unwrap().tint, Vec3A::ONE);
    assert_eq!(s.scene.objects[0].material, 1);
}

/// `[materials.NAME.disney]` alone is Mitsuba's `principled` with its
/// defaults (base colour 0.5, `specular` 0.5), with `thin = true` its
/// `principledthin` (index 1.5); `specular` sets the index as Mitsuba does,
/// and a refracting index of 1 becomes 1.001.
#[test]
fn disney_tables_take_mitsuba_defaults() {
    let s = parse(
        r#"
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
[materials.a.disney]
[materials.b.disney]
thin = true
[materials.c.disney]
specular = 0.3
[materials.d.disney]
eta = 1
spec_trans = 0.5
[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 2
material = "a"
"#,
    );
    let [a, b, c, d] = [0, 1, 2, 3].map(|i| (s.scene.materials[i].diffuse, s.scene.materials[i].disney.unwrap()));
    assert_eq!(a.0, Vec3A::splat(0.5));
    assert_eq!(a.1, caustic::scene::Disney::default());
    assert_eq!(b.1, caustic::scene::Disney::thin_default());
    assert_eq!(b.1.eta, 1.5);
    assert!(
        (c.1.eta - (2.0 / (1.0 - (0.08f32 * 0.3).sqrt()) - 1.0)).abs() < 1e-6,
        "{:?}",
        c.1
    );
    assert_eq!((d.1.eta, d.1.spec_trans), (1.001, 0.5));
}

#[test]
fn shipped_test_scenes_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                !scene.scene.objects.is_empty() && !scene.scene.lights.is_empty(),
                "{}",
                path.display()
            );
            assert!(scene.scene.meshes.is_empty(), "test scenes use analytic shapes only");
            count += 1;
        }
    }
    assert!(count >= 3, "{count} scenes in {}", dir.display());
}

#[test]
fn shipped_scenes_have_what_their_tests_need() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test");
    let mirror = load_scene(&dir.join("mirror.toml")).unwrap();
    assert!(mirror
        .scene
        .materials
        .iter()
        .any(|m| m.mirror.is_some_and(|m| m.reflectivity > 0.5)));
    let shadow = load_scene(&dir.join("shadow.toml")).unwrap();
    match &shadow.scene.lights[0] {
        Light::Area(a) => assert!(a.normal.y < -0.99, "the light must face the floor"),
        l => panic!("{l:?}"),
    }
    let spheres = load_scene(&dir.join("spheres.toml")).unwrap();
    assert!(matches!(spheres.scene.lights[0], Light::Point { .. }));
    assert_eq!(
        spheres
            .scene
            .objects
            .iter()
            .filter(|o| matches!(o.shape, Shape::Sphere(_)))
            .count(),
        3
    );
}

#[test]
fn scene_bounds_cover_the_objects() {
    let s = parse(EVERY_KEY);
    let b = s.scene.bounds();
    // The wall (centre y = 1, 6 high along y) spans y ∈ [−2, 4].
    assert!((b.min.y + 2.0).abs() < 1e-5 && (b.max.y - 4.0).abs() < 1e-5, "{b:?}");
}

fn docs() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md")).unwrap()
}

/// The complete example of `docs/scene-format.md`.
fn documented_example() -> String {
    let doc = docs();
    let body = &doc[doc.find("<!-- complete-example -->").expect("marker")..];
    let begin = body.find("```toml\n").unwrap() + "```toml\n".len();
    let end = body[begin..].find("```").unwrap();
    body[begin..begin + end].to_string()
}

/// Every key the parser knows appears in a table row of the documentation:
/// the parser's own "expected one of …" list is the source of truth.
#[test]
fn documentation_covers_every_key() {
    let doc = docs();
    let cam = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n";
    let probes = [
        format!("{cam}[render]\nzzz = 1\n"),
        format!("{cam}zzz = 1\n"),
        format!("{cam}[materials.m]\nzzz = 1\n"),
        format!("{cam}[materials.m.mirror]\nzzz = 1\n"),
        format!("{cam}[materials.m.dielectric]\nzzz = 1\n"),
        format!("{cam}[materials.m.blend]\nzzz = 1\n"),
        format!("{cam}[materials.m.coating]\nzzz = 1\n"),
        format!("{cam}[materials.m.principled]\nzzz = 1\n"),
        format!("{cam}[[lights]]\nzzz = 1\n"),
        format!("{cam}[[objects]]\nzzz = 1\n"),
        format!("{cam}[media.m]\nzzz = 1\n"),
        "zzz = 1\n".to_string(),
    ];
    let mut checked = 0;
    for probe in probes {
        let msg = parse_scene(&probe, Path::new("probe.toml")).unwrap_err().to_string();
        let list = &msg[msg.find("expected").unwrap_or_else(|| panic!("{msg}"))..];
        for key in list.split('`').skip(1).step_by(2) {
            assert!(
                doc.contains(&format!("| `{key}` "))
                    || doc.contains(&format!("(or `{key}`)"))
                    || doc.contains(&format!("`[{key}"))
                    || doc.contains(&format!("`[[{key}")),
                "key `{key}` is not documented"
            );
            checked += 1;
        }
    }
    assert!(checked > 40, "{checked}");
}

/// The documented example is valid in every key; its mesh file is not
/// shipped beside the docs, so loading stops at the mesh (tests/scene_meshes.rs
/// loads it with the file present).
#[test]
fn documented_example_is_valid_up_to_its_mesh_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("example.toml");
    match parse_scene(&documented_example(), &path) {
        Err(SceneError::Mesh { object, .. }) => assert_eq!(object, "prism"),
        other => panic!("{other:?}"),
    }
    // Without the mesh objects it loads completely.
    let text = documented_example();
    let cut = text.find("[[objects]]\nname = \"prism\"").unwrap();
    let scene = parse_scene(&text[..cut], &path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.scene.objects.len(), 7);
    assert_eq!(scene.scene.lights.len(), 2);
    assert_eq!(scene.scene.materials.len(), 6);
    // And it is an example to follow: no parameter the integrator ignores.
    let warnings = caustic::integrator::lint::material_warnings(&scene.scene, scene.settings.integrator);
    assert!(warnings.is_empty(), "{warnings:?}");
}

/// Blends copy the materials they name (blends first), and refuse unknown
/// names, blends containing themselves and blends without a side.
#[test]
fn blends_name_other_materials() {
    let head = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n";
    let text = format!(
        "{head}[materials.red]\ndiffuse = [0.8, 0.1, 0.1]\n\n[materials.gold]\nconductor = {{ metal = \"gold\", roughness = 0.2 }}\n\n\
         [materials.mix]\nblend = {{ first = \"red\", second = \"gold\", weight = 0.25 }}\n\n\
         [materials.veil]\nblend = {{ second = \"mix\", weight = 0.4 }}\n"
    );
    let scene = parse_scene(&text, Path::new("blend.toml")).unwrap();
    let by_name = |n: &str| scene.scene.materials.iter().find(|m| m.name == n).unwrap();
    let mix = by_name("mix").blend.as_deref().unwrap();
    assert_eq!(mix.weight, 0.25);
    assert_eq!(mix.first.as_ref().unwrap().diffuse, by_name("red").diffuse);
    assert!(mix.second.as_ref().unwrap().conductor.is_some());
    let veil = by_name("veil").blend.as_deref().unwrap();
    assert!(veil.first.is_none(), "a missing side is a hole");
    assert!(
        veil.second.as_ref().unwrap().blend.is_some(),
        "the blend named is filled in first"
    );
    assert!(by_name("veil").has_holes() && !by_name("mix").has_holes());
    for (body, message) in [
        (
            "[materials.a]\nblend = { first = \"b\" }\n",
            "blend names `b`, which is not a material",
        ),
        (
            "[materials.a]\nblend = { first = \"c\" }\n[materials.c]\nblend = { second = \"a\" }\n",
            "contains itself",
        ),
        (
            "[materials.a]\nblend = { weight = 0.5 }\n",
            "needs `first`, `second` or both",
        ),
        (
            "[materials.a]\ndiffuse = 0.5\n[materials.b]\nblend = { first = \"a\", weight = 2.0 }\n",
            "in [0, 1]",
        ),
    ] {
        let e = parse_scene(&format!("{head}{body}"), Path::new("blend.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(message) && e.contains("blend.toml:"), "{body}: {e}");
    }
}

/// The principled table's keys, their defaults and textures, and its
/// errors.
#[test]
fn principled_materials_read_their_keys() {
    let head = "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n";
    let text = format!(
        "{head}[textures.rough]\ntype = \"checkerboard\"\ncolour0 = 0.2\ncolour1 = 0.7\n\n\
         [materials.paint]\ndiffuse = [0.1, 0.2, 0.6]\n\
         principled = {{ metallic = 0.25, roughness = \"rough\", ior = 1.45, transmission = 0.5, thin = false, \
         clearcoat = 1.0, clearcoat_roughness = 0.1 }}\n\n[materials.plain]\nprincipled = {{}}\n"
    );
    let scene = parse_scene(&text, Path::new("principled.toml")).unwrap_or_else(|e| panic!("{e}"));
    let paint = scene.scene.materials.iter().find(|m| m.name == "paint").unwrap();
    let p = paint.principled.unwrap();
    assert_eq!((p.metallic, p.ior, p.transmission, p.thin), (0.25, 1.45, 0.5, false));
    assert_eq!((p.clearcoat, p.clearcoat_roughness), (1.0, 0.1));
    assert!(paint.textures.as_ref().unwrap().principled_roughness.is_some());
    assert_eq!(paint.diffuse, Vec3A::new(0.1, 0.2, 0.6));
    let plain = scene
        .scene
        .materials
        .iter()
        .find(|m| m.name == "plain")
        .unwrap()
        .principled
        .unwrap();
    assert_eq!((plain.metallic, plain.roughness, plain.ior), (0.0, 0.5, 1.5));
    assert!(plain.thin && plain.transmission == 0.0 && plain.clearcoat == 0.0);
    for (body, message) in [
        (
            "principled = { metallic = 1.5 }",
            "6:27: `metallic` = 1.5 must be in [0, 1]",
        ),
        (
            "principled = { ior = 0.5 }",
            "6:22: principled `ior` = 0.5 must be in [1, 10]",
        ),
        (
            "coating = { ior = 1.5 }\nprincipled = { roughness = 0.2 }",
            "7:14: material `m` has both `coating` and `principled`",
        ),
        ("principled = { sheen = 1 }", "6:16: unknown field `sheen`"),
    ] {
        let e = parse_scene(&format!("{head}[materials.m]\n{body}\n"), Path::new("principled.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("principled.toml:") && e.contains(message), "{body}: {e}");
    }
}
