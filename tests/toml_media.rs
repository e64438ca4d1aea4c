//! Homogeneous media in caustic's TOML (`[media.NAME]`, objects'
//! `interior` / `exterior`, the camera's `medium`, `null` materials,
//! `integrator = "volpath"`): a scene equal to its Mitsuba XML twin, part
//! by part and pixel for pixel, and the refusals with their place.

mod common;

use common::same::{assert_same_scene, render_small, Names};
use std::path::Path;

const XML: &str = r#"<scene version="3.0.0">
<integrator type="volpath"><integer name="max_depth" value="12"/></integrator>
<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="0.05, 0.06, 0.08"/><float name="albedo" value="0.9"/></medium>
<medium type="homogeneous" id="cloud"><rgb name="sigma_t" value="0.375, 0.625, 1"/><rgb name="albedo" value="0.95, 0.8, 0.6"/><float name="scale" value="4.8"/><phase type="hg"><float name="g" value="0.5"/></phase></medium>
<sensor type="perspective">
  <float name="fov" value="45"/>
  <transform name="to_world"><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
  <ref id="fog"/>
  <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
  <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/><rfilter type="box"/></film>
</sensor>
<shape type="sphere"><float name="radius" value="8"/><bsdf type="null"/><ref name="interior" id="fog"/></shape>
<shape type="sphere"><point name="center" x="-0.7" y="0.1" z="0"/><float name="radius" value="0.6"/><bsdf type="null"/><ref name="interior" id="cloud"/><ref name="exterior" id="fog"/></shape>
<shape type="sphere">
  <point name="center" x="0.75" y="0" z="0.2"/><float name="radius" value="0.5"/>
  <bsdf type="dielectric"><float name="int_ior" value="1.33"/><float name="ext_ior" value="1"/></bsdf>
  <medium type="homogeneous" name="interior"><rgb name="sigma_t" value="0.8, 0.4, 0.2"/><float name="albedo" value="0.5"/><boolean name="sample_emitters" value="false"/></medium>
  <ref name="exterior" id="fog"/>
</shape>
<shape type="sphere"><point name="center" x="0" y="-100.5" z="0"/><float name="radius" value="100"/><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.55, 0.5"/></bsdf></shape>
<shape type="sphere"><point name="center" x="0" y="2" z="0"/><float name="radius" value="0.3"/><emitter type="area"><rgb name="radiance" value="12, 11, 9"/></emitter></shape>
<emitter type="constant"><rgb name="radiance" value="0.25, 0.3, 0.4"/></emitter>
</scene>
"#;

const TOML: &str = r#"[render]
width = 16
height = 16
spp = 4
integrator = "volpath"
max_depth = 11

