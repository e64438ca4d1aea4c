//! Accelerator kernels: KD-tree (and Embree) builds, closest-hit and
//! occlusion throughput on the camera, shadow and incoherent ray sets of
//! `caustic bench`, and the two ray–triangle tests.
//!
//! `cargo bench --bench accel` (about two minutes; a filter such as
//! `cargo bench --bench accel -- rays/` runs a part). The dragon is used when
//! its asset is already on disk, else skipped (the build group) or replaced
//! by the generated torus scene (the ray groups; the group name says which).

mod common;

use caustic::accel::kdtree::KdTreeAccel;
use caustic::accel::triangle::{moller_trumbore, WatertightRay};
use caustic::accel::{self, Accel, AccelKind, AccelOptions};
use caustic::analysis::bench::default_accels;
use caustic::analysis::rays::{count_hits, standard_ray_sets, Query};
use caustic::math::rng::{Domain, Rng};
use caustic::math::{Ray, Vec3A};
use caustic::scene::Scene;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode, Throughput};
use std::hint::black_box;

/// Rays per set in the throughput benches (the camera set is a 341×193 image).
const RAYS: usize = 1 << 16;

fn build_group(c: &mut Criterion, label: &str, scene: &Scene) {
    let options = AccelOptions::default();
    let mut group = c.benchmark_group(format!("build/{label}"));
    // Builds take up to seconds: the same single iteration per sample.
    group.sampling_mode(SamplingMode::Flat);
    group.throughput(Throughput::Elements(scene.instanced_triangles()));
    group.bench_function("kdtree", |b| b.iter(|| black_box(KdTreeAccel::build(scene, &options))));
    if cfg!(feature = "embree") {
        group.bench_function("embree", |b| {
            b.iter(|| black_box(accel::build(scene, AccelKind::Embree, &options).expect("Embree builds")))
        });
    }
    group.finish();
}

fn builds(c: &mut Criterion) {
    build_group(c, "torus-131k", &common::torus_scene());
    if let Some(dragon) = common::dragon_scene() {
        build_group(c, "dragon", &dragon);
    }
}

fn queries(c: &mut Criterion) {
    let (label, scene) = match common::dragon_scene() {
        Some(s) => ("dragon", s),
        None => ("torus-131k", common::torus_scene()),
    };
    let options = AccelOptions::default();
    let accels: Vec<(AccelKind, Box<dyn Accel>)> = default_accels()
        .into_iter()
        .map(|k| (k, accel::build(&scene, k, &options).expect("accelerator builds")))
        .collect();
    // The same rays for every accelerator: shadow rays from the first one's camera hits.
    let sets = standard_ray_sets(&scene, accels[0].1.as_ref(), RAYS, 16.0 / 9.0, 1);
    for set in &sets {
        let mut group = c.benchmark_group(format!("rays/{label}/{}", set.kind));
        group.throughput(Throughput::Elements(set.rays.len() as u64));
        for (kind, accel) in &accels {
            for query in [Query::Closest, Query::Occluded] {
                group.bench_function(BenchmarkId::new(kind.name(), query.name()), |b| {
                    b.iter(|| count_hits(accel.as_ref(), black_box(&set.rays), query))
                });
            }
        }
        group.finish();
    }
}

/// Ray–triangle pairs: small random triangles in the unit cube, each with a
/// ray from a random point aimed near its centroid (about half of them hit).
fn triangle_pairs(n: usize) -> Vec<(Ray, [Vec3A; 3])> {
    let mut rng = Rng::new(3, Domain::Analysis, 20, 0);
    let mut point = |scale: f32| Vec3A::new(rng.f32(), rng.f32(), rng.f32()) * scale;
    (0..n)
        .map(|_| {
            let c = point(1.0);
            let tri = [c + point(0.1) - 0.05, c + point(0.1) - 0.05, c + point(0.1) - 0.05];
            let origin = point(4.0) - 2.0;
            let target = (tri[0] + tri[1] + tri[2]) / 3.0 + point(0.06) - 0.03;
            (Ray::new(origin, (target - origin).normalize()), tri)
        })
        .collect()
}

fn triangles(c: &mut Criterion) {
    let pairs = triangle_pairs(4096);
    let mut group = c.benchmark_group("triangle");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    // The watertight test's per-ray setup (permutation, shear) is part of
    // its cost for one triangle; traversal amortises it over a leaf.
    group.bench_function("watertight", |b| {
        b.iter(|| {
            black_box(&pairs)
                .iter()
                .filter(|(r, [p0, p1, p2])| WatertightRay::new(r).intersect(*p0, *p1, *p2, f32::INFINITY).is_some())
                .count()
        })
    });
    group.bench_function("watertight_prepared", |b| {
        let prepared: Vec<(WatertightRay, [Vec3A; 3])> =
            pairs.iter().map(|(r, t)| (WatertightRay::new(r), *t)).collect();
        b.iter(|| {
            black_box(&prepared)
                .iter()
                .filter(|(w, [p0, p1, p2])| w.intersect(*p0, *p1, *p2, f32::INFINITY).is_some())
                .count()
        })
    });
    group.bench_function("moller_trumbore", |b| {
        b.iter(|| {
            black_box(&pairs)
                .iter()
                .filter(|(r, [p0, p1, p2])| moller_trumbore(r, *p0, *p1, *p2, f32::INFINITY).is_some())
                .count()
        })
    });
    group.finish();
}

criterion_group! {
    name = accel_benches;
    config = common::quick(3);
    targets = triangles, queries, builds
}
criterion_main!(accel_benches);
