//! Bad scene files: every error names the file, the line and column of the
//! offending key or value, and what is wrong.

use caustic::scene::{load_scene, parse_scene, SceneError};
use std::path::Path;

/// A valid camera on lines 1–3; test cases append from line 4.
const CAMERA: &str = "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n";

/// A material `m` on lines 4–5; objects and lights append from line 6.
const CAMERA_AND_MATERIAL: &str =
    "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\n[materials.m]\ndiffuse = [0.5, 0.5, 0.5]\n";

const FILE: &str = "scenes/bad.toml";

/// Parses `text` as `scenes/bad.toml` and checks that the error is at
/// `line:col` and that its message contains `needle`.
#[track_caller]
fn expect_error(text: &str, line: usize, col: usize, needle: &str) -> SceneError {
    let err = match parse_scene(text, Path::new(FILE)) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    };
    let msg = err.to_string();
    let prefix = format!("{FILE}:{line}:{col}: ");
    assert!(msg.starts_with(&prefix), "expected `{prefix}…`, got `{msg}`");
    assert!(msg.contains(needle), "expected `{needle}` in `{msg}`");
    assert!(!msg.contains('\n'), "one line: `{msg}`");
    let place = err.place().unwrap();
    assert_eq!((place.line, place.column), (line, col));
    assert_eq!(err.path(), Path::new(FILE));
    err
}

#[test]
fn toml_syntax_error() {
    expect_error(&format!("{CAMERA}[render\nwidth = 3\n"), 4, 8, "invalid table header");
    expect_error(&format!("{CAMERA}[render]\nwidth = \n"), 5, 9, "");
    expect_error(
        &format!("{CAMERA}[render]\nwidth = 3\nwidth = 4\n"),
        6,
        1,
        "duplicate key",
    );
}

#[test]
fn unknown_key_in_every_table_kind() {
    expect_error(&format!("{CAMERA}[render]\nwidht = 5\n"), 5, 1, "unknown field `widht`");
    expect_error(&format!("{CAMERA}fov_deg = 40\n"), 4, 1, "unknown field `fov_deg`");
    expect_error(
        &format!("{CAMERA}[materials.m]\nbogus = 1\n"),
        5,
        1,
        "unknown field `bogus`",
    );
    expect_error(
        &format!("{CAMERA}[materials.m.mirror]\nshine = 1\n"),
        5,
        1,
        "unknown field `shine`",
    );
    expect_error(
        &format!("{CAMERA}[materials.g]\ndielectric = {{ ior = 1.5, tnit = [1, 1, 1] }}\n"),
        5,
        27,
        "unknown field `tnit`",
    );
    expect_error(
        &format!("{CAMERA}[[lights]]\ntype = \"point\"\nposition = [0, 5, 0]\nradius = 1\n"),
        7,
        1,
        "unknown field `radius`",
    );
    expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncentre = [0, 0, 0]\n"),
        9,
        1,
        "unknown field `centre`",
    );
    expect_error(
        &format!("{CAMERA}[photon]\ncount = 5\n"),
        4,
        2,
        "unknown field `photon`",
    );
}

#[test]
fn key_of_another_type_is_rejected() {
    expect_error(
        &format!(
            "{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"quad\"\nmaterial = \"m\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [0, 1, 0]\nradius = 2\n"
        ),
        12,
        10,
        "`radius` does not apply to a quad",
    );
    expect_error(
        &format!("{CAMERA}[[lights]]\ntype = \"point\"\nposition = [0, 5, 0]\nsamples = 8\n"),
        7,
        11,
        "`samples` does not apply to a point light",
    );
}

