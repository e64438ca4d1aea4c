//! KD-tree against the brute-force oracle: identical closest hits (object,
//! triangle, t, u, v bit for bit) and identical occlusion answers on seeded
//! random rays, for both triangle tests, on meshes built here.

use caustic::accel::brute::BruteForce;
use caustic::accel::kdtree::KdTreeAccel;
use caustic::accel::{Accel, AccelOptions, Hit, TriangleTest};
use caustic::math::rng::{Domain, Rng};
use caustic::math::{Aabb, Ray, Transform, Vec3, Vec3A};
use caustic::scene::{Camera, Material, Mesh, Object, Quad, Scene, Shape, Sphere};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

const RAYS_PER_MESH: u64 = 100_000;

use caustic::geometry::generate::icosphere;

/// Random triangles of mixed sizes, including long needles, in [-1, 1]³.
fn soup(n: usize, seed: u64) -> Mesh {
    let mut rng = Rng::new(seed, Domain::Analysis, 1, 0);
    let mut p = Vec::new();
    let mut tris = Vec::new();
    for i in 0..n {
        let c = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3::ONE;
        let size = if i % 10 == 0 { 0.8 } else { 0.08 };
        for _ in 0..3 {
            let d = Vec3::new(rng.f32(), rng.f32(), rng.f32()) - Vec3::splat(0.5);
            p.push(c + d * size);
        }
        if i % 17 == 0 {
            // Needle: third vertex almost on the first edge.
            let k = p.len();
            p[k - 1] = p[k - 3] * 0.5 + p[k - 2] * 0.5 + Vec3::splat(1e-4);
        }
        let k = p.len() as u32;
        tris.push([k - 3, k - 2, k - 1]);
    }
    Mesh::new("soup", p, tris, None).unwrap()
}

/// Axis-aligned grids: a floor (z = 0) of n×n quads, a wall (x = 0) sharing
/// its edge, a second copy of part of the floor (coplanar duplicate
/// triangles: exact ties), and a degenerate triangle.
fn grid(n: u32) -> Mesh {
    let mut p = Vec::new();
    let mut tris = Vec::new();
    let step = 1.0 / n as f32;
    let sheet = |p: &mut Vec<Vec3>, tris: &mut Vec<[u32; 3]>, f: &dyn Fn(f32, f32) -> Vec3, m: u32| {
        let base = p.len() as u32;
        for j in 0..=m {
            for i in 0..=m {
                p.push(f(i as f32 * step, j as f32 * step));
            }
        }
        for j in 0..m {
            for i in 0..m {
                let a = base + j * (m + 1) + i;
                let b = a + 1;
                let c = a + m + 1;
                let d = c + 1;
                tris.push([a, b, d]);
                tris.push([a, d, c]);
            }
        }
    };
    sheet(&mut p, &mut tris, &|u, v| Vec3::new(u, v, 0.0), n);
    sheet(&mut p, &mut tris, &|u, v| Vec3::new(0.0, u, v), n);
    sheet(&mut p, &mut tris, &|u, v| Vec3::new(u, v, 0.0), n / 2);
    sheet(&mut p, &mut tris, &|u, v| Vec3::new(u, 0.5, v), n / 2);
    let k = p.len() as u32;
    p.extend([
        Vec3::new(0.3, 0.3, 0.3),
        Vec3::new(0.3, 0.3, 0.3),
        Vec3::new(0.6, 0.6, 0.6),
    ]);
    tris.push([k, k + 1, k + 2]);
    Mesh::new("grid", p, tris, None).unwrap()
}

