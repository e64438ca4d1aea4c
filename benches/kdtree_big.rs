//! KD-tree build time, memory and ray throughput on big generated meshes (a
//! proxy for the Stanford dragon every checkout has): `cargo bench --bench
//! kdtree_big`. Prints the figures; the hit counts show that the rays did
//! the work.

use caustic::accel::kdtree::KdTreeAccel;
use caustic::accel::{Accel, AccelOptions};
use caustic::math::rng::{Domain, Rng};
use caustic::math::{Ray, Transform, Vec3, Vec3A};
use caustic::scene::{Camera, Material, Mesh, Object, Scene, Shape};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// `n` random small triangles (edge ≈ 0.003) in the unit cube.
fn small_soup(n: usize) -> Mesh {
    let mut rng = Rng::new(42, Domain::Analysis, 0, 0);
    let mut p = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let c = Vec3::new(rng.f32(), rng.f32(), rng.f32());
        for _ in 0..3 {
            p.push(c + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - Vec3::splat(0.5)) * 0.006);
        }
    }
    let tris = (0..n as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    Mesh::new("soup", p, tris, None).unwrap()
}

/// A closed, bumpy surface of `2·n²` triangles (a displaced UV sphere): closer
/// to a scanned model than the soup.
fn bumpy_sphere(n: u32) -> Mesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let theta = std::f32::consts::PI * j as f32 / n as f32;
            let phi = std::f32::consts::TAU * i as f32 / n as f32;
            let r = 1.0 + 0.05 * (7.0 * theta).sin() * (11.0 * phi).cos() + 0.02 * (23.0 * phi + 5.0 * theta).sin();
            p.push(Vec3::new(
                r * theta.sin() * phi.cos(),
                r * theta.cos(),
                r * theta.sin() * phi.sin(),
            ));
        }
    }
    let mut tris = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            tris.push([a, a + n + 1, a + n + 2]);
            tris.push([a, a + n + 2, a + 1]);
        }
    }
    Mesh::new("bumpy", p, tris, None).unwrap()
}

fn scene_of(mesh: Mesh) -> Scene {
    Scene {
        media: Default::default(),
        ambient: Vec3A::ZERO,
        water_medium: None,
        camera: Camera::new(Vec3A::new(0.0, 0.0, 4.0), Vec3A::ZERO, Vec3A::Y, 45.0).unwrap(),
        materials: vec![Material::diffuse("white", Vec3A::ONE)],
        lights: vec![],
        meshes: vec![Arc::new(mesh)],
        objects: vec![Object {
            name: "mesh".into(),
            shape: Shape::Mesh {
                mesh: 0,
                transform: Transform::IDENTITY,
                smooth: false,
            },
            material: 0,
        }],
    }
}

fn measure(label: &str, scene: &Scene) {
    let t = Instant::now();
    let kd = KdTreeAccel::build(scene, &AccelOptions::default());
    let build = t.elapsed();
    let stats = kd.stats();
    println!(
        "{label}: {} triangles, build {:.3} s, {:.1} MiB",
        scene.instanced_triangles(),
        build.as_secs_f64(),
        stats.memory_bytes as f64 / (1 << 20) as f64
    );
    for (k, v) in &stats.details {
        println!("    {k}: {v}");
    }
    let b = scene.bounds();
    let (w, h) = (1024u32, 1024u32);
    let cam = Camera::new(
        b.center() + Vec3A::new(0.3, 0.4, 2.5) * b.extent().max_element(),
        b.center(),
        Vec3A::Y,
        40.0,
    )
    .unwrap();
    let camera_rays: Vec<Ray> = (0..w * h)
        .map(|i| cam.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5, w, h))
        .collect();
    let t = Instant::now();
    let hits: Vec<Option<f32>> = camera_rays
        .par_iter()
        .map(|r| kd.intersect(r, f32::INFINITY).map(|h| h.t))
        .collect();
    let secs = t.elapsed().as_secs_f64();
    let n_hit = hits.iter().flatten().count();
    println!(
        "    camera rays: {:.2} Mrays/s ({} of {} hit)",
        camera_rays.len() as f64 / secs / 1e6,
        n_hit,
        camera_rays.len()
    );
    // Shadow rays from the hit points towards a light above (occluded).
    let light = b.center() + Vec3A::new(0.5, 3.0, 1.0) * b.extent().max_element();
    let shadow: Vec<(Ray, f32)> = camera_rays
        .iter()
        .zip(&hits)
        .filter_map(|(r, t)| t.map(|t| r.at(t * 0.9999)))
        .map(|p| (Ray::new(p, light - p), 0.9999))
        .collect();
    let t = Instant::now();
    let blocked = shadow.par_iter().filter(|(r, tm)| kd.occluded(r, *tm)).count();
    let secs = t.elapsed().as_secs_f64();
    println!(
        "    shadow rays: {:.2} Mrays/s ({} of {} blocked)",
        shadow.len() as f64 / secs / 1e6,
        blocked,
        shadow.len()
    );
    // Incoherent rays: random origins in the bounds, random directions.
    let random: Vec<Ray> = (0..1_000_000u64)
        .map(|i| {
            let mut rng = Rng::new(9, Domain::Analysis, 1, i);
            let o = b.min + b.extent() * Vec3A::new(rng.f32(), rng.f32(), rng.f32());
            let d = Vec3A::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize_or(Vec3A::X);
            Ray::new(o, d)
        })
        .collect();
    let t = Instant::now();
    let n = random
        .par_iter()
        .filter(|r| kd.intersect(r, f32::INFINITY).is_some())
        .count();
    let secs = t.elapsed().as_secs_f64();
    println!(
        "    random rays: {:.2} Mrays/s ({n} hit) on {} threads",
        random.len() as f64 / secs / 1e6,
        rayon::current_num_threads()
    );
}

fn main() {
    // `cargo bench` passes `--bench`; `cargo test --benches` runs it too,
    // which this measurement is not for.
    if !std::env::args().any(|a| a == "--bench") {
        println!("kdtree_big: a measurement, run by `cargo bench --bench kdtree_big`");
        return;
    }
    measure("soup 1M", &scene_of(small_soup(1_000_000)));
    measure("bumpy sphere 880k", &scene_of(bumpy_sphere(663)));
}