#[test]
fn wrong_types() {
    expect_error(
        &format!("{CAMERA}[render]\nwidth = \"wide\"\n"),
        5,
        9,
        "invalid type: string \"wide\"",
    );
    expect_error(
        &format!("{CAMERA}[render]\nspp = 2.5\n"),
        5,
        7,
        "invalid type: floating point",
    );
    expect_error(&format!("{CAMERA}[render]\nwidth = -5\n"), 5, 9, "expected u32");
    expect_error(
        &format!(
            "{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [1, 2]\nradius = 1\n"
        ),
        9,
        10,
        "expected an array of 3 numbers, found 2 elements",
    );
    expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [1, 2, \"x\"]\n"),
        9,
        17,
        "invalid type: string \"x\"",
    );
    expect_error(
        &format!("{CAMERA}[materials.m]\nmirror = 0.5\n"),
        5,
        10,
        "invalid type: floating point",
    );
}

#[test]
fn unknown_enum_values() {
    expect_error(
        &format!("{CAMERA}[render]\ntone_map = \"reinhard\"\n"),
        5,
        12,
        "unknown variant `reinhard`",
    );
    expect_error(
        &format!("{CAMERA}[render]\ntriangle_test = \"fast\"\n"),
        5,
        17,
        "expected `watertight` or `moller-trumbore`",
    );
    expect_error(
        &format!("{CAMERA}[render]\nsharing = \"both\"\n"),
        5,
        11,
        "unknown variant `both`",
    );
    expect_error(
        &format!("{CAMERA}[materials.m]\nmodel = \"lambert\"\n"),
        5,
        9,
        "unknown variant `lambert`",
    );
    expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"cube\"\nmaterial = \"m\"\n"),
        7,
        8,
        "unknown variant `cube`",
    );
    expect_error(
        &format!("{CAMERA}[[lights]]\ntype = \"laser\"\nposition = [0, 0, 0]\n"),
        5,
        8,
        "unknown variant `laser`",
    );
}

#[test]
fn missing_keys() {
    // Required by the parser: reported at the table that lacks it.
    expect_error("[camera]\nposition = [0, 1, 5]\n", 1, 1, "missing field `look_at`");
    expect_error("[render]\nwidth = 10\n", 1, 1, "missing field `camera`");
    expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\n"),
        6,
        1,
        "missing field `material`",
    );
    // Required by the object's type: reported at its `type`.
    expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\n"),
        7,
        8,
        "a sphere needs `radius`",
    );
    expect_error(
        &format!("{CAMERA}[[lights]]\ntype = \"area\"\nposition = [0, 5, 0]\nu = [1, 0, 0]\n"),
        5,
        8,
        "an area light needs `v`",
    );
    expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"mesh\"\nmaterial = \"m\"\n"),
        7,
        8,
        "a mesh needs `file`",
    );
    expect_error(
        &format!(
            "{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"quad\"\nmaterial = \"m\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\n"
        ),
        9,
        10,
        "needs `v`",
    );
}

#[test]
fn missing_material_points_at_the_reference() {
    let err = expect_error(
        &format!("{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\nmaterial = \"gold\"\ncenter = [0, 0, 0]\nradius = 1\n"),
        8,
        12,
        "unknown material `gold` (defined: `m`)",
    );
    assert!(matches!(err, SceneError::UnknownMaterial { .. }));
    expect_error(
        &format!("{CAMERA}[[objects]]\ntype = \"sphere\"\nmaterial = \"gold\"\ncenter = [0, 0, 0]\nradius = 1\n"),
        6,
        12,
        "(defined: none)",
    );
}

#[test]
fn nan_and_infinity_literals() {
    expect_error(
        &format!(
            "{CAMERA_AND_MATERIAL}[[objects]]\ntype = \"sphere\"\nmaterial = \"m\"\ncenter = [0, 0, 0]\nradius = nan\n"
        ),
        10,
        10,
        "`radius` is NaN",
    );
    expect_error(
        "[camera]\nposition = [inf, 1, 5]\nlook_at = [0, 0, 0]\n",
        2,
        12,
        "`position` is infinite",
    );
    expect_error(
        &format!("{CAMERA}[render]\nexposure = -inf\n"),
        5,
        12,
        "`exposure` is infinite",
    );
    expect_error(
        &format!("{CAMERA}[materials.m]\nshininess = +nan\n"),
        5,
        13,
        "`shininess` is NaN",
    );
    // Finite in TOML (f64) but not in f32.
    expect_error(
        &format!("{CAMERA}[[lights]]\ntype = \"point\"\nposition = [0, 1e300, 0]\n"),
        6,
        12,
        "too large",
    );
}

