//! Seeded ray sets of the three kinds a renderer casts, and a timed run of a
//! set through any [`Accel`]: the kernels of `caustic bench`
//! (`analysis::bench`), of the Criterion benches in `benches/` and of the
//! `#[ignore]`d throughput tests.
//!
//! * **camera**: primary rays of the scene camera, one jittered sample per
//!   pixel in scanline order (coherent: neighbours traverse the same cells);
//! * **shadow**: from the camera rays' hit points towards a seeded point of
//!   every light, stopping just short of it (`occluded` queries);
//! * **incoherent**: uniform origins in the scene bounds, uniform directions
//!   on the sphere (every ray takes its own path through the structure).
//!
//! Every set is a pure function of the scene, the seed and the count (the
//! shadow set also of the accelerator that found the camera hits, which the
//! caller chooses once and uses for every accelerator it compares), so all
//! accelerators are timed on exactly the same rays.

use crate::accel::{Accel, Hit};
use crate::math::rng::{Domain, Rng};
use crate::math::sampling::uniform_sphere;
use crate::math::{offset_ray_origin, Aabb, Ray, Vec2, Vec3A};
use crate::scene::{Light, Scene};
use rayon::prelude::*;
use std::fmt;
use std::time::Instant;

/// Rays handed to one rayon task: big enough to amortise scheduling, small
/// enough that neighbouring camera rays stay on one thread, as in a tiled
/// renderer (a 32×32 tile).
pub const CHUNK: usize = 1024;

/// Which query a ray set is timed with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Query {
    /// Closest hit (`Accel::intersect`).
    Closest,
    /// Any hit (`Accel::occluded`).
    Occluded,
}

impl Query {
    /// `"closest"` or `"occluded"`.
    pub fn name(self) -> &'static str {
        match self {
            Query::Closest => "closest",
            Query::Occluded => "occluded",
        }
    }
}

/// The kinds of ray set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RayKind {
    /// Primary rays from the scene camera (coherent).
    Camera,
    /// Occlusion rays from the camera rays' hits towards the lights.
    Shadow,
    /// Random origins in the scene bounds, random directions.
    Incoherent,
}

impl RayKind {
    /// The three kinds, in report order.
    pub const ALL: [RayKind; 3] = [RayKind::Camera, RayKind::Shadow, RayKind::Incoherent];

    /// `"camera"`, `"shadow"` or `"incoherent"`.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Shadow => "shadow",
            RayKind::Incoherent => "incoherent",
        }
    }

    /// The query the kind is timed with: occlusion for shadow rays, closest hit otherwise.
    pub fn query(self) -> Query {
        match self {
            RayKind::Shadow => Query::Occluded,
            RayKind::Camera | RayKind::Incoherent => Query::Closest,
        }
    }
}

impl fmt::Display for RayKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of rays with their `t_max`, of one kind.
#[derive(Clone, Debug)]
pub struct RaySet {
    /// What the rays are.
    pub kind: RayKind,
    /// Rays and their `t_max`.
    pub rays: Vec<(Ray, f32)>,
}

impl RaySet {
    /// The query the set is timed with.
    pub fn query(&self) -> Query {
        self.kind.query()
    }
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

    /// Millions of rays per CPU second (one core's throughput), when known
    /// and the run lasted at least one clock tick of CPU time.
    pub fn mrays_per_cpu_s(&self) -> Option<f64> {
        self.cpu_seconds
            .filter(|&c| c >= 0.01)
            .map(|c| self.rays as f64 / c / 1e6)
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

/// Counts the rays of `rays` that hit (closest) or are occluded, on the
/// current rayon pool in chunks of [`CHUNK`]. The count does not depend on
/// the number of threads.
pub fn count_hits(accel: &dyn Accel, rays: &[(Ray, f32)], query: Query) -> usize {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|(r, t_max)| match query {
                    Query::Closest => accel.intersect(r, *t_max).is_some(),
                    Query::Occluded => accel.occluded(r, *t_max),
                })
                .count()
        })
        .sum()
}

/// Times [`count_hits`] on `rays`.
pub fn throughput(accel: &dyn Accel, rays: &[(Ray, f32)], query: Query) -> Throughput {
    let cpu_start = process_cpu_seconds();
    let start = Instant::now();
    let hits = count_hits(accel, rays, query);
    Throughput {
        rays: rays.len(),
        hits,
        seconds: start.elapsed().as_secs_f64(),
        cpu_seconds: cpu_start.zip(process_cpu_seconds()).map(|(a, b)| b - a),
    }
}

