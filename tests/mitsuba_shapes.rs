//! Mitsuba's `disk`, `cylinder`, `shapegroup` and `instance`: hits and
//! texture coordinates against the values Mitsuba 3.9.1 reports for the
//! same XML and rays (`to_world` scaled, mirrored, sheared; `p0`, `p1`,
//! `radius`; `flip_normals`), the same shapes written in TOML, instances
//! sharing their group's meshes and materials, and the refusals with their
//! place (exit code 2 on the command line).

mod common;

use caustic::accel::brute::BruteForce;
use caustic::accel::{Accel, TriangleTest};
use caustic::math::{Ray, Vec2, Vec3A};
use caustic::scene::mitsuba::load_mitsuba_scene;
use caustic::scene::LoadedScene;
use caustic::scene::{parse_scene, Scene, Shape, SurfaceInteraction};
use std::f32::consts::{FRAC_1_SQRT_2, PI, SQRT_2};
use std::path::Path;

const SENSOR: &str = r#"<sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>"#;

/// A textured BSDF, so that shading computes texture coordinates.
const TEXTURED: &str = r#"<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf>"#;

use common::mitsuba::write;

fn scene_text(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n    {SENSOR}\n{body}\n</scene>\n")
}

fn load(body: &str) -> LoadedScene {
    common::mitsuba::load(&scene_text(body)).into_loaded()
}

fn load_error(body: &str) -> String {
    common::mitsuba::error(&scene_text(body))
}

fn shade(scene: &Scene, origin: [f32; 3], dir: [f32; 3]) -> SurfaceInteraction {
    let ray = Ray::new(Vec3A::from(origin), Vec3A::from(dir));
    let hit = BruteForce::new(scene, TriangleTest::Watertight)
        .intersect(&ray, f32::INFINITY)
        .expect("the ray hits");
    scene.surface_interaction(&ray, &hit)
}

fn near(a: Vec3A, b: [f32; 3]) -> bool {
    (a - Vec3A::from(b)).abs().max_element() <= 2e-5
}

/// What Mitsuba 3.9.1 reports for a ray: `si.p`, `si.n`, `si.uv`,
/// `si.dp_du`, `si.dp_dv` (printed by `mi.load_dict` + `ray_intersect`).
struct Expected {
    p: [f32; 3],
    n: [f32; 3],
    uv: [f32; 2],
    dpdu: [f32; 3],
    dpdv: [f32; 3],
}

fn check(shape: &str, origin: [f32; 3], dir: [f32; 3], e: Expected) {
    let scene = load(&shape.replace("BSDF", TEXTURED));
    let si = shade(&scene.scene, origin, dir);
    let uv_ok = (si.uv - Vec2::from(e.uv)).abs().max_element() <= 2e-5;
    assert!(
        near(si.p, e.p) && near(si.ng, e.n) && uv_ok && near(si.dpdu, e.dpdu) && near(si.dpdv, e.dpdv),
        "{shape}\np {} n {} uv {} dpdu {} dpdv {}",
        si.p,
        si.ng,
        si.uv,
        si.dpdu,
        si.dpdv
    );
}