#[test]
fn invalid_shapes() {
    let obj = |body: &str| format!("{CAMERA_AND_MATERIAL}[[objects]]\nmaterial = \"m\"\n{body}");
    // Lines: 6 [[objects]], 7 material, 8.. body.
    expect_error(
        &obj("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = -1\n"),
        10,
        10,
        "sphere `radius` = -1 must be > 0",
    );
    expect_error(
        &obj("type = \"sphere\"\ncenter = [0, 0, 0]\nradius = 0\n"),
        10,
        10,
        "must be > 0",
    );
    expect_error(
        &obj("type = \"quad\"\ncenter = [0, 0, 0]\nsize = [0, 1]\nnormal = [0, 1, 0]\n"),
        10,
        8,
        "degenerate quad: `size` = [0, 1] must be positive",
    );
    expect_error(
        &obj("type = \"quad\"\ncorner = [0, 0, 0]\nu = [1, 0, 0]\nv = [2, 0, 0]\n"),
        11,
        5,
        "degenerate quad: `u` and `v` are parallel",
    );
    expect_error(
        &obj("type = \"quad\"\ncorner = [0, 0, 0]\nu = [0, 0, 0]\nv = [2, 0, 0]\n"),
        10,
        5,
        "degenerate quad: `u` is the zero vector",
    );
    expect_error(
        &obj("type = \"quad\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nnormal = [0, 0, 0]\n"),
        11,
        10,
        "`normal` is the zero vector",
    );
    expect_error(
        &obj("type = \"quad\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nnormal = [0, 0, 1]\nup = [0, 0, -2]\n"),
        12,
        6,
        "`up` is parallel to its `normal`",
    );
    expect_error(
        &obj("type = \"quad\"\ncenter = [0, 0, 0]\nsize = [1, 1]\nnormal = [0, 0, 1]\nrotate = [0, 90, 0]\n"),
        12,
        10,
        "either as `normal` (+ `up`) or as `rotate`",
    );
    expect_error(
        &obj("type = \"mesh\"\nfile = \"m.off\"\nscale = [1, 0, 1]\n"),
        10,
        9,
        "`scale` is zero on an axis",
    );
}

#[test]
fn invalid_lights() {
    let light = |body: &str| format!("{CAMERA}[[lights]]\ntype = \"area\"\nposition = [0, 5, 0]\n{body}");
    // Lines: 4 [[lights]], 5 type, 6 position, 7.. body.
    expect_error(&light("u = [0, 0, 0]\nv = [0, 0, 1]\n"), 7, 5, "`u` is the zero vector");
    expect_error(
        &light("u = [1, 0, 0]\nv = [-3, 0, 0]\n"),
        8,
        5,
        "edges `u` and `v` are parallel",
    );
    expect_error(
        &light("u = [1, 0, 0]\nv = [0, 0, 1]\nsamples = 0\n"),
        9,
        11,
        "`samples` = 0 is out of range",
    );
    expect_error(
        &light("u = [1, 0, 0]\nv = [0, 0, 1]\nintensity = -2\n"),
        9,
        13,
        "`intensity` = -2 must be ≥ 0",
    );
    expect_error(
        &light("u = [1, 0, 0]\nv = [0, 0, 1]\ncolour = [1, -1, 1]\n"),
        9,
        10,
        "negative component",
    );
}

#[test]
fn invalid_materials() {
    let mat = |body: &str| format!("{CAMERA}[materials.m]\n{body}");
    expect_error(&mat("dielectric = { ior = 0 }\n"), 5, 22, "`ior` = 0 must be > 0");
    expect_error(&mat("dielectric = { ior = -1.5 }\n"), 5, 22, "`ior` = -1.5 must be > 0");
    expect_error(&mat("diffuse = [1.5, 0.5, 0.5]\n"), 5, 11, "reflectances are in [0, 1]");
    expect_error(
        &mat("mirror = { reflectivity = 1.2 }\n"),
        5,
        27,
        "`reflectivity` = 1.2 must be in [0, 1]",
    );
    expect_error(&mat("shininess = 0\n"), 5, 13, "`shininess` = 0 must be > 0");
    expect_error(
        &mat("mirror = { reflectivity = 1 }\ndielectric = { ior = 1.5 }\n"),
        6,
        14,
        "both `mirror` and `dielectric`",
    );
}