/// A closed cube [-1, 1]³, each face an n×n grid of quads (shared vertices).
fn closed_box(n: u32) -> Mesh {
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut p = Vec::new();
    let mut tris = Vec::new();
    let mut vertex = |q: [i32; 3], p: &mut Vec<Vec3>| {
        *index.entry(q).or_insert_with(|| {
            p.push(Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * (2.0 / n as f32) - Vec3::ONE);
            p.len() as u32 - 1
        })
    };
    let n = n as i32;
    for axis in 0..3 {
        for side in [0, n] {
            for j in 0..n {
                for i in 0..n {
                    let at = |a: i32, b: i32| {
                        let mut q = [0; 3];
                        q[axis] = side;
                        q[(axis + 1) % 3] = a;
                        q[(axis + 2) % 3] = b;
                        q
                    };
                    let a = vertex(at(i, j), &mut p);
                    let b = vertex(at(i + 1, j), &mut p);
                    let c = vertex(at(i, j + 1), &mut p);
                    let d = vertex(at(i + 1, j + 1), &mut p);
                    tris.push([a, b, d]);
                    tris.push([a, d, c]);
                }
            }
        }
    }
    Mesh::new("box", p, tris, None).unwrap()
}

/// The mesh instanced three times (identity, rotated and scaled, non-uniform
/// scale with an axis-aligned rotation) plus two spheres and two quads.
fn scene_with(mesh: Mesh) -> Scene {
    let mesh = Arc::new(mesh);
    let instance = |name: &str, t: Transform| Object {
        name: name.into(),
        shape: Shape::Mesh {
            mesh: 0,
            transform: t,
            smooth: false,
        },
        material: 0,
    };
    let analytic = |name: &str, shape: Shape| Object {
        name: name.into(),
        shape,
        material: 0,
    };
    let objects = vec![
        instance("plain", Transform::IDENTITY),
        instance(
            "turned",
            Transform::from_srt(Vec3::splat(0.7), Vec3::new(30.0, 45.0, 10.0), Vec3::new(2.5, 0.3, -0.5)).unwrap(),
        ),
        instance(
            "stretched",
            Transform::from_srt(
                Vec3::new(1.5, 0.5, 1.0),
                Vec3::new(0.0, 90.0, 0.0),
                Vec3::new(-2.0, 1.0, 1.0),
            )
            .unwrap(),
        ),
        analytic(
            "ball",
            Shape::Sphere(Sphere {
                center: Vec3A::new(0.5, 2.5, 0.0),
                radius: 0.75,
            }),
        ),
        analytic(
            "inner ball",
            Shape::Sphere(Sphere {
                center: Vec3A::new(0.1, 0.1, 0.1),
                radius: 0.3,
            }),
        ),
        analytic(
            "floor",
            Shape::Quad(
                Quad::new(
                    Vec3A::new(-4.0, -2.0, -4.0),
                    Vec3A::new(8.0, 0.0, 0.0),
                    Vec3A::new(0.0, 0.0, 8.0),
                )
                .unwrap(),
            ),
        ),
        analytic(
            "tilted",
            Shape::Quad(
                Quad::new(
                    Vec3A::new(-1.0, -1.0, 2.0),
                    Vec3A::new(2.0, 0.5, 0.0),
                    Vec3A::new(0.0, 2.0, 0.7),
                )
                .unwrap(),
            ),
        ),
    ];
    Scene {
        media: Default::default(),
        camera: Camera::new(Vec3A::new(0.0, 0.0, 8.0), Vec3A::ZERO, Vec3A::Y, 45.0).unwrap(),
        materials: vec![Material::diffuse("white", Vec3A::ONE)],
        lights: vec![],
        meshes: vec![mesh],
        objects,
        ambient: Vec3A::ZERO,
        water_medium: None,
    }
}

/// World-space vertices of every mesh instance.
fn world_vertices(scene: &Scene) -> Vec<Vec3A> {
    let mut out = Vec::new();
    for o in &scene.objects {
        if let Shape::Mesh { mesh, transform, .. } = &o.shape {
            let m = &scene.meshes[*mesh as usize];
            out.extend(m.positions.iter().map(|&p| transform.point(Vec3A::from(p))));
        }
    }
    out
}