/// The smallest `width × height` image with about the aspect `aspect`
/// (width / height) that has at least `count` pixels.
pub fn image_for(count: usize, aspect: f32) -> (u32, u32) {
    let aspect = if aspect.is_finite() && aspect > 0.0 {
        aspect
    } else {
        1.0
    };
    let width = ((count as f64 * aspect as f64).sqrt().round() as u64).clamp(1, u32::MAX as u64);
    let height = (count as u64).div_ceil(width).max(1);
    (width as u32, height.min(u32::MAX as u64) as u32)
}

/// `count` camera rays over a `width × height` image (from [`image_for`]),
/// one per pixel in scanline order, each through a seeded jittered point
/// of its pixel (the renderer's one-sample case).
pub fn camera_rays(scene: &Scene, count: usize, aspect: f32, seed: u64) -> Vec<(Ray, f32)> {
    let (width, height) = image_for(count, aspect);
    (0..count as u64)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % width as u64, i / width as u64);
            let (jx, jy) = Rng::new(seed, Domain::Analysis, 10, i).f32x2();
            let ray = scene.camera.ray(x as f32 + jx, y as f32 + jy, width, height);
            (ray, f32::INFINITY)
        })
        .collect()
}

/// Hit points of `primary` found with `reference`, in the order of `primary`.
fn shading_points(reference: &dyn Accel, primary: &[(Ray, f32)]) -> Vec<(Ray, Hit)> {
    primary
        .par_iter()
        .filter_map(|(r, t_max)| reference.intersect(r, *t_max).map(|h| (*r, h)))
        .collect()
}

