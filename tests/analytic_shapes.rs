//! Disks and cylinders: intersection and parametrisation against values
//! Mitsuba 3.9.1 reports for the same shapes and rays, robust ray spawning,
//! the accelerators against each other (0 disagreements, alpha cutouts
//! included), emission against closed forms (by the emitter's own sampling
//! and through the path integrator's MIS), and the TOML keys.

mod common;

use caustic::accel::brute::BruteForce;
use caustic::accel::{self, Accel, AccelKind, AccelOptions, TriangleTest};
use caustic::analysis::crosscheck::{crosscheck, CrosscheckOptions};
use caustic::math::offset_ray_origin;
use caustic::math::rng::{Domain, Rng};
use caustic::math::{Frame, Ray, Vec2, Vec3A};
use caustic::scene::light::ShapeEmitter;
use caustic::scene::LoadedScene;
use caustic::scene::{parse_scene, Cylinder, Disk, Shape, SurfaceInteraction};
use std::f32::consts::{FRAC_1_SQRT_2, PI, SQRT_2, TAU};
use std::path::Path;

fn load(text: &str) -> LoadedScene {
    parse_scene(text, Path::new("shapes.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn load_err(text: &str) -> String {
    parse_scene(text, Path::new("shapes.toml")).unwrap_err().to_string()
}

const HEAD: &str = "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 40\n\
                    [materials.m]\ndiffuse = 0.5\n";

fn close(a: Vec3A, b: Vec3A, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

/// The first hit of `ray` (brute force) as shading data; the material is
/// textured, so the texture coordinates are computed.
fn shade(scene: &LoadedScene, ray: Ray) -> SurfaceInteraction {
    let brute = BruteForce::new(&scene.scene, TriangleTest::Watertight);
    let hit = brute.intersect(&ray, f32::INFINITY).expect("the ray hits");
    scene.scene.surface_interaction(&ray, &hit)
}

/// A textured material makes `surface_interaction` compute uv and ∂p/∂uv.
fn textured(object: &str) -> LoadedScene {
    load(&format!(
        "{HEAD}[materials.t]\ndiffuse = {{ type = \"checkerboard\", colour0 = 0.2, colour1 = 0.8 }}\n{}",
        object.replace("\"m\"", "\"t\"")
    ))
}

#[test]
fn disk_uv_and_frame_follow_mitsuba() {
    // Mitsuba 3.9.1, `disk` with to_world = identity: the ray
    // (−0.2, −0.1, 5) → −z hits at t = 5 with uv (0.223607, 0.573792),
    // ∂p/∂u (−0.894427, −0.447214, 0), ∂p/∂v (0.628319, −1.25664, 0), n +z.
    let scene = textured(
        "[[objects]]\ntype = \"disk\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nnormal = [0.0, 0.0, 1.0]\n\
         up = [0.0, 1.0, 0.0]\nmaterial = \"m\"",
    );
    let si = shade(&scene, Ray::new(Vec3A::new(-0.2, -0.1, 5.0), -Vec3A::Z));
    assert!((si.t - 5.0).abs() < 1e-6);
    assert!(close(si.p, Vec3A::new(-0.2, -0.1, 0.0), 1e-6));
    assert!(close(si.ng, Vec3A::Z, 1e-6));
    assert!(
        (si.uv - Vec2::new(0.223607, 0.573792)).abs().max_element() < 1e-5,
        "{}",
        si.uv
    );
    assert!(
        close(si.dpdu, Vec3A::new(-0.894427, -0.447214, 0.0), 1e-5),
        "{}",
        si.dpdu
    );
    assert!(close(si.dpdv, Vec3A::new(0.628319, -1.25664, 0.0), 1e-5), "{}", si.dpdv);
    // By hand: +x is φ = 0, +y is φ = π/2 (v = 0.25), the rim r = 1.
    let si = shade(&scene, Ray::new(Vec3A::new(0.0, 0.5, 1.0), -Vec3A::Z));
    assert!((si.uv - Vec2::new(0.5, 0.25)).abs().max_element() < 1e-6, "{}", si.uv);
    let si = shade(&scene, Ray::new(Vec3A::new(0.999, 0.0, 1.0), -Vec3A::Z));
    assert!((si.uv - Vec2::new(0.999, 0.0)).abs().max_element() < 1e-6, "{}", si.uv);
    // Outside the rim: no hit; from behind: the same point (the disk is
    // one surface, its emission and one-sided BSDFs read `ng`).
    let brute = BruteForce::new(&scene.scene, TriangleTest::Watertight);
    assert!(brute
        .intersect(&Ray::new(Vec3A::new(0.8, 0.61, 1.0), -Vec3A::Z), f32::INFINITY)
        .is_none());
    let si = shade(&scene, Ray::new(Vec3A::new(-0.2, -0.1, -5.0), Vec3A::Z));
    assert!(close(si.ng, Vec3A::Z, 1e-6) && (si.uv.y - 0.573792).abs() < 1e-5);
}

#[test]
fn elliptic_disk_is_sampled_uniformly_with_its_area() {
    // Mitsuba 3.9.1, `disk` scaled by (2, 1, 1): area 2π, and the ray
    // above hits with uv (0.141421, 0.625), ∂p/∂u (−1.41421, −0.707107, 0),
    // ∂p/∂v (1.25664, −0.628318, 0).
    let d = Disk::new(Vec3A::ZERO, Vec3A::X * 2.0, Vec3A::Y, false).unwrap();
    assert!((d.area() - TAU).abs() < 1e-5);
    let (t, x, y) = d
        .intersect(&Ray::new(Vec3A::new(-0.2, -0.1, 5.0), -Vec3A::Z), f32::INFINITY)
        .unwrap();
    assert_eq!(t, 5.0);
    let (uv, dpdu, dpdv) = d.uv(x, y);
    assert!((uv - Vec2::new(0.141421, 0.625)).abs().max_element() < 1e-5, "{uv}");
    assert!(close(dpdu, Vec3A::new(-SQRT_2, -FRAC_1_SQRT_2, 0.0), 1e-5));
    assert!(close(dpdv, Vec3A::new(1.25664, -0.628318, 0.0), 1e-5));
    let b = d.bounds();
    assert!(close(b.min, Vec3A::new(-2.0, -1.0, 0.0), 1e-6) && close(b.max, Vec3A::new(2.0, 1.0, 0.0), 1e-6));
    // Uniform in area: the inner ellipse of half the semi-axes holds a quarter of the points.
    let scene = load(&format!(
        "{HEAD}[materials.lamp]\ndiffuse = 0.0\nemission = 1.0\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-5.0, -5.0, -1.0]\nu = [10.0, 0.0, 0.0]\nv = [0.0, 10.0, 0.0]\nmaterial = \"m\""
    ));
    let mut scene = scene;
    scene.scene.objects[0].shape = Shape::Disk(d);
    let e = ShapeEmitter::new(&scene.scene, 0).unwrap();
    assert!((e.area - TAU).abs() < 1e-5);
    let mut rng = Rng::new(5, Domain::Photon, 0, 0);
    let n = 40_000;
    let inner = (0..n)
        .filter(|_| {
            let q = e.sample_point(Vec2::from(rng.f32x2()), false);
            assert!(q.p.z == 0.0 && (q.p.x / 2.0).powi(2) + q.p.y.powi(2) <= 1.0 + 1e-5);
            (q.p.x / 2.0).powi(2) + q.p.y.powi(2) <= 0.25
        })
        .count();
    assert!((inner as f64 / n as f64 - 0.25).abs() < 0.01, "{inner}");
}

#[test]
fn cylinder_uv_and_normals_follow_mitsuba() {
    // Mitsuba 3.9.1, `cylinder` p0 = 0, p1 = (0, 0, 2), radius 0.5: the ray
    // (5, 0.3, 0.5) → −x hits at t = 4.6, p (0.4, 0.3, 0.5), n (0.8, 0.6, 0),
    // uv (0.102416, 0.25), ∂p/∂u (−1.88496, 2.51327, 0), ∂p/∂v (0, 0, 2).
    let scene = textured(
        "[[objects]]\ntype = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 0.0, 2.0]\nradius = 0.5\nmaterial = \"m\"",
    );
    let si = shade(&scene, Ray::new(Vec3A::new(5.0, 0.3, 0.5), -Vec3A::X));
    assert!((si.t - 4.6).abs() < 1e-5, "{}", si.t);
    assert!(close(si.p, Vec3A::new(0.4, 0.3, 0.5), 1e-6));
    assert!(close(si.ng, Vec3A::new(0.8, 0.6, 0.0), 1e-6));
    assert!(
        (si.uv - Vec2::new(0.102416, 0.25)).abs().max_element() < 1e-5,
        "{}",
        si.uv
    );
    assert!(close(si.dpdu, Vec3A::new(-1.88496, 2.51327, 0.0), 1e-5), "{}", si.dpdu);
    assert!(close(si.dpdv, Vec3A::new(0.0, 0.0, 2.0), 1e-6));
    // Open ends: a ray down the axis misses; one through an end meets the inside.
    let brute = BruteForce::new(&scene.scene, TriangleTest::Watertight);
    assert!(brute
        .intersect(&Ray::new(Vec3A::new(0.1, 0.0, 5.0), -Vec3A::Z), f32::INFINITY)
        .is_none());
    let inside = Ray::new(Vec3A::new(0.0, 0.0, 3.0), Vec3A::new(0.3, 0.0, -1.0).normalize());
    let si = shade(&scene, inside);
    assert!(close(si.p, Vec3A::new(0.5, 0.0, 3.0 - 0.5 / 0.3), 1e-5), "{}", si.p);
    assert!(
        close(si.ng, Vec3A::X, 1e-6),
        "normals point outward, also seen from inside"
    );
    // Above the top end (z > 2) and below the base: no hit.
    assert!(brute
        .intersect(&Ray::new(Vec3A::new(5.0, 0.0, 2.01), -Vec3A::X), f32::INFINITY)
        .is_none());
    assert!(brute
        .intersect(&Ray::new(Vec3A::new(5.0, 0.0, -0.01), -Vec3A::X), f32::INFINITY)
        .is_none());

    // p1 = (2, 0, 0): Mitsuba's frame about +x has s = (0, 0, −1),
    // t = (0, 1, 0). The ray (0.3, 5, 0.5) → −y hits (0.3, 0.866025, 0.5)
    // with n (0, 0.866025, 0.5), uv (1/3, 0.15), ∂p/∂u (0, −π, 5.4414), ∂p/∂v (2, 0, 0).
    let scene = textured(
        "[[objects]]\ntype = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [2.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"",
    );
    let si = shade(&scene, Ray::new(Vec3A::new(0.3, 5.0, 0.5), -Vec3A::Y));
    assert!(close(si.p, Vec3A::new(0.3, 0.866025, 0.5), 1e-5));
    assert!(close(si.ng, Vec3A::new(0.0, 0.866025, 0.5), 1e-5));
    assert!(
        (si.uv - Vec2::new(1.0 / 3.0, 0.15)).abs().max_element() < 1e-5,
        "{}",
        si.uv
    );
    assert!(close(si.dpdu, Vec3A::new(0.0, -PI, 5.4414), 1e-4), "{}", si.dpdu);
    assert!(close(si.dpdv, Vec3A::new(2.0, 0.0, 0.0), 1e-6));
    // flip_normals: inward.
    let scene = textured(
        "[[objects]]\ntype = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 0.0, 2.0]\nradius = 0.5\n\
         flip_normals = true\nmaterial = \"m\"",
    );
    let si = shade(&scene, Ray::new(Vec3A::new(5.0, 0.3, 0.5), -Vec3A::X));
    assert!(close(si.ng, Vec3A::new(-0.8, -0.6, 0.0), 1e-6));
}

/// Rays leaving a hit by `offset_ray_origin` never find the surface they
/// leave, on disks and cylinders far from the origin (large coordinates,
/// small shapes) and on a wide, short tube, reflected or transmitted. A
/// disk has no other point to hit; a ray crossing a tube's wall into it
/// meets the far wall at the chord `2 r |cos θ|` (and grazing ones, whose
/// chord is too short to tell from the surface left, are not counted).
#[test]
fn spawned_rays_do_not_hit_their_own_surface() {
    let far = Vec3A::new(3000.0, -2000.0, 1500.0);
    let frame = Frame::from_normal(Vec3A::new(0.3, 0.5, -0.8).normalize());
    let shapes = [
        (
            Shape::Disk(Disk::new(far, frame.s * 0.3, frame.t * 0.7, false).unwrap()),
            None,
        ),
        (
            Shape::Cylinder(Cylinder::new(far, [frame.s, frame.t, frame.n], 0.05, 2.0, false).unwrap()),
            Some(0.05f32),
        ),
        (
            Shape::Cylinder(Cylinder::new(Vec3A::ZERO, [frame.s, frame.t, frame.n], 40.0, 0.1, true).unwrap()),
            Some(40.0),
        ),
    ];
    let mut rng = Rng::new(11, Domain::Photon, 0, 0);
    for (shape, radius) in shapes {
        let mut scene = load(&format!(
            "{HEAD}[[objects]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\""
        ));
        scene.scene.objects[0].shape = shape.clone();
        let brute = BruteForce::new(&scene.scene, TriangleTest::Watertight);
        let e = ShapeEmitter::new(&scene.scene, 0).unwrap();
        let (mut tested, mut self_hits) = (0, 0);
        for _ in 0..20_000 {
            // A point of the surface, approached from a random direction.
            let q = e.sample_point(Vec2::from(rng.f32x2()), false);
            let w = caustic::math::sampling::uniform_sphere(Vec2::from(rng.f32x2()));
            let ray = Ray::new(q.p + w * 0.5, -w);
            let Some(hit) = brute.intersect(&ray, 1.0) else {
                continue;
            };
            let si = scene.scene.surface_interaction(&ray, &hit);
            // Leave on both sides: reflected and transmitted.
            let reflected = caustic::math::sampling::uniform_sphere(Vec2::from(rng.f32x2()));
            for dir in [reflected, -w] {
                let cos = dir.dot(si.ng).abs();
                if cos < 1e-2 {
                    continue;
                }
                let o = offset_ray_origin(si.p, si.p_error, si.ng, dir);
                tested += 1;
                if let Some(h) = brute.intersect(&Ray::new(o, dir), f32::INFINITY) {
                    let chord = radius.map_or(0.0, |r| 2.0 * r * cos);
                    if h.t < 0.5 * chord || radius.is_none() {
                        self_hits += 1;
                    }
                }
            }
        }
        assert!(tested > 10_000, "{tested}");
        assert_eq!(
            self_hits, 0,
            "{shape:?}: {self_hits} of {tested} spawned rays hit their own surface"
        );
    }
}

/// Disks (round, elliptic, sheared, facing away) and cylinders (tilted,
/// long and thin, flipped), some with an alpha mask, beside a sphere, a
/// quad and a mesh: Embree and the KD-tree against brute force, 0
/// disagreements.
#[test]
fn accelerators_agree_on_disks_and_cylinders() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("tet.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    )
    .unwrap();
    let text = "[render]\nwidth = 64\nheight = 48\n\
         [camera]\nposition = [0.0, 2.0, 8.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 50\n\
         [materials.m]\ndiffuse = 0.5\n\
         [materials.holes]\ndiffuse = 0.5\nalpha = { type = \"checkerboard\", colour0 = 0.0, colour1 = 1.0, scale = 4.0 }\n\
         [[lights]]\ntype = \"point\"\nposition = [0.0, 4.0, 2.0]\nintensity = 1.0\n\
         [[objects]]\ntype = \"quad\"\ncenter = [0.0, -1.0, 0.0]\nsize = [8.0, 8.0]\nnormal = [0.0, 1.0, 0.0]\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [2.5, 0.0, 0.0]\nradius = 0.6\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"mesh\"\nfile = \"tet.obj\"\ntranslate = [-2.5, -0.5, 0.5]\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"disk\"\ncenter = [0.0, 0.5, 0.0]\nradius = 0.8\nnormal = [0.2, 1.0, 0.3]\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"disk\"\ncenter = [-1.0, 1.0, -1.0]\nradius = 0.6\nrotate = [20.0, 40.0, 0.0]\nmaterial = \"holes\"\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [1.0, -1.0, -1.0]\np1 = [1.4, 1.5, -0.6]\nradius = 0.4\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [-2.0, 0.0, 2.0]\np1 = [2.0, 0.3, 2.0]\nradius = 0.05\nflip_normals = true\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [0.0, -1.0, 0.0]\np1 = [0.0, 0.0, 0.0]\nradius = 1.5\nmaterial = \"holes\"\n";
    let mut scene = parse_scene(text, &dir.path().join("s.toml")).unwrap_or_else(|e| panic!("{e}"));
    // An elliptic, sheared disk facing −(a × b), as Mitsuba's `to_world` may make one.
    scene.scene.objects.push(caustic::scene::Object {
        name: "ellipse".into(),
        shape: Shape::Disk(
            Disk::new(
                Vec3A::new(0.0, 1.5, 1.0),
                Vec3A::new(0.9, 0.0, 0.1),
                Vec3A::new(0.3, 0.2, -0.4),
                true,
            )
            .unwrap(),
        ),
        material: 0,
    });
    assert!(caustic::scene::Cutouts::of(&scene.scene).is_some());
    let brute = BruteForce::new(&scene.scene, TriangleTest::Watertight);
    let mut kinds = vec![AccelKind::KdTree];
    if cfg!(feature = "embree") {
        kinds.push(AccelKind::Embree);
    }
    for kind in kinds {
        let a = accel::build(&scene.scene, kind, &AccelOptions::default()).unwrap();
        let report = crosscheck(
            &scene.scene,
            a.as_ref(),
            &brute,
            &CrosscheckOptions {
                rays: 40_000,
                seed: 77,
                image: (scene.settings.width, scene.settings.height),
            },
        );
        eprintln!("{}\n{report}", kind.name());
        assert!(report.is_ok(), "{}: disagreements\n{report}", kind.name());
        let total = report.total();
        assert!(total.hits * 2 > total.rays, "{report}");
        // The analytic shapes are the same code in every backend: the same bits.
        let mut rng = Rng::new(3, Domain::Photon, 0, 0);
        for _ in 0..5_000 {
            let o = Vec3A::new(rng.f32() * 8.0 - 4.0, rng.f32() * 4.0 - 1.0, rng.f32() * 8.0 - 4.0);
            let ray = Ray::new(o, caustic::math::sampling::uniform_sphere(Vec2::from(rng.f32x2())));
            let (x, y) = (a.intersect(&ray, f32::INFINITY), brute.intersect(&ray, f32::INFINITY));
            if let (Some(x), Some(y)) = (x, y) {
                if matches!(
                    scene.scene.objects[x.instance as usize].shape,
                    Shape::Disk(_) | Shape::Cylinder(_)
                ) {
                    assert_eq!(x, y, "{}: {ray:?}", kind.name());
                }
            }
            assert_eq!(a.occluded(&ray, 3.0), brute.occluded(&ray, 3.0), "{ray:?}");
        }
    }
}

/// Irradiance at a point on the axis, at distance h below an emitting
/// disk of radius r and radiance L: `E = π L r² / (r² + h²)`; estimated
/// with the emitter's own area sampling (`sample_from` and `pdf_from`).
#[test]
fn an_emitting_disk_gives_its_closed_form_irradiance() {
    let (r, h, radiance) = (0.6f32, 1.3f32, 2.0f32);
    let scene = load(&format!(
        "{HEAD}[materials.lamp]\ndiffuse = 0.0\nemission = {radiance}\n\
         [[objects]]\ntype = \"disk\"\ncenter = [0.0, {h}, 0.0]\nradius = {r}\nnormal = [0.0, -1.0, 0.0]\nmaterial = \"lamp\""
    ));
    let e = ShapeEmitter::new(&scene.scene, 0).unwrap();
    assert!((e.area - PI * r * r).abs() < 1e-5);
    let mut rng = Rng::new(8, Domain::Photon, 0, 0);
    let n = 100_000;
    let mut sum = 0.0f64;
    for _ in 0..n {
        let (q, pdf) = e.sample_from(Vec3A::ZERO, Vec2::from(rng.f32x2()), false).unwrap();
        assert!((e.pdf_from(Vec3A::ZERO, q.p, q.n) - pdf).abs() <= 1e-5 * pdf);
        let w = q.p.normalize();
        assert!(q.n.dot(-w) > 0.0, "the disk faces the point");
        sum += f64::from(radiance * w.y / pdf);
    }
    let expected = PI * radiance * r * r / (r * r + h * h);
    let estimate = sum / n as f64;
    assert!(
        (estimate / f64::from(expected) - 1.0).abs() < 0.005,
        "{estimate} against {expected}"
    );
}

/// A tube of radius R and length ℓ emitting inward lights the centre of
/// one of its open ends, facing along the axis, with `E = π L ℓ² / (ℓ² +
/// R²)` (the wall fills the directions from the far opening's rim,
/// θ = atan(R/ℓ), to the horizon). With outward normals the inside emits
/// nothing (the path integrator's test below sees that side).
#[test]
fn an_inward_emitting_cylinder_gives_its_closed_form_irradiance() {
    let (radius, length, radiance) = (0.5f32, 1.5f32, 3.0f32);
    let scene = load(&format!(
        "{HEAD}[materials.lamp]\ndiffuse = 0.0\nemission = {radiance}\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 0.0, {length}]\nradius = {radius}\n\
         flip_normals = true\nmaterial = \"lamp\""
    ));
    let e = ShapeEmitter::new(&scene.scene, 0).unwrap();
    assert!((e.area - TAU * radius * length).abs() < 1e-5);
    let mut rng = Rng::new(9, Domain::Photon, 0, 0);
    let n = 200_000;
    let mut sum = 0.0f64;
    for _ in 0..n {
        let Some((q, pdf)) = e.sample_from(Vec3A::ZERO, Vec2::from(rng.f32x2()), false) else {
            continue;
        };
        assert!((e.pdf_from(Vec3A::ZERO, q.p, q.n) - pdf).abs() <= 1e-4 * pdf);
        let w = q.p.normalize();
        assert!(q.n.dot(-w) >= -1e-6, "the wall faces the axis");
        sum += f64::from(radiance * w.z.max(0.0) / pdf);
    }
    let expected = PI * radiance * length * length / (length * length + radius * radius);
    let estimate = sum / n as f64;
    assert!(
        (estimate / f64::from(expected) - 1.0).abs() < 0.01,
        "{estimate} against {expected}"
    );
}

/// A 4 × 4 floor of albedo 0.5 seen from above, lit by `light` (path
/// tracing, direct light only, MIS between light and BSDF samples).
fn floor_scene(light: &str) -> LoadedScene {
    load(&format!(
        "[render]\nwidth = 32\nheight = 32\nspp = 64\nintegrator = \"path\"\nmax_depth = 1\nseed = 5\n\
         [camera]\nposition = [0.0, 3.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov = 30\n\
         [materials.floor]\ndiffuse = 0.5\n\
         [materials.lamp]\ndiffuse = 0.0\nemission = 4.0\n\
         [[objects]]\ntype = \"quad\"\ncenter = [0.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nnormal = [0.0, 1.0, 0.0]\n\
         up = [0.0, 0.0, -1.0]\nmaterial = \"floor\"\n{light}\n"
    ))
}

fn film_sum(scene: &LoadedScene) -> (Vec<f32>, f64) {
    let film = common::render::film(scene, AccelKind::KdTree);
    let red: Vec<f32> = film.pixels.iter().map(|p| p[0]).collect();
    let sum = red.iter().map(|&x| f64::from(x)).sum();
    (red, sum)
}

/// An emitting disk parallel to the floor, out of the camera's view, lights
/// each floor point with the view factor of a parallel disk at horizontal
/// offset ρ: `E = (π L / 2)(1 − (h² + ρ² − r²) / √((h² + ρ² + r²)² − 4 r² ρ²))`.
/// The path integrator finds it by light sampling and by BSDF sampling
/// (MIS), so both must see the disk with the same pdf; the Whitted
/// integrator by its stratified shadow samples.
#[test]
fn the_path_integrator_sees_an_emitting_disk() {
    let (r, h) = (0.3f32, 1.0f32);
    let c = Vec3A::new(1.6, h, 0.0);
    let scene = floor_scene(&format!(
        "[[objects]]\ntype = \"disk\"\ncenter = [{}, {h}, 0.0]\nradius = {r}\nnormal = [0.0, -1.0, 0.0]\nmaterial = \"lamp\"",
        c.x
    ));
    let (_, sum) = film_sum(&scene);
    let s = &scene.settings;
    let mut expected = 0.0f64;
    for y in 0..32 {
        for x in 0..32 {
            let ray = scene
                .scene
                .camera
                .ray(x as f32 + 0.5, y as f32 + 0.5, s.width, s.height);
            let p = ray.at(-ray.origin.y / ray.dir.y);
            let rho2 = (p.x - c.x).powi(2) + (p.z - c.z).powi(2);
            let z = h * h + rho2 + r * r;
            let e = PI * 4.0 / 2.0 * (1.0 - (h * h + rho2 - r * r) / (z * z - 4.0 * r * r * rho2).sqrt());
            expected += f64::from(0.5 / PI * e);
        }
    }
    assert!((sum / expected - 1.0).abs() < 0.01, "{sum} against {expected}");
    // The Whitted integrator's direct light from emitting objects, too.
    let mut whitted = scene.clone();
    whitted.settings.integrator = caustic::scene::IntegratorKind::Whitted;
    whitted.settings.max_depth = None;
    let (_, sum) = film_sum(&whitted);
    assert!((sum / expected - 1.0).abs() < 0.01, "Whitted: {sum} against {expected}");
    // Turned away from the floor, it lights nothing.
    let away = floor_scene(&format!(
        "[[objects]]\ntype = \"disk\"\ncenter = [{}, {h}, 0.0]\nradius = {r}\nnormal = [0.0, 1.0, 0.0]\nmaterial = \"lamp\"",
        c.x
    ));
    assert_eq!(film_sum(&away).1, 0.0);
}

/// An emitting cylinder lying above the floor, out of view, against the
/// same tube as a fine triangle mesh (the mesh's facets cut the circle, so
/// its area is smaller by `sin(π/n)/(π/n)`, 0.04% at 64 sides).
#[test]
fn an_emitting_cylinder_lights_as_its_mesh_does() {
    let dir = tempfile::tempdir().unwrap();
    let (radius, sides) = (0.2f32, 64);
    let mut obj = String::new();
    for i in 0..sides {
        let phi = TAU * i as f32 / sides as f32;
        let (y, z) = (1.0 + radius * phi.cos(), radius * phi.sin());
        obj += &format!("v 1.4 {y} {z}\nv 2.4 {y} {z}\n");
    }
    for i in 0..sides {
        let (a, b) = (2 * i + 1, 2 * ((i + 1) % sides) + 1);
        // Outward winding: (x0, φ0), (x0, φ1), (x1, φ1).
        obj += &format!("f {a} {b} {}\nf {a} {} {}\n", b + 1, b + 1, a + 1);
    }
    std::fs::write(dir.path().join("tube.obj"), obj).unwrap();
    let cylinder = floor_scene(&format!(
        "[[objects]]\ntype = \"cylinder\"\np0 = [1.4, 1.0, 0.0]\np1 = [2.4, 1.0, 0.0]\nradius = {radius}\nmaterial = \"lamp\""
    ));
    let e = ShapeEmitter::new(&cylinder.scene, 1).unwrap();
    assert!((e.area - TAU * radius).abs() < 1e-5);
    let mesh_scene = {
        let s = "[render]\nwidth = 32\nheight = 32\nspp = 64\nintegrator = \"path\"\nmax_depth = 1\nseed = 5\n\
             [camera]\nposition = [0.0, 3.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov = 30\n\
             [materials.floor]\ndiffuse = 0.5\n[materials.lamp]\ndiffuse = 0.0\nemission = 4.0\n\
             [[objects]]\ntype = \"quad\"\ncenter = [0.0, 0.0, 0.0]\nsize = [4.0, 4.0]\nnormal = [0.0, 1.0, 0.0]\n\
             up = [0.0, 0.0, -1.0]\nmaterial = \"floor\"\n\
             [[objects]]\ntype = \"mesh\"\nfile = \"tube.obj\"\nmaterial = \"lamp\"\n";
        parse_scene(s, &dir.path().join("tube.toml")).unwrap_or_else(|e| panic!("{e}"))
    };
    // 512 samples: the mesh's few large facets make its light samples noisier.
    let (mut cylinder, mut mesh_scene) = (cylinder, mesh_scene);
    cylinder.settings.spp = 512;
    mesh_scene.settings.spp = 512;
    let (_, with_cylinder) = film_sum(&cylinder);
    let (_, with_mesh) = film_sum(&mesh_scene);
    assert!(with_cylinder > 0.0);
    assert!(
        (with_cylinder / with_mesh - 1.0).abs() < 0.01,
        "{with_cylinder} against the mesh's {with_mesh}"
    );
}

#[test]
fn toml_keys_are_read_and_checked() {
    let scene = load(&format!(
        "{HEAD}[[objects]]\ntype = \"disk\"\ncenter = [1.0, 2.0, 3.0]\nradius = 2.0\nrotate = [90.0, 0.0, 0.0]\nmaterial = \"m\"\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [0.0, 1.0, 0.0]\np1 = [0.0, 1.0, 3.0]\nradius = 0.25\nmaterial = \"m\""
    ));
    let Shape::Disk(d) = &scene.scene.objects[0].shape else {
        panic!()
    };
    assert!(close(d.center, Vec3A::new(1.0, 2.0, 3.0), 0.0));
    // rotate 90° about x: +z → −y, the disk faces −y; a = 2x, b = 2z.
    assert!(close(d.normal, -Vec3A::Y, 1e-6) && close(d.a, Vec3A::X * 2.0, 1e-6) && close(d.b, Vec3A::Z * 2.0, 1e-6));
    let Shape::Cylinder(c) = &scene.scene.objects[1].shape else {
        panic!()
    };
    assert_eq!((c.radius, c.length, c.inward), (0.25, 3.0, false));
    assert!(close(c.base, Vec3A::Y, 0.0) && close(c.axis, Vec3A::Z, 0.0));
    assert_eq!(scene.scene.objects[0].name, "disk#0");
    let cases = [
        ("type = \"disk\"\ncenter = [0.0, 0.0, 0.0]\nmaterial = \"m\"", "`radius`"),
        ("type = \"disk\"\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\nmaterial = \"m\"", "must be > 0"),
        (
            "type = \"disk\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nnormal = [0.0, 1.0, 0.0]\nrotate = [1.0, 0.0, 0.0]\nmaterial = \"m\"",
            "the disk's orientation either as `normal`",
        ),
        ("type = \"disk\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\np0 = [0.0, 0.0, 0.0]\nmaterial = \"m\"", "`p0`"),
        ("type = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"", "`p1`"),
        (
            "type = \"cylinder\"\np0 = [1.0, 0.0, 0.0]\np1 = [1.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"",
            "`p1` equals `p0`",
        ),
        ("type = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 0.0, 1.0]\nradius = 0.0\nmaterial = \"m\"", "must be > 0"),
        (
            "type = \"cylinder\"\np0 = [0.0, 0.0, 0.0]\np1 = [0.0, 0.0, 1.0]\nradius = 1.0\ncenter = [0.0, 0.0, 0.0]\nmaterial = \"m\"",
            "`center`",
        ),
    ];
    for (object, message) in cases {
        let e = load_err(&format!("{HEAD}[[objects]]\n{object}\n"));
        assert!(e.contains(message) && e.contains("shapes.toml:"), "{object}: {e}");
    }
}

/// An alpha mask cuts holes in disks and cylinders on every accelerator:
/// a ray meets the disk exactly where the mask, read at the disk's texture
/// coordinates `(r, φ/2π)`, is opaque; through a hole in a cylinder's near
/// wall it meets the far wall (or nothing, where that is a hole too).
#[test]
fn alpha_masks_cut_disks_and_cylinders() {
    let scene = load(&format!(
        "{HEAD}[materials.holes]\ndiffuse = 0.5\n\
         alpha = {{ type = \"checkerboard\", colour0 = 0.0, colour1 = 1.0, scale = 4.0 }}\n\
         [[objects]]\ntype = \"disk\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"holes\"\n\
         [[objects]]\ntype = \"cylinder\"\np0 = [5.0, 0.0, -1.0]\np1 = [5.0, 0.0, 1.0]\nradius = 1.0\nmaterial = \"holes\""
    ));
    let material = &scene.scene.materials[scene.scene.objects[0].material as usize];
    let mask = material.textures.as_ref().unwrap().alpha.clone().unwrap();
    let Shape::Disk(disk) = scene.scene.objects[0].shape.clone() else {
        panic!()
    };
    let Shape::Cylinder(tube) = scene.scene.objects[1].shape.clone() else {
        panic!()
    };
    let mut kinds = vec![AccelKind::Brute, AccelKind::KdTree];
    if cfg!(feature = "embree") {
        kinds.push(AccelKind::Embree);
    }
    let mut rng = Rng::new(4, Domain::Photon, 0, 0);
    for kind in kinds {
        let a = accel::build(&scene.scene, kind, &AccelOptions::default()).unwrap();
        let (mut holes, mut solid, mut far) = (0, 0, 0);
        for _ in 0..2_000 {
            // Down onto the disk.
            let (x, y) = (rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0);
            if x * x + y * y < 0.98 {
                let ray = Ray::new(Vec3A::new(x, y, 3.0), -Vec3A::Z);
                let opaque = mask.opaque_at(disk.uv(x, y).0);
                let hit = a.intersect(&ray, f32::INFINITY);
                assert_eq!(hit.is_some(), opaque, "{}: disk at ({x}, {y})", kind.name());
                assert_eq!(a.occluded(&ray, 10.0), opaque);
                if opaque {
                    solid += 1;
                } else {
                    holes += 1;
                }
            }
            // Across the tube, along −x.
            let (y, z) = (rng.f32() * 1.6 - 0.8, rng.f32() * 1.8 - 0.9);
            let ray = Ray::new(Vec3A::new(10.0, y, z), -Vec3A::X);
            let near = Vec3A::new(5.0 + (1.0 - y * y).sqrt(), y, z);
            let back = Vec3A::new(5.0 - (1.0 - y * y).sqrt(), y, z);
            let (near_opaque, far_opaque) = (mask.opaque_at(tube.uv(near).0), mask.opaque_at(tube.uv(back).0));
            let hit = a.intersect(&ray, f32::INFINITY).map(|h| ray.at(h.t));
            match hit {
                Some(p) if near_opaque => assert!((p - near).length() < 1e-4, "{}: {p}", kind.name()),
                Some(p) => {
                    assert!(far_opaque && (p - back).length() < 1e-4, "{}: {p}", kind.name());
                    far += 1;
                }
                None => assert!(!near_opaque && !far_opaque, "{}: ({y}, {z})", kind.name()),
            }
        }
        assert!(holes > 100 && solid > 100 && far > 50, "{holes} {solid} {far}");
    }
}