#[test]
fn disks_hit_and_shade_as_in_mitsuba() {
    let (o, d) = ([-0.2, -0.1, 5.0], [0.0, 0.0, -1.0]);
    let disk = |transform: &str, extra: &str| {
        format!(r#"<shape type="disk">{extra}<transform name="to_world">{transform}</transform>BSDF</shape>"#)
    };
    check(
        &disk("", ""),
        o,
        d,
        Expected {
            p: [-0.2, -0.1, 0.0],
            n: [0.0, 0.0, 1.0],
            uv: [0.223607, 0.573792],
            dpdu: [-0.894427, -0.447214, 0.0],
            dpdv: [0.628319, -1.25664, 0.0],
        },
    );
    // Elliptic.
    check(
        &disk(r#"<scale x="2"/>"#, ""),
        o,
        d,
        Expected {
            p: [-0.2, -0.1, 0.0],
            n: [0.0, 0.0, 1.0],
            uv: [0.141421, 0.625],
            dpdu: [-SQRT_2, -FRAC_1_SQRT_2, 0.0],
            dpdv: [1.25664, -0.628318, 0.0],
        },
    );
    // Mirrored: the normal M⁻ᵀ·ẑ stays +z, φ runs the other way.
    check(
        &disk(r#"<scale x="-1"/>"#, ""),
        o,
        d,
        Expected {
            p: [-0.2, -0.1, 0.0],
            n: [0.0, 0.0, 1.0],
            uv: [0.223607, 0.926208],
            dpdu: [-0.894427, -0.447214, 0.0],
            dpdv: [-0.628319, 1.25664, 0.0],
        },
    );
    check(
        &disk("", r#"<boolean name="flip_normals" value="true"/>"#),
        o,
        d,
        Expected {
            p: [-0.2, -0.1, 0.0],
            n: [0.0, 0.0, -1.0],
            uv: [0.223607, 0.573792],
            dpdu: [-0.894427, -0.447214, 0.0],
            dpdv: [0.628319, -1.25664, 0.0],
        },
    );
    // Sheared (x += 0.5 y): still a disk's affine image.
    check(
        &disk(r#"<matrix value="1 0.5 0 0  0 1 0 0  0 0 1 0  0 0 0 1"/>"#, ""),
        o,
        d,
        Expected {
            p: [-0.2, -0.1, 0.0],
            n: [0.0, 0.0, 1.0],
            uv: [0.180278, 0.593584],
            dpdu: [-1.1094, -0.5547, 0.0],
            dpdv: [0.15708, -0.942478, 0.0],
        },
    );
}

#[test]
fn cylinders_hit_and_shade_as_in_mitsuba() {
    let cylinder = |props: &str, transform: &str| {
        format!(r#"<shape type="cylinder">{props}<transform name="to_world">{transform}</transform>BSDF</shape>"#)
    };
    let x_ray = ([5.0, 0.3, 0.5], [-1.0, 0.0, 0.0]);
    check(
        &cylinder("", ""),
        x_ray.0,
        x_ray.1,
        Expected {
            p: [0.953939, 0.3, 0.5],
            n: [0.953939, 0.3, 0.0],
            uv: [0.0484933, 0.5],
            dpdu: [-1.88496, 5.99378, 0.0],
            dpdv: [0.0, 0.0, 1.0],
        },
    );
    check(
        &cylinder(
            r#"<point name="p0" value="0, 0, 0"/><point name="p1" x="0" y="0" z="2"/><float name="radius" value="0.5"/>"#,
            "",
        ),
        x_ray.0,
        x_ray.1,
        Expected {
            p: [0.4, 0.3, 0.5],
            n: [0.8, 0.6, 0.0],
            uv: [0.102416, 0.25],
            dpdu: [-1.88496, 2.51327, 0.0],
            dpdv: [0.0, 0.0, 2.0],
        },
    );
    check(
        &cylinder(r#"<point name="p1" x="2" y="0" z="0"/>"#, ""),
        [0.3, 5.0, 0.5],
        [0.0, -1.0, 0.0],
        Expected {
            p: [0.3, 0.866025, 0.5],
            n: [0.0, 0.866025, 0.5],
            uv: [0.333333, 0.15],
            dpdu: [0.0, -PI, 5.4414],
            dpdv: [2.0, 0.0, 0.0],
        },
    );
    // Mirrored: the normals stay outward.
    check(
        &cylinder("", r#"<scale x="-1"/>"#),
        x_ray.0,
        x_ray.1,
        Expected {
            p: [0.95394, 0.3, 0.5],
            n: [0.953939, 0.3, 0.0],
            uv: [0.451507, 0.5],
            dpdu: [1.88496, -5.99378, 0.0],
            dpdv: [0.0, 0.0, 1.0],
        },
    );
    // Mirrored along the axis, then tilted 30° about y (the near side is
    // past the end: the ray meets the inside of the far wall).
    check(
        &cylinder("", r#"<scale z="-1"/><rotate y="1" angle="30"/>"#),
        [5.0, 0.3, -0.3],
        [-1.0, 0.0, 0.0],
        Expected {
            p: [-1.27472, 0.3, -0.3],
            n: [-0.826136, 0.3, 0.47697],
            uv: [0.451507, 0.897167],
            dpdu: [-1.63242, -5.99378, 0.942478],
            dpdv: [-0.5, 0.0, -0.866025],
        },
    );
    check(
        &cylinder(r#"<boolean name="flip_normals" value="true"/>"#, r#"<scale z="-1"/>"#),
        [5.0, 0.3, -0.3],
        [-1.0, 0.0, 0.0],
        Expected {
            p: [0.95394, 0.3, -0.3],
            n: [-0.953939, -0.3, 0.0],
            uv: [0.0484933, 0.3],
            dpdu: [-1.88496, 5.99378, 0.0],
            dpdv: [0.0, 0.0, -1.0],
        },
    );
}

/// The same disk and cylinder written in TOML and in Mitsuba's XML are the
/// same shapes (a TOML cylinder's azimuth uses Mitsuba's frame about its axis).
#[test]
fn toml_and_mitsuba_give_the_same_shapes() {
    let xml = load(
        r#"<shape type="disk"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="1"/></transform></shape>
           <shape type="cylinder"><point name="p0" value="1, 0, 0"/><point name="p1" value="1, 2, 1"/><float name="radius" value="0.3"/>
           <boolean name="flip_normals" value="true"/></shape>"#,
    );
    let toml = parse_scene(
        "[camera]\nposition = [0.0, 0.0, 9.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40\n[materials.m]\ndiffuse = 0.5\n\
         [[objects]]\ntype = \"disk\"\ncenter = [0.0, 1.0, 0.0]\nradius = 0.5\nrotate = [90.0, 0.0, 0.0]\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [1.0, 0.0, 0.0]\np1 = [1.0, 2.0, 1.0]\nradius = 0.3\nflip_normals = true\nmaterial = \"m\"\n",
        Path::new("same.toml"),
    )
    .unwrap();
    let (Shape::Disk(a), Shape::Disk(b)) = (&xml.scene.objects[0].shape, &toml.scene.objects[0].shape) else {
        panic!()
    };
    let same = |x: Vec3A, y: Vec3A| (x - y).abs().max_element() < 1e-6;
    assert!(same(a.center, b.center) && same(a.a, b.a) && same(a.b, b.b) && same(a.normal, b.normal));
    assert!(same(a.normal, -Vec3A::Y), "{}", a.normal);
    let (Shape::Cylinder(a), Shape::Cylinder(b)) = (&xml.scene.objects[1].shape, &toml.scene.objects[1].shape) else {
        panic!()
    };
    assert!(same(a.base, b.base) && same(a.s, b.s) && same(a.t, b.t) && same(a.axis, b.axis));
    assert!((a.radius - b.radius).abs() < 1e-6 && (a.length - b.length).abs() < 1e-6 && a.inward && b.inward);
}

/// Two instances of a group holding a mesh, a disk and a cylinder: six
/// objects, the mesh and the materials shared, the transforms composed
/// (instance after member); an unreferenced group renders nothing.
#[test]
fn instances_share_their_group_and_compose_transforms() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "tri.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n",
    );
    let body = r#"<shape type="shapegroup" id="g">
            <shape type="obj" id="tri"><string name="filename" value="tri.obj"/>
                <transform name="to_world"><translate x="1"/></transform>
                <bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf></shape>
            <shape type="disk" id="lid"><transform name="to_world"><translate z="2"/></transform></shape>
            <shape type="cylinder" id="tube"><float name="radius" value="0.5"/></shape>
        </shape>
        <shape type="shapegroup" id="unused"><shape type="sphere"/></shape>
        <shape type="instance" id="first"><ref id="g"/></shape>
        <shape type="instance" id="second"><ref id="g"/>
            <transform name="to_world"><rotate z="1" angle="90"/><translate x="10"/></transform></shape>"#;
    let path = write(dir.path(), "scene.xml", &scene_text(body));
    let scene = load_mitsuba_scene(&path, &[])
        .unwrap_or_else(|e| panic!("{e}"))
        .into_loaded();
    let names: Vec<&str> = scene.scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "first/tri",
            "first/lid",
            "first/tube",
            "second/tri",
            "second/lid",
            "second/tube"
        ]
    );
    assert_eq!(scene.scene.meshes.len(), 1, "one mesh for both instances");
    assert_eq!(scene.scene.objects[0].material, scene.scene.objects[3].material);
    assert_eq!(scene.scene.objects[1].material, scene.scene.objects[4].material);
    let Shape::Mesh { mesh, transform, .. } = &scene.scene.objects[3].shape else {
        panic!()
    };
    assert_eq!(*mesh, 0);
    // Member first: (0, 0, 0) → (1, 0, 0), rotated → (0, 1, 0), moved → (10, 1, 0).
    assert!((transform.point(Vec3A::ZERO) - Vec3A::new(10.0, 1.0, 0.0)).length() < 1e-5);
    let Shape::Disk(lid) = &scene.scene.objects[4].shape else {
        panic!()
    };
    assert!((lid.center - Vec3A::new(10.0, 0.0, 2.0)).length() < 1e-5);
    assert!(
        (lid.a - Vec3A::Y).length() < 1e-6,
        "the rotation turns the disk's x axis to +y"
    );
    let Shape::Cylinder(tube) = &scene.scene.objects[5].shape else {
        panic!()
    };
    assert!((tube.base - Vec3A::new(10.0, 0.0, 0.0)).length() < 1e-5 && tube.radius == 0.5);
    // The second instance is where its transform puts it.
    let si = shade(&scene.scene, [10.0, 0.0, 9.0], [0.0, 0.0, -1.0]);
    assert!((si.p - Vec3A::new(10.0, 0.0, 2.0)).length() < 1e-5, "{}", si.p);
}

/// A mirroring instance keeps the faces' fronts (Mitsuba moves the
/// group's normals as normals) and shares the mesh even with
/// `face_normals`; a mirroring `to_world` of the shape itself reverses the
/// winding Mitsuba orients face normals by, as before.
#[test]
fn a_mirroring_instance_keeps_face_normals() {
    let dir = tempfile::tempdir().unwrap();
    // A triangle facing +z by its winding, lying over the origin.
    write(dir.path(), "tri.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n");
    let body = r#"<shape type="shapegroup" id="g">
            <shape type="obj"><string name="filename" value="tri.obj"/><boolean name="face_normals" value="true"/></shape>
        </shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><translate z="1"/></transform></shape>
        <shape type="instance"><ref id="g"/><transform name="to_world"><scale x="-1"/><translate x="3"/></transform></shape>
        <shape type="obj"><string name="filename" value="tri.obj"/><boolean name="face_normals" value="true"/>
            <transform name="to_world"><scale x="-1"/><translate x="-3"/></transform></shape>"#;
    let path = write(dir.path(), "scene.xml", &scene_text(body));
    let scene = load_mitsuba_scene(&path, &[])
        .unwrap_or_else(|e| panic!("{e}"))
        .into_loaded();
    let mesh = |i: usize| match &scene.scene.objects[i].shape {
        Shape::Mesh { mesh, .. } => *mesh,
        _ => panic!(),
    };
    assert_eq!(mesh(0), mesh(1), "the instances share the mesh");
    assert_ne!(mesh(0), mesh(2), "the mirrored shape's own mesh is flipped");
    for (x, z) in [(0.0, 1.0), (3.0, 0.0), (-3.0, 0.0)] {
        let si = shade(&scene.scene, [x, 0.0, 5.0], [0.0, 0.0, -1.0]);
        assert!((si.p.z - z).abs() < 1e-6, "{}", si.p);
        let expected = if x < 0.0 { -1.0 } else { 1.0 };
        assert_eq!(si.ng.z, expected, "at x = {x}");
    }
}

/// Mitsuba gives a shape without a BSDF a grey diffuse, a black one when
/// it emits (`Shape`'s constructor).
#[test]
fn an_emitting_shape_without_a_bsdf_is_black() {
    let scene = load(
        r#"<shape type="disk"><emitter type="area"><rgb name="radiance" value="2, 2, 2"/></emitter></shape>
           <shape type="cylinder"/>"#,
    );
    let lamp = &scene.scene.materials[scene.scene.objects[0].material as usize];
    assert_eq!((lamp.diffuse, lamp.emission), (Vec3A::ZERO, Vec3A::splat(2.0)));
    let tube = &scene.scene.materials[scene.scene.objects[1].material as usize];
    assert_eq!(tube.diffuse, Vec3A::splat(0.5));
}

#[test]
fn what_cannot_be_mapped_is_refused_at_its_place() {
    let group = |member: &str| {
        format!(
            "<shape type=\"shapegroup\" id=\"g\">\n{member}\n</shape>\n<shape type=\"instance\"><ref id=\"g\"/></shape>"
        )
    };
    let cases = [
        (
            group(r#"<shape type="sphere"><emitter type="area"/></shape>"#),
            "instancing of emitters is not supported",
        ),
        (
            group(r#"<shape type="shapegroup"><shape type="sphere"/></shape>"#),
            "nested instancing",
        ),
        (
            r#"<shape type="shapegroup" id="h"><shape type="sphere"/></shape>
               <shape type="shapegroup" id="g"><shape type="instance"><ref id="h"/></shape></shape>
               <shape type="instance"><ref id="g"/></shape>"#
                .to_string(),
            "nested instancing",
        ),
        (r#"<shape type="instance"/>"#.to_string(), "needs a <ref"),
        (
            r#"<shape type="sphere" id="s"/><shape type="instance"><ref id="s"/></shape>"#.to_string(),
            "not to a <shape type=\"sphere\">",
        ),
        (
            group(r#"<shape type="sphere"/>"#).replace("<ref id=\"g\"/>", "<ref id=\"g\"/><bsdf type=\"diffuse\"/>"),
            "does not take a <bsdf>",
        ),
        (
            r#"<shape type="cylinder"><transform name="to_world"><scale x="2"/></transform></shape>"#.to_string(),
            "unevenly across its axis",
        ),
        (
            r#"<shape type="shapegroup" id="g"><shape type="cylinder"/></shape>
               <shape type="instance"><ref id="g"/><transform name="to_world"><scale y="2"/></transform></shape>"#
                .to_string(),
            "the instance's `to_world` shears the cylinder or scales it unevenly",
        ),
        (
            r#"<shape type="cylinder"><point name="p1" value="0, 0, 0"/></shape>"#.to_string(),
            "`p0` and `p1` coincide",
        ),
        (
            r#"<shape type="cylinder"><float name="radius" value="-1"/></shape>"#.to_string(),
            "`radius`",
        ),
        (
            r#"<shape type="disk"><transform name="to_world"><scale z="0"/></transform></shape>"#.to_string(),
            "singular",
        ),
        (
            r#"<shape type="disk"><float name="radius" value="2"/></shape>"#.to_string(),
            "`radius` is not a parameter",
        ),
    ];
    for (body, message) in &cases {
        let e = load_error(body);
        assert!(e.contains(message) && e.contains("scene.xml:"), "{body}: {e}");
    }
    // The emitter's own line and column.
    let e = load_error(&group(
        "  <shape type=\"sphere\">\n    <emitter type=\"area\"/>\n  </shape>",
    ));
    assert!(e.contains("scene.xml:8:5"), "{e}");
    // The command line: exit code 2 and the place.
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "bad.xml", &scene_text(&cases[0].0));
    let out = common::cli::caustic(&["info", path.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("bad.xml:") && stderr.contains("instancing of emitters"),
        "{stderr}"
    );
    // `caustic info` counts the disks and cylinders.
    let good = write(
        dir.path(),
        "good.xml",
        &scene_text(r#"<shape type="disk"/><shape type="cylinder"/><shape type="cylinder"/>"#),
    );
    let out = common::cli::caustic(&["info", good.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        stdout.contains("objects     3 (0 mesh instances, 1 disk, 2 cylinders)"),
        "{stdout}"
    );
}