/// `[materials.NAME.disney]`: each bad value at its place, the keys of the
/// other variant at the table.
#[test]
fn invalid_disney_parameters() {
    let mat = |body: &str| format!("{CAMERA}[materials.m]\n{body}");
    expect_error(
        &mat("disney = { roughness = 1.5 }\n"),
        5,
        24,
        "`roughness` = 1.5 must be in [0, 1]",
    );
    expect_error(
        &mat("disney = { thin = true, diff_trans = 2.5 }\n"),
        5,
        38,
        "`diff_trans` = 2.5 must be in [0, 2]",
    );
    expect_error(
        &mat("disney = { thin = true, metallic = 0.5 }\n"),
        5,
        10,
        "`metallic` is not a parameter of a thin Disney BSDF",
    );
    expect_error(
        &mat("disney = { diff_trans = 0.5 }\n"),
        5,
        10,
        "`diff_trans` is not a parameter of a (not thin) Disney BSDF",
    );
    expect_error(
        &mat("disney = { eta = 1.4, specular = 0.5 }\n"),
        5,
        18,
        "give `eta` or `specular`, not both",
    );
    expect_error(
        &mat("disney = { specular = 12.5 }\n"),
        5,
        23,
        "`specular` = 12.5 must be in [0, 12.5)",
    );
    expect_error(&mat("disney = { eta = 0 }\n"), 5, 18, "`eta` = 0 must be > 0");
    expect_error(
        &mat("disney = { eta = { type = \"checkerboard\" } }\n"),
        5,
        18,
        "only a thin Disney BSDF takes a texture",
    );
    expect_error(
        &mat("disney = { sheen = [0.5, 0.5, 0.5] }\n"),
        5,
        20,
        "`sheen` is a number or a texture, not a colour",
    );
    expect_error(
        &mat("disney = { specular_sampling_rate = -1 }\n"),
        5,
        37,
        "`specular_sampling_rate` = -1 must be ≥ 0",
    );
    expect_error(
        &mat("principled = { metallic = 1 }\ndisney = { sheen = 1 }\n"),
        6,
        10,
        "both `principled` and `disney`",
    );
}

#[test]
fn degenerate_camera() {
    expect_error(
        "[camera]\nposition = [1, 2, 3]\nlook_at = [1, 2, 3]\n",
        3,
        11,
        "the camera has no viewing direction",
    );
    expect_error(
        "[camera]\nposition = [0, 0, 0]\nlook_at = [0, 5, 0]\nup = [0, 2, 0]\n",
        4,
        6,
        "`up` is parallel to the viewing direction",
    );
    expect_error(
        "[camera]\nposition = [0, 5, 0]\nlook_at = [0, 0, 0]\n",
        3,
        11,
        "the default `up` [0, 1, 0] is parallel",
    );
    expect_error(
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 0, 0]\n",
        4,
        6,
        "`up` is the zero vector",
    );
    expect_error(
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 180\n",
        4,
        8,
        "`vfov` = 180° must be in (0, 180)",
    );
}

