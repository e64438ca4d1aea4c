//! Scenes for the tests: the scene files by path, accelerators built for
//! them, quads, and the cross-check scene built in code (an icosphere
//! instanced several times with rotations and scales, a random triangle
//! soup, spheres and quads) with seeded ray generators.

use caustic::accel::{self, Accel, AccelKind, AccelOptions};
use caustic::math::rng::{Domain, Rng};
use caustic::math::{Ray, Transform, Vec3, Vec3A};
use caustic::scene::{Camera, LoadedScene, Material, Mesh, Object, Quad, Scene, Shape, Sphere};
use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use caustic::geometry::generate::icosphere;

/// A path relative to the crate root (`scenes/test/caustic.toml`).
pub fn path(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The scene file at `relative` (to the crate root), loaded.
pub fn load(relative: &str) -> LoadedScene {
    let p = path(relative);
    caustic::scene::load_scene(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `kind` built on `scene` with the default options.
pub fn build(scene: &Scene, kind: AccelKind) -> Box<dyn Accel> {
    accel::build(scene, kind, &AccelOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", kind.name()))
}

/// A quad object `corner + a·u + b·v` of material index `material`,
/// facing `u × v`.
pub fn quad(corner: [f32; 3], u: [f32; 3], v: [f32; 3], material: u32) -> Object {
    Object {
        name: "quad".into(),
        shape: Shape::Quad(Quad::new(corner.into(), u.into(), v.into()).unwrap()),
        material,
    }
}

/// `n` random triangles in the box [-1, 1]³ (overlapping, of all shapes).
pub fn soup(n: usize, seed: u64) -> Mesh {
    let mut rng = Rng::new(seed, Domain::Analysis, 77, 0);
    let mut p = Vec::new();
    let mut f = Vec::new();
    for i in 0..n {
        let c = Vec3::new(rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0, rng.f32() * 2.0 - 1.0);
        for _ in 0..3 {
            let d = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5) * 0.6;
            p.push(c + d);
        }
        let b = 3 * i as u32;
        f.push([b, b + 1, b + 2]);
    }
    Mesh::new("soup", p, f, None).unwrap()
}

fn object(name: &str, shape: Shape) -> Object {
    Object {
        name: name.into(),
        shape,
        material: 0,
    }
}

/// The cross-check scene: a floor and a back wall (quads), three spheres,
/// six rotated, scaled and translated instances of one icosphere (one BLAS),
/// and a soup (a second BLAS) used twice.
pub fn test_scene() -> Scene {
    let ico = Arc::new(icosphere(1));
    let soup = Arc::new(soup(200, 5));
    let mut objects = vec![
        object(
            "floor",
            Shape::Quad(
                Quad::new(
                    Vec3A::new(-6.0, -1.5, -6.0),
                    Vec3A::new(0.0, 0.0, 12.0),
                    Vec3A::new(12.0, 0.0, 0.0),
                )
                .unwrap(),
            ),
        ),
        object(
            "wall",
            Shape::Quad(
                Quad::new(
                    Vec3A::new(-6.0, -1.5, -6.0),
                    Vec3A::new(12.0, 0.0, 0.0),
                    Vec3A::new(0.0, 8.0, 0.5),
                )
                .unwrap(),
            ),
        ),
        object(
            "sphere a",
            Shape::Sphere(Sphere {
                center: Vec3A::new(2.5, 0.0, 1.0),
                radius: 1.0,
            }),
        ),
        object(
            "sphere b",
            Shape::Sphere(Sphere {
                center: Vec3A::new(-2.0, 1.5, -2.0),
                radius: 0.6,
            }),
        ),
        object(
            "sphere small",
            Shape::Sphere(Sphere {
                center: Vec3A::new(0.5, 3.0, 2.0),
                radius: 0.05,
            }),
        ),
    ];
    for k in 0..6 {
        let fk = k as f32;
        let transform = Transform::from_srt(
            Vec3::new(0.5 + 0.1 * fk, 0.7, 0.5 + 0.05 * fk),
            Vec3::new(17.0 * fk, 33.0 * fk + 5.0, 9.0 * fk),
            Vec3::new(-3.0 + 1.3 * fk, 0.2 * fk, 2.5 - 0.9 * fk),
        )
        .unwrap();
        objects.push(object(
            &format!("ico {k}"),
            Shape::Mesh {
                mesh: 0,
                transform,
                smooth: true,
            },
        ));
    }
    for (k, offset) in [Vec3::new(0.0, 1.0, 0.0), Vec3::new(3.0, 2.5, -3.0)]
        .into_iter()
        .enumerate()
    {
        objects.push(object(
            &format!("soup {k}"),
            Shape::Mesh {
                mesh: 1,
                transform: Transform::from_srt(Vec3::ONE, Vec3::new(0.0, 40.0 * k as f32, 0.0), offset).unwrap(),
                smooth: false,
            },
        ));
    }
    Scene {
        media: Default::default(),
        ambient: Vec3A::ZERO,
        water_medium: None,
        camera: Camera::new(Vec3A::new(0.0, 1.0, 9.0), Vec3A::ZERO, Vec3A::Y, 45.0).unwrap(),
        materials: vec![Material::diffuse("grey", Vec3A::splat(0.5))],
        lights: vec![],
        meshes: vec![ico, soup],
        objects,
    }
}

/// Unit vector uniform on the sphere.
pub fn uniform_dir(rng: &mut Rng) -> Vec3A {
    let z = rng.f32() * 2.0 - 1.0;
    let phi = rng.f32() * std::f32::consts::TAU;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Ray `i` of a seeded set: half start anywhere in the (enlarged) scene
/// bounds with a uniform direction, half are aimed at a random point of a
/// random object so that most of them hit something.
pub fn ray(scene: &Scene, seed: u64, i: u64) -> Ray {
    let mut rng = Rng::new(seed, Domain::Analysis, i, 1);
    let b = scene.bounds();
    let lo = b.min - b.extent() * 0.2;
    let ext = b.extent() * 1.4;
    let origin = lo + ext * Vec3A::new(rng.f32(), rng.f32(), rng.f32());
    if i.is_multiple_of(2) {
        return Ray::new(origin, uniform_dir(&mut rng));
    }
    let k = rng.below(scene.objects.len() as u32) as usize;
    let ob = scene.object_bounds(k);
    let target = ob.min + ob.extent() * Vec3A::new(rng.f32(), rng.f32(), rng.f32());
    let dir = (target - origin).normalize_or(Vec3A::Z);
    Ray::new(origin, dir)
}