fn unit_vector(rng: &mut Rng) -> Vec3A {
    let z = rng.f32() * 2.0 - 1.0;
    let phi = rng.f32() * std::f32::consts::TAU;
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Ray `i` of the seeded set: mixes uniform rays from inside and around the
/// scene, rays aimed at vertices, axis-parallel rays (two zero direction
/// components) and rays in axis planes through vertex coordinates (one zero
/// component), some with a finite `t_max`.
fn ray(i: u64, seed: u64, bounds: &Aabb, vertices: &[Vec3A]) -> (Ray, f32) {
    let mut rng = Rng::new(seed, Domain::Analysis, 7, i);
    let around = |rng: &mut Rng, grow: f32| {
        let e = bounds.extent() * grow;
        let lo = bounds.min - (e - bounds.extent()) * 0.5;
        lo + e * Vec3A::new(rng.f32(), rng.f32(), rng.f32())
    };
    let vertex = |rng: &mut Rng| vertices[rng.below(vertices.len() as u32) as usize];
    let (origin, dir) = match i % 6 {
        0 => (around(&mut rng, 1.2), unit_vector(&mut rng)),
        1 => {
            let o = around(&mut rng, 2.0);
            let target = around(&mut rng, 0.8);
            (o, target - o)
        }
        2 => {
            // Two zero components: origin shares two coordinates with a vertex.
            let v = vertex(&mut rng);
            let axis = rng.below(3) as usize;
            let mut o = v;
            o[axis] = around(&mut rng, 1.5)[axis];
            let mut d = Vec3A::ZERO;
            d[axis] = if rng.f32() < 0.5 { 1.0 } else { -1.0 };
            (o, d)
        }
        3 => {
            // One zero component: a ray in the axis plane through a vertex.
            let v = vertex(&mut rng);
            let axis = rng.below(3) as usize;
            let mut o = around(&mut rng, 1.5);
            o[axis] = v[axis];
            let mut d = unit_vector(&mut rng);
            d[axis] = 0.0;
            (o, d)
        }
        4 => {
            let o = around(&mut rng, 1.5);
            (o, vertex(&mut rng) - o)
        }
        _ => (around(&mut rng, 1.0), unit_vector(&mut rng)),
    };
    let t_max = if i % 6 == 5 { rng.f32() * 3.0 } else { f32::INFINITY };
    (Ray::new(origin, dir), t_max)
}

/// Compares the KD-tree with brute force on `RAYS_PER_MESH` rays for both
/// triangle tests; panics listing the first disagreements.
fn check_against_oracle(scene: &Scene, seed: u64) {
    let bounds = scene.bounds();
    let vertices = world_vertices(scene);
    for test in [TriangleTest::Watertight, TriangleTest::MollerTrumbore] {
        let options = AccelOptions {
            triangle_test: test,
            ..Default::default()
        };
        let kd = KdTreeAccel::build(scene, &options);
        let brute = BruteForce::new(scene, test);
        let results: Vec<(Option<Hit>, Option<Hit>, bool, bool)> = (0..RAYS_PER_MESH)
            .into_par_iter()
            .map(|i| {
                let (r, t_max) = ray(i, seed, &bounds, &vertices);
                let closest = brute.intersect(&r, t_max);
                // The oracle's any-hit answer equals "has a closest hit"; it is
                // also queried directly on every 8th ray (it costs as much).
                let brute_occluded = if i % 8 == 0 {
                    brute.occluded(&r, t_max)
                } else {
                    closest.is_some()
                };
                (kd.intersect(&r, t_max), closest, kd.occluded(&r, t_max), brute_occluded)
            })
            .collect();
        let mut bad = Vec::new();
        let mut hits_per_object = vec![0usize; scene.objects.len()];
        for (i, (a, b, oa, ob)) in results.iter().enumerate() {
            if a != b || oa != ob {
                bad.push((i, *a, *b, *oa, *ob));
            }
            if let Some(h) = b {
                hits_per_object[h.instance as usize] += 1;
            }
        }
        assert!(
            bad.is_empty(),
            "{:?}: {} of {RAYS_PER_MESH} rays disagree; first: {:#?}",
            test,
            bad.len(),
            &bad[..bad.len().min(5)]
                .iter()
                .map(|&(i, a, b, oa, ob)| (ray(i as u64, seed, &bounds, &vertices), a, b, oa, ob))
                .collect::<Vec<_>>()
        );
        // The rays must exercise every object, or the comparison proves little.
        for (i, &n) in hits_per_object.iter().enumerate() {
            assert!(n > 30, "{test:?}: object {i} hit by only {n} rays");
        }
        let stats = kd.stats();
        assert_eq!(stats.blas_count, 1);
        assert_eq!(stats.instances, scene.objects.len());
    }
}

#[test]
fn icosphere_matches_brute_force() {
    check_against_oracle(&scene_with(icosphere(2)), 1);
}

#[test]
fn triangle_soup_matches_brute_force() {
    check_against_oracle(&scene_with(soup(600, 2)), 2);
}

#[test]
fn axis_aligned_grid_matches_brute_force() {
    check_against_oracle(&scene_with(grid(10)), 3);
}

#[test]
fn closed_box_matches_brute_force() {
    check_against_oracle(&scene_with(closed_box(5)), 4);
}

#[test]
fn empty_scene_and_degenerate_rays_find_nothing() {
    let mut scene = scene_with(icosphere(1));
    let kd = KdTreeAccel::build(&scene, &AccelOptions::default());
    let brute = BruteForce::new(&scene, TriangleTest::Watertight);
    let rays = [
        Ray::new(Vec3A::ZERO, Vec3A::ZERO),
        Ray::new(Vec3A::new(f32::NAN, 0.0, 0.0), Vec3A::X),
        Ray::new(Vec3A::ZERO, Vec3A::new(f32::NAN, 1.0, 0.0)),
        Ray::new(Vec3A::ZERO, Vec3A::new(f32::INFINITY, 0.0, 0.0)),
    ];
    for r in rays {
        assert_eq!(
            kd.intersect(&r, f32::INFINITY),
            brute.intersect(&r, f32::INFINITY),
            "{r:?}"
        );
        assert_eq!(
            kd.occluded(&r, f32::INFINITY),
            brute.occluded(&r, f32::INFINITY),
            "{r:?}"
        );
    }
    // t_max ≤ 0 or NaN: nothing.
    let r = Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z);
    assert!(kd.intersect(&r, f32::INFINITY).is_some());
    for t in [0.0, -1.0, f32::NAN] {
        assert!(kd.intersect(&r, t).is_none() && !kd.occluded(&r, t));
    }
    scene.objects.clear();
    let empty = KdTreeAccel::build(&scene, &AccelOptions::default());
    assert!(empty.intersect(&r, f32::INFINITY).is_none());
    assert!(!empty.occluded(&r, f32::INFINITY));
    assert_eq!(empty.stats().blas_count, 0);
}

#[test]
fn node_boxes_cover_the_scene() {
    let scene = scene_with(icosphere(3));
    let kd = KdTreeAccel::build(&scene, &AccelOptions::default());
    let all = kd.node_boxes(u32::MAX);
    let shallow = kd.node_boxes(2);
    assert!(shallow.iter().all(|&(_, d)| d <= 2));
    assert!(all.len() > shallow.len());
    // Roots (depth 0): the top level plus one per mesh instance.
    assert_eq!(all.iter().filter(|&&(_, d)| d == 0).count(), 1 + 3);
    let bounds = scene.bounds();
    let root = all.iter().find(|&&(_, d)| d == 0).unwrap().0;
    assert!(root.min.cmple(bounds.min + 1e-4).all() && root.max.cmpge(bounds.max - 1e-4).all());
    let details: HashMap<String, String> = kd.stats().details.into_iter().collect();
    assert!(details["bottom depth"].parse::<u32>().unwrap() > 5);
    assert_eq!(details["triangles"], "1280");
}
