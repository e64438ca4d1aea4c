//! Ray-throughput measurement shared by the benchmarks, the `#[ignore]`d
//! performance tests and the command line: seeded ray sets of the three
//! kinds a renderer casts (primary camera rays, shadow rays towards the
//! lights, incoherent bounce rays) and a timed run of one set through any
//! [`Accel`].

use crate::accel::{Accel, Hit};
use crate::math::rng::{Domain, Rng};
use crate::math::{offset_ray_origin, Ray, Vec3A};
use crate::scene::{Light, Scene};
use rayon::prelude::*;
use std::time::Instant;

/// Which query a ray set is timed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// Closest hit (`Accel::intersect`).
    Closest,
    /// Any hit (`Accel::occluded`).
    Occluded,
}

/// A named set of rays with their `t_max`, and the query they are timed with.
#[derive(Clone, Debug)]
pub struct RaySet {
    /// Short name ("camera", "shadow", "incoherent").
    pub name: &'static str,
    /// Query the rays are meant for.
    pub query: Query,
    /// Rays and their `t_max`.
    pub rays: Vec<(Ray, f32)>,
}

/// The outcome of a timed run.
#[derive(Clone, Copy, Debug)]
pub struct Throughput {
    /// Rays cast.
    pub rays: usize,
    /// Rays that hit something (closest) or were occluded.
    pub hits: usize,
    /// Wall time of the run.
    pub seconds: f64,
    /// CPU time of the whole process during the run (all threads; Linux
    /// only, 10 ms resolution): on a shared machine, rays per CPU second are
    /// steadier than rays per wall second.
    pub cpu_seconds: Option<f64>,
}

impl Throughput {
    /// Millions of rays per second (wall time, all rayon threads).
    pub fn mrays_per_s(&self) -> f64 {
        self.rays as f64 / self.seconds.max(1e-12) / 1e6
    }

    /// Millions of rays per CPU second (one core's throughput), when known.
    pub fn mrays_per_cpu_s(&self) -> Option<f64> {
        self.cpu_seconds.map(|c| self.rays as f64 / c.max(1e-3) / 1e6)
    }
}

/// User + system CPU time of this process so far, from `/proc/self/stat`.
pub fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are the
    // 14th and 15th fields overall, in clock ticks (100 per second on Linux).
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// Times `rays` through `accel` on the current rayon pool (rays are handed
/// out in chunks of 1024 so neighbouring camera rays stay on one thread, as in
/// a tiled renderer).
pub fn throughput(accel: &dyn Accel, rays: &[(Ray, f32)], query: Query) -> Throughput {
    let cpu_start = process_cpu_seconds();
    let start = Instant::now();
    let hits: usize = rays
        .par_chunks(1024)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|(r, t_max)| match query {
                    Query::Closest => accel.intersect(r, *t_max).is_some(),
                    Query::Occluded => accel.occluded(r, *t_max),
                })
                .count()
        })
        .sum();
    Throughput {
        rays: rays.len(),
        hits,
        seconds: start.elapsed().as_secs_f64(),
        cpu_seconds: cpu_start.zip(process_cpu_seconds()).map(|(a, b)| b - a),
    }
}

/// One camera ray through the centre of each pixel of a `width`×`height` image
/// of the scene's camera, in scanline order.
pub fn camera_rays(scene: &Scene, width: u32, height: u32) -> Vec<(Ray, f32)> {
    (0..width * height)
        .into_par_iter()
        .map(|i| {
            let ray = scene
                .camera
                .ray((i % width) as f32 + 0.5, (i / width) as f32 + 0.5, width, height);
            (ray, f32::INFINITY)
        })
        .collect()
}

/// Shading points of `primary` found with `reference`: the hit, its surface
/// interaction, and the primary ray.
fn shading_points(reference: &dyn Accel, primary: &[(Ray, f32)]) -> Vec<(Ray, Hit)> {
    primary
        .par_iter()
        .filter_map(|(r, t_max)| reference.intersect(r, *t_max).map(|h| (*r, h)))
        .collect()
}

/// Shadow rays from the hit points of `primary` (found with `reference`)
/// towards each light: point lights' positions, and for area lights one
/// seeded point on the rectangle per shading point. The origins are offset
/// off the surface (`offset_ray_origin`) and `t_max` stops just short of the
/// light, as the renderer's shadow rays do.
pub fn shadow_rays(scene: &Scene, reference: &dyn Accel, primary: &[(Ray, f32)], seed: u64) -> Vec<(Ray, f32)> {
    let points = shading_points(reference, primary);
    points
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, (ray, hit))| {
            let si = scene.surface_interaction(ray, hit);
            let mut rng = Rng::new(seed, Domain::Analysis, 2, i as u64);
            let mut out = Vec::with_capacity(scene.lights.len());
            for light in &scene.lights {
                let target = match light {
                    Light::Point { position, .. } => *position,
                    Light::Area(a) => a.center + a.u * (rng.f32() - 0.5) + a.v * (rng.f32() - 0.5),
                };
                let o = offset_ray_origin(si.p, si.p_error, si.ng, target - si.p);
                let d = target - o;
                if d != Vec3A::ZERO && d.is_finite() {
                    out.push((Ray::new(o, d), 1.0 - 1e-4));
                }
            }
            out
        })
        .collect()
}