/// Shadow rays from the hit points of `primary` (found with `reference`)
/// towards each light: a point light's position, and one seeded uniform
/// point of an area light's rectangle per hit point. The origins are offset
/// off the surface with its error bound (`offset_ray_origin`) and `t_max`
/// stops just short of the light, as the renderer's shadow rays do.
pub fn shadow_rays(scene: &Scene, reference: &dyn Accel, primary: &[(Ray, f32)], seed: u64) -> Vec<(Ray, f32)> {
    let points = shading_points(reference, primary);
    points
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, (ray, hit))| {
            let si = scene.surface_interaction(ray, hit);
            let mut rng = Rng::new(seed, Domain::Analysis, 11, i as u64);
            let mut out = Vec::with_capacity(scene.lights.len());
            for light in &scene.lights {
                let target = match light {
                    Light::Point { position, .. } => *position,
                    Light::Spot(s) => s.position,
                    Light::Area(a) => a.center + a.u * (rng.f32() - 0.5) + a.v * (rng.f32() - 0.5),
                    Light::Environment { .. } | Light::Directional { .. } => continue,
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

/// The box incoherent rays start in: the scene bounds, or the unit cube
/// around the origin when the scene has no finite bounds.
fn ray_bounds(scene: &Scene) -> Aabb {
    let b = scene.bounds();
    if b.is_empty() || !b.min.is_finite() || !b.max.is_finite() {
        Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0))
    } else {
        b
    }
}

/// `count` incoherent rays: origins uniform in the scene bounds, directions
/// uniform on the unit sphere, unbounded.
pub fn incoherent_rays(scene: &Scene, count: usize, seed: u64) -> Vec<(Ray, f32)> {
    let bounds = ray_bounds(scene);
    let extent = bounds.extent();
    (0..count as u64)
        .into_par_iter()
        .map(|i| {
            let mut rng = Rng::new(seed, Domain::Analysis, 12, i);
            let o = bounds.min + extent * Vec3A::new(rng.f32(), rng.f32(), rng.f32());
            let (u1, u2) = rng.f32x2();
            (Ray::new(o, uniform_sphere(Vec2::new(u1, u2))), f32::INFINITY)
        })
        .collect()
}

/// The three standard sets for `scene`: `count` camera rays over an image of
/// aspect `aspect`, the shadow rays from their hits (found with `reference`),
/// and `count` incoherent rays.
pub fn standard_ray_sets(scene: &Scene, reference: &dyn Accel, count: usize, aspect: f32, seed: u64) -> Vec<RaySet> {
    let camera = camera_rays(scene, count, aspect, seed);
    let shadow = shadow_rays(scene, reference, &camera, seed);
    let incoherent = incoherent_rays(scene, count, seed);
    vec![
        RaySet {
            kind: RayKind::Camera,
            rays: camera,
        },
        RaySet {
            kind: RayKind::Shadow,
            rays: shadow,
        },
        RaySet {
            kind: RayKind::Incoherent,
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
    use crate::scene::{Camera, Material, Object, Quad, Shape, Sphere};

    fn floor_scene() -> Scene {
        Scene {
            media: Default::default(),
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
            ambient: Vec3A::ZERO,
            water_medium: None,
        }
    }

    #[test]
    fn image_has_enough_pixels_and_the_aspect() {
        for (n, aspect) in [
            (1, 1.0),
            (1000, 16.0 / 9.0),
            (230_400, 16.0 / 9.0),
            (7, 0.25),
            (5, f32::NAN),
        ] {
            let (w, h) = image_for(n, aspect);
            assert!(w as usize * h as usize >= n, "{n} {aspect}: {w}×{h}");
            // No spare row: the last row holds at least one of the rays.
            assert!((w as usize) * (h as usize - 1) < n, "{n} {aspect}: {w}×{h}");
        }
        let (w, h) = image_for(100_000, 2.0);
        assert!((w as f32 / h as f32 - 2.0).abs() < 0.01, "{w}×{h}");
        assert_eq!(image_for(230_400, 16.0 / 9.0), (640, 360));
    }

    #[test]
    fn ray_sets_hit_a_quad_and_are_counted() {
        let scene = floor_scene();
        let brute = BruteForce::new(&scene, TriangleTest::Watertight);
        let sets = standard_ray_sets(&scene, &brute, 768, 4.0 / 3.0, 1);
        assert_eq!(sets[0].rays.len(), 768);
        let camera = throughput(&brute, &sets[0].rays, Query::Closest);
        // The lower part of the image sees the floor, the upper part the sky.
        assert!(camera.hits > 0 && camera.hits < 768, "{camera:?}");
        // Nothing stands between the floor and the light.
        assert_eq!(sets[1].rays.len(), camera.hits);
        assert_eq!(throughput(&brute, &sets[1].rays, Query::Occluded).hits, 0);
        // Incoherent rays start on the (flat) floor's bounds: those going down hit it
        // from the origin's own plane, never at t > 0 beyond rounding; those going
        // up escape. So about none hit, and all are unit and finite.
        assert_eq!(sets[2].rays.len(), 768);
        assert!(sets[2]
            .rays
            .iter()
            .all(|(r, _)| (r.dir.length() - 1.0).abs() < 1e-5 && r.origin.is_finite()));
    }

    #[test]
    fn sets_are_seeded_and_occlusion_is_seen() {
        let mut scene = floor_scene();
        scene.objects.push(Object {
            name: "ball".into(),
            shape: Shape::Sphere(Sphere {
                center: Vec3A::new(0.0, 1.5, 0.0),
                radius: 0.5,
            }),
            material: 0,
        });
        let brute = BruteForce::new(&scene, TriangleTest::Watertight);
        let a = standard_ray_sets(&scene, &brute, 2000, 1.5, 7);
        let b = standard_ray_sets(&scene, &brute, 2000, 1.5, 7);
        let c = standard_ray_sets(&scene, &brute, 2000, 1.5, 8);
        for (x, y) in a.iter().zip(&b) {
            assert_eq!(x.kind, y.kind);
            assert_eq!(x.rays, y.rays);
        }
        assert_ne!(a[2].rays, c[2].rays);
        // The ball, between the light and the floor below it, shadows some floor points.
        let shadow = throughput(&brute, &a[1].rays, Query::Occluded);
        assert!(shadow.hits > 0 && shadow.hits < shadow.rays, "{shadow:?}");
        // Random rays inside the bounds (floor to ball top) hit the floor or the ball about half the time.
        let incoherent = throughput(&brute, &a[2].rays, Query::Closest);
        assert!(incoherent.hits > 200 && incoherent.hits < 1800, "{incoherent:?}");
        assert!(incoherent.mrays_per_s() > 0.0 && incoherent.mrays_per_s().is_finite());
    }
}