#[test]
fn absurd_render_settings() {
    expect_error(
        &format!("{CAMERA}[render]\nwidth = 100000\n"),
        5,
        9,
        "`width` = 100000 is out of range",
    );
    expect_error(
        &format!("{CAMERA}[render]\nwidth = 0\n"),
        5,
        9,
        "`width` = 0 is out of range",
    );
    expect_error(
        &format!("{CAMERA}[render]\nspp = 0\n"),
        5,
        7,
        "`spp` = 0 is out of range",
    );
    // 65536² pixels: 256 GiB of film, refused before any allocation.
    expect_error(
        &format!("{CAMERA}[render]\nwidth = 65536\nheight = 65536\n"),
        5,
        9,
        "GiB of film",
    );
    // 4096² pixels × 100000 spp = 1.7e12 camera samples > 2^40.
    expect_error(
        &format!("{CAMERA}[render]\nwidth = 4096\nheight = 4096\nspp = 100000\n"),
        7,
        7,
        "camera samples, more than the limit of 2^40",
    );
    expect_error(
        &format!("{CAMERA}[render]\nmax_depth = 1000\n"),
        5,
        13,
        "`max_depth` = 1000 is out of range",
    );
    expect_error(&format!("{CAMERA}[render]\nexposure = 100\n"), 5, 12, "out of range");
    expect_error(
        &format!("{CAMERA}[render]\nambient = [-0.1, 0, 0]\n"),
        5,
        11,
        "negative component",
    );
}

#[test]
fn missing_mesh_file_names_the_key_and_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        format!("{CAMERA_AND_MATERIAL}[[objects]]\nname = \"prism\"\ntype = \"mesh\"\nmaterial = \"m\"\nfile = \"missing/star.off\"\n"),
    )
    .unwrap();
    let err = load_scene(&scene).unwrap_err();
    let msg = err.to_string();
    let prefix = format!("{}:10:8: mesh of object `prism`: ", scene.display());
    assert!(msg.starts_with(&prefix), "{msg}");
    // The mesh error names the resolved mesh path (relative to the scene file).
    assert!(
        msg.contains(&dir.path().join("missing/star.off").display().to_string()),
        "{msg}"
    );
    assert!(matches!(err, SceneError::Mesh { .. }));
}

#[test]
fn missing_scene_file() {
    let err = load_scene(Path::new("no/such/scene.toml")).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.starts_with("no/such/scene.toml: cannot read the scene file: "),
        "{msg}"
    );
    assert!(matches!(&err, SceneError::Read { error, .. } if error.kind() == std::io::ErrorKind::NotFound));
    assert_eq!(err.place(), None);
}

#[test]
fn directory_as_scene_path() {
    let dir = tempfile::tempdir().unwrap();
    let err = load_scene(dir.path()).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!("{}: is a directory, not a scene file", dir.path().display())
    );
}

#[test]
fn non_utf8_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("latin1.toml");
    let mut bytes = CAMERA.as_bytes().to_vec();
    bytes.extend_from_slice(b"# caf\xe9\n");
    std::fs::write(&path, bytes).unwrap();
    let err = load_scene(&path).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!("{}:4:6: the scene file is not valid UTF-8 text", path.display())
    );
}

#[test]
fn oversized_scene_file_is_not_read_whole() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.toml");
    let file = std::fs::File::create(&path).unwrap();
    // Sparse: no disk space used.
    file.set_len(caustic::scene::load::MAX_SCENE_FILE_BYTES + 1).unwrap();
    let err = load_scene(&path).unwrap_err();
    assert!(
        err.to_string().contains("the scene file is larger than 16777216 bytes"),
        "{err}"
    );
}

#[test]
fn load_scene_reports_places_too() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, format!("{CAMERA}[render]\nspp = \"many\"\n")).unwrap();
    let msg = load_scene(&path).unwrap_err().to_string();
    assert!(
        msg.starts_with(&format!("{}:5:7: invalid type", path.display())),
        "{msg}"
    );
}

#[test]
fn material_microfacet_and_sides() {
    expect_error(
        &format!("{CAMERA}[materials.m]\nmicrofacet = \"phong\"\n"),
        5,
        14,
        "expected ggx or beckmann",
    );
    let scene = parse_scene(
        &format!("{CAMERA}[materials.m]\nmicrofacet = \"beckmann\"\none_sided = true\nconductor = {{ metal = \"gold\", roughness = 0.3 }}\n"),
        Path::new(FILE),
    )
    .unwrap();
    let m = &scene.scene.materials[0];
    assert_eq!(m.microfacet, caustic::scene::MicrofacetDistribution::Beckmann);
    assert!(m.one_sided);
}