[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
fov = 45
fov_axis = "x"
focus_distance = 1
near_clip = 0.01
medium = "fog"

[media.fog]
sigma_t = [0.05, 0.06, 0.08]
albedo = 0.9

[media.cloud]
sigma_t = [0.375, 0.625, 1]
albedo = [0.95, 0.8, 0.6]
scale = 4.8
phase = { hg = 0.5 }

[media.water]
sigma_t = [0.8, 0.4, 0.2]
albedo = 0.5
sample_emitters = false

[materials.boundary]
null = true
diffuse = 0
shininess = 1

[materials.glass]
dielectric = { ior = 1.33, fresnel = "exact" }
shininess = 1

[materials.floor]
diffuse = [0.6, 0.55, 0.5]
ambient = 0
shininess = 1
one_sided = true

[materials.lamp]
diffuse = 0
ambient = 0
shininess = 1
one_sided = true
emission = [12, 11, 9]

[[lights]]
type = "environment"
colour = [0.25, 0.3, 0.4]

[[objects]]
type = "sphere"
center = [0, 0, 0]
radius = 8
material = "boundary"
interior = "fog"

[[objects]]
type = "sphere"
center = [-0.7, 0.1, 0]
radius = 0.6
material = "boundary"
interior = "cloud"
exterior = "fog"

[[objects]]
type = "sphere"
center = [0.75, 0, 0.2]
radius = 0.5
material = "glass"
interior = "water"
exterior = "fog"

[[objects]]
type = "sphere"
center = [0, -100.5, 0]
radius = 100
material = "floor"

[[objects]]
type = "sphere"
center = [0, 2, 0]
radius = 0.3
material = "lamp"
"#;

fn toml(text: &str) -> Result<caustic::scene::LoadedScene, String> {
    caustic::scene::parse_scene(text, Path::new("scene.toml")).map_err(|e| e.to_string())
}

#[test]
fn a_toml_scene_with_media_equals_its_mitsuba_twin() {
    let xml = common::mitsuba::load(XML);
    assert!(xml.warnings.is_empty(), "{:?}", xml.warnings);
    let ours = toml(TOML).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(ours.scene.media.list.len(), 3);
    // In name order: cloud, fog, water.
    assert_eq!(ours.scene.media.camera, Some(1));
    let xml = xml.into_loaded();
    assert_same_scene(&xml, &ours, Names::Ignored);
    let (a, b) = (render_small(&xml, 16, 16, 4), render_small(&ours, 16, 16, 4));
    assert!(a.iter().any(|p| p.iter().any(|c| *c > 0.0)));
    assert_eq!(a, b, "the two scenes render differently");
}

#[test]
fn media_keys_are_refused_at_their_place() {
    let cases: &[(&str, &str, &str, &str)] = &[
        (
            "integrator = \"volpath\"",
            "integrator = \"path\"",
            "scene.toml:21:1",
            "rendered by `integrator = \"volpath\"`",
        ),
        (
            "interior = \"cloud\"",
            "interior = \"clod\"",
            "scene.toml:70:12",
            "`interior` names `clod`, which is not in `[media]` (the media are: cloud, fog, water)",
        ),
        (
            "albedo = 0.9",
            "albedo = 1.5",
            "scene.toml:19:10",
            "`albedo` = [1.5, 1.5, 1.5] must be in [0, 1]",
        ),
        (
            "phase = { hg = 0.5 }",
            "phase = { hg = 1 }",
            "scene.toml:25:9",
            "`hg` = 1 must be in (−1, 1)",
        ),
        (
            "phase = { hg = 0.5 }",
            "phase = \"rayleigh\"",
            "scene.toml:25:9",
            "unknown `phase` `rayleigh`",
        ),
        (
            "scale = 4.8",
            "scale = -1",
            "scene.toml:24:9",
            "`scale` = -1 must be ≥ 0",
        ),
        (
            "sigma_t = [0.8, 0.4, 0.2]",
            "sigma_t = [0.8, -0.4, 0.2]",
            "scene.toml:28:11",
            "`sigma_t`",
        ),
        ("medium = \"fog\"", "medium = 3", "scene.toml:15:10", "invalid type"),
        (
            "interior = \"water\"",
            "",
            "scene.toml:27:1",
            "`[media.water]` is not used",
        ),
        (
            "dielectric = { ior = 1.33, fresnel = \"exact\" }",
            "dielectric = { ior = 1.33, fresnel = \"exact\" }\nnull = true",
            "scene.toml:39:8",
            "material `glass` has both `dielectric` and `null`",
        ),
    ];
    for (from, to, place, message) in cases {
        assert!(TOML.contains(from), "{from}");
        let e = toml(&TOML.replacen(from, to, 1)).expect_err(to);
        assert!(e.contains(place) && e.contains(message), "{to}: {e}");
    }
}

/// The example of `[media.NAME]` in the format's documentation loads, with
/// the camera in the fog and the ink inside the glass.
#[test]
fn the_documented_media_example_loads() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene-format.md")).unwrap();
    let section = &doc[doc.find("## `[media.NAME]`").expect("the section")..];
    let begin = section.find("```toml\n").unwrap() + "```toml\n".len();
    let end = section[begin..].find("```").unwrap();
    let scene = toml(&section[begin..begin + end]).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = scene.scene.media.list.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["fog", "ink"]);
    assert_eq!(scene.scene.media.camera, Some(0));
    assert_eq!(scene.scene.media.interface(1).interior, Some(1));
    assert_eq!(scene.scene.media.pass_through, caustic::scene::PassThrough::Volumetric);
    assert!(scene.scene.is_volumetric());
}