/// Incoherent rays: from each hit point of `primary` (found with `reference`),
/// a seeded direction uniform over the hemisphere on the side the primary
/// ray came from (diffuse bounces).
pub fn incoherent_rays(scene: &Scene, reference: &dyn Accel, primary: &[(Ray, f32)], seed: u64) -> Vec<(Ray, f32)> {
    let points = shading_points(reference, primary);
    points
        .par_iter()
        .enumerate()
        .map(|(i, (ray, hit))| {
            let si = scene.surface_interaction(ray, hit);
            let mut rng = Rng::new(seed, Domain::Analysis, 3, i as u64);
            let z = rng.f32() * 2.0 - 1.0;
            let phi = rng.f32() * std::f32::consts::TAU;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let mut d = Vec3A::new(r * phi.cos(), r * phi.sin(), z);
            // Same side as the viewer: reflect directions that go through the surface.
            if (d.dot(si.ng) > 0.0) != (ray.dir.dot(si.ng) < 0.0) {
                d = -d;
            }
            let o = offset_ray_origin(si.p, si.p_error, si.ng, d);
            (Ray::new(o, d), f32::INFINITY)
        })
        .collect()
}

/// The three standard sets for `scene` at `width`×`height`: camera rays,
/// shadow rays and incoherent rays (the last two from the camera rays' hits,
/// found with `reference`).
pub fn standard_ray_sets(scene: &Scene, reference: &dyn Accel, width: u32, height: u32, seed: u64) -> Vec<RaySet> {
    let camera = camera_rays(scene, width, height);
    let shadow = shadow_rays(scene, reference, &camera, seed);
    let incoherent = incoherent_rays(scene, reference, &camera, seed);
    vec![
        RaySet {
            name: "camera",
            query: Query::Closest,
            rays: camera,
        },
        RaySet {
            name: "shadow",
            query: Query::Occluded,
            rays: shadow,
        },
        RaySet {
            name: "incoherent",
            query: Query::Closest,
            rays: incoherent,
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::brute::BruteForce;
    use crate::accel::TriangleTest;
    use crate::math::Vec3;
    use crate::scene::{Camera, Material, Object, Quad, RenderSettings, Shape};

    #[test]
    fn ray_sets_hit_a_quad_and_are_counted() {
        let scene = Scene {
            settings: RenderSettings::default(),
            camera: Camera::new(Vec3A::new(0.0, 1.0, 5.0), Vec3A::ZERO, Vec3A::Y, 40.0).unwrap(),
            materials: vec![Material::diffuse("white", Vec3A::ONE)],
            lights: vec![Light::Point {
                position: Vec3A::new(0.0, 3.0, 0.0),
                intensity: Vec3A::ONE,
            }],
            meshes: vec![],
            objects: vec![Object {
                name: "floor".into(),
                shape: Shape::Quad(
                    Quad::new(
                        Vec3A::new(-50.0, 0.0, -50.0),
                        Vec3A::from(Vec3::new(100.0, 0.0, 0.0)),
                        Vec3A::new(0.0, 0.0, 100.0),
                    )
                    .unwrap(),
                ),
                material: 0,
            }],
        };
        let brute = BruteForce::new(&scene, TriangleTest::Watertight);
        let sets = standard_ray_sets(&scene, &brute, 32, 24, 1);
        assert_eq!(sets[0].rays.len(), 32 * 24);
        let camera = throughput(&brute, &sets[0].rays, Query::Closest);
        // The lower part of the image sees the floor, the upper part the sky.
        assert!(camera.hits > 0 && camera.hits < 32 * 24, "{camera:?}");
        // Nothing stands between the floor and the light.
        assert_eq!(sets[1].rays.len(), camera.hits);
        assert_eq!(throughput(&brute, &sets[1].rays, Query::Occluded).hits, 0);
        // Bounce rays leave the floor upwards and escape.
        assert!(sets[2].rays.iter().all(|(r, _)| r.dir.y >= 0.0));
        assert_eq!(throughput(&brute, &sets[2].rays, Query::Closest).hits, 0);
    }
}
