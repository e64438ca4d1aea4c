//! Cross-check of two accelerators (`caustic crosscheck`): seeded rays are cast
//! through both, and every answer is classified as an agreement, a tie (both
//! answers are right within floating-point precision) or a disagreement.
//!
//! # The rays
//!
//! Ray `i` is of kind `RayKind::ALL[i % 4]`, so each kind gets 25% of the rays
//! (±1), interleaved so that any prefix of the ray set is balanced. It draws
//! from its own stream `Rng::new(seed, Domain::Analysis, i, kind)`; rays are
//! processed by rayon in fixed chunks and the chunks merged in index order, so
//! the report is identical for any thread count.
//!
//! - **camera**: primary rays of `scene.camera` through a uniformly jittered
//!   film position of the scene's image;
//! - **bounds**: half from a point on a sphere of 1.5× the scene bounds'
//!   half-diagonal towards a uniform point of the bounds, half from a uniform
//!   point inside the bounds in a uniform direction;
//! - **feature**: aimed *exactly* (up to the rounding of the normalised
//!   direction) at a mesh vertex (1/3) or a point on a mesh edge (2/3) of a
//!   random triangle of a random object, transformed to world space; quads
//!   give their corners and edges, spheres a point of their silhouette seen
//!   from the origin (the sphere's boundary), disks a point of their rim,
//!   cylinders a point of a rim or of a silhouette line. Origins: half on the outer
//!   sphere, half in the object's bounds scaled 3× about its centre;
//! - **shadow**: from the first hit of a bounds ray (found by accelerator `a`,
//!   origin moved off the surface with `offset_ray_origin`) towards a random
//!   light position (a point light, or a uniform point of an area light; a
//!   uniform point of the bounds when the scene has no light), with
//!   `t_max` = the distance to it.
//!
//! Every ray gets a closest-hit query (`t_max` = ∞, or the light distance for
//! shadow rays) and an occlusion query. Shadow rays use their light distance;
//! the others draw `t_max` as ∞, a point before the closest hit (0.2–0.98 t)
//! or after it (1.02–3 t), so that `occluded` is tested both ways.
//!
//! # Tolerances
//!
//! `m = |o| + |p| + |T|` is the magnitude of the coordinates entering a hit's
//! computation: ray origin, hit point and, for mesh instances, the instance's
//! translation (object-space coordinates are bounded by `|p| + |T|` in world
//! units). f32 arithmetic on such coordinates is exact to a few `ε·m`
//! (ε = 1.19e-7): that is the scale of every absolute tolerance below.
//!
//! - **t** is known to `δt = (1e-5·t·|d| + 1e-6·m) / (|d|·|cos θ|)`: a relative
//!   1e-5, plus an absolute term because the two backends move
//!   the ray into the instance's object space each with its own inverse
//!   matrix (glam's, Embree's), so their object-space origins differ by a few
//!   ulps of `|o|`; for a ray starting next to a surface (t ≪ |o|) that is a
//!   large *relative* difference, a property of f32 transforms and not a
//!   wrong hit. Dividing by the incidence cosine is the error propagation of
//!   a plane intersection: a position error `e` across the surface moves the
//!   hit by `e / |cos θ|` along the ray, so grazing hits have uncertain t.
//! - **u, v** agree within 1e-4, or the two hit points (reconstructed from each
//!   backend's u, v) are within `δt·|d|`: the point where a ray pierces a
//!   plane moves along the plane by `e / |cos θ|` for a position error `e`,
//!   like t, and on a small triangle hit by a grazing ray that changes (u, v)
//!   by more than 1e-4. Spheres carry no (u, v).
//! - **boundary**: a hit is on its primitive's boundary when the ray passes
//!   within `1e-6·m` (world units, ≈ 8 ε·m, computed in f64) of a triangle or
//!   quad edge line, or of a sphere's silhouette (a disk: its rim; a
//!   cylinder: its silhouette lines and rims). The distance is measured
//!   perpendicular to the ray, in the plane where ray–triangle tests decide
//!   inside/outside (Woop et al. 2013's edge functions, Embree's as well), so
//!   grazing rays need no special case.
//!
//! # Verdicts
//!
//! Closest hit:
//! - **agreement**: both miss, or both hit the same instance and primitive
//!   with |Δt| ≤ δt and (u, v) as above;
//! - **tie** (allowed, counted): different primitives at the same t
//!   (`|Δt| ≤ δt₁ + δt₂`: a shared edge or vertex, coplanar or intersecting
//!   triangles); or the nearer hit (the only hit, for hit against miss) lies
//!   on its primitive's boundary, where the two triangle tests may round to
//!   different sides and either neighbour, or a miss through an open edge, is
//!   right; or the nearer hit is within δt of an end of the open query
//!   interval (0, t_max), which is as ambiguous as an edge;
//! - **disagreement**: anything else, including the same primitive at
//!   different t and an invalid hit (instance or primitive out of range, t
//!   outside [0, t_max], NaN). A hit against a miss is a tie only through the
//!   boundary or interval rule: a miss is never excused by the hit being
//!   "close to" an edge by a looser measure.
//!
//! Occlusion: the same boolean is an agreement. Otherwise every blocker the
//! "occluded" side can find in (0, t_max) must be ambiguous (boundary or
//! within δt of t_max or 0): the blockers are walked front to back with the
//! closest-hit query (up to 8), and one unambiguous blocker, or none at all
//! (an `occluded` answer no closest-hit query confirms), is a disagreement.
//!
//! # Replay
//!
//! Each disagreement is printed with a replay string `ox,oy,oz,dx,dy,dz,t_max`
//! of seven f32 values in Rust's shortest round-trip notation (`{:e}`, e.g.
//! `-1.2345678e-1`; `inf` for no limit): [`parse_ray`] reads it back to the
//! exact same bits, and [`compare_one`] runs both queries on it with that
//! `t_max`, giving the same verdict for the query that failed.
//!
//! # Layout
//!
//! `rays` generates the seeded rays, `compare` classifies the answers of
//! both accelerators for one ray (tolerances, ties), `replay` writes and
//! reads replay strings, and `report` sums the verdicts and prints them; this
//! module runs the rays in parallel chunks.

use crate::accel::Accel;
use crate::math::rng::{Domain, Rng};
use crate::scene::Scene;
use rayon::prelude::*;

mod compare;
mod rays;
mod replay;
mod report;

pub use compare::{
    compare_closest, compare_occlusion, compare_one, ClosestComparison, Comparison, OcclusionComparison, TieReason,
    Verdict, ABS_SCALE, BOUNDARY_SCALE, REL_T, UV_TOL,
};
pub use rays::RayKind;
pub use replay::{format_ray, parse_ray, ReplayParseError};
pub use report::{CrosscheckReport, Disagreement, KindCounts, Query, MAX_REPORTED};

use compare::describe;
use rays::RayGenerator;

/// Rays per rayon work item.
const CHUNK: u64 = 1024;

/// Settings of a cross-check run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CrosscheckOptions {
    /// Number of rays (split 25% per [`RayKind`]).
    pub rays: u64,
    /// Seed of the ray streams.
    pub seed: u64,
    /// The image (width, height) whose pixels camera rays go through.
    pub image: (u32, u32),
}

impl Default for CrosscheckOptions {
    fn default() -> Self {
        Self {
            rays: 100_000,
            seed: 0,
            image: (640, 480),
        }
    }
}

/// Casts `opts.rays` seeded rays through `a` and `b` and reports how they compare.
pub fn crosscheck(scene: &Scene, a: &dyn Accel, b: &dyn Accel, opts: &CrosscheckOptions) -> CrosscheckReport {
    let generator = RayGenerator::new(scene, opts.seed, opts.image);
    let (a_name, b_name) = (a.stats().name, b.stats().name);
    let chunks = opts.rays.div_ceil(CHUNK);
    let parts: Vec<CrosscheckReport> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut part = CrosscheckReport::empty(String::new(), String::new(), opts.seed);
            for i in c * CHUNK..((c + 1) * CHUNK).min(opts.rays) {
                check_ray(&generator, a, b, i, &mut part);
            }
            part
        })
        .collect();
    let mut report = CrosscheckReport::empty(a_name, b_name, opts.seed);
    for part in parts {
        report.merge(part);
    }
    report
}

/// Generates ray `index`, compares both queries and adds the result to `out`.
fn check_ray(generator: &RayGenerator<'_>, a: &dyn Accel, b: &dyn Accel, index: u64, out: &mut CrosscheckReport) {
    let scene = generator.scene;
    let kind = RayKind::of_ray(index);
    let mut rng = Rng::new(generator.seed, Domain::Analysis, index, kind as u64);
    let (ray, t_max) = generator.ray(kind, &mut rng, a);
    let (ha, hb) = (a.intersect(&ray, t_max), b.intersect(&ray, t_max));
    let closest = compare_closest(scene, &ray, t_max, ha, hb);
    let occlusion_t_max = match (kind, ha.or(hb)) {
        (RayKind::Shadow, _) => t_max,
        (_, None) => f32::INFINITY,
        (_, Some(h)) => match rng.below(3) {
            0 => f32::INFINITY,
            1 => h.t * (0.2 + 0.78 * rng.f32()),
            _ => h.t * (1.02 + 2.0 * rng.f32()),
        },
    };
    let occlusion = compare_occlusion(scene, a, b, &ray, occlusion_t_max);

    let counts = &mut out.per_kind[kind as usize];
    counts.rays += 1;
    counts.hits += (ha.is_some() || hb.is_some()) as u64;
    match &closest.verdict {
        Verdict::Agree => counts.agreements += 1,
        Verdict::Tie(r) => {
            counts.ties += 1;
            out.ties_by_reason[*r as usize] += 1;
        }
        Verdict::Disagree(_) => counts.disagreements += 1,
    }
    match &occlusion.verdict {
        Verdict::Agree => counts.occlusion_agreements += 1,
        Verdict::Tie(r) => {
            counts.occlusion_ties += 1;
            out.ties_by_reason[*r as usize] += 1;
        }
        Verdict::Disagree(_) => counts.occlusion_disagreements += 1,
    }
    if let (Some(rel), Some(used)) = (closest.rel_dt, closest.tolerance_used) {
        out.agreeing_hits += 1;
        out.max_rel_dt = out.max_rel_dt.max(rel as f64);
        out.sum_rel_dt += rel as f64;
        out.max_tolerance_used = out.max_tolerance_used.max(used as f64);
    }
    if let Verdict::Disagree(why) = &closest.verdict {
        if out.disagreements.len() < MAX_REPORTED {
            out.disagreements.push(Disagreement {
                index,
                kind,
                query: Query::Closest,
                ray,
                t_max,
                a: ha,
                b: hb,
                occluded: None,
                reason: format!(
                    "a: {}; b: {}; {why}",
                    describe(scene, ha.as_ref()),
                    describe(scene, hb.as_ref())
                ),
            });
        }
    }
    if let Verdict::Disagree(why) = &occlusion.verdict {
        if out.disagreements.len() < MAX_REPORTED {
            let (oa, ob) = (occlusion.a, occlusion.b);
            out.disagreements.push(Disagreement {
                index,
                kind,
                query: Query::Occluded,
                ray,
                t_max: occlusion_t_max,
                a: if oa { occlusion.blocker } else { None },
                b: if ob { occlusion.blocker } else { None },
                occluded: Some((oa, ob)),
                reason: format!(
                    "a occluded: {oa}; b occluded: {ob}; blocker: {}; {why}",
                    describe(scene, occlusion.blocker.as_ref())
                ),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::brute::BruteForce;
    use crate::accel::{AccelStats, Hit, TriangleTest};
    use crate::math::{Ray, Transform, Vec3, Vec3A};
    use crate::scene::{AreaLight, Camera, Light, Material, Mesh, Object, Quad, Shape, Sphere};
    use std::sync::Arc;

    /// A closed octahedron (instanced twice), a floor quad, a sphere, an area light.
    pub(super) fn small_scene() -> Scene {
        let p = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let f = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        let octa = Arc::new(Mesh::new("octa", p, f, None).unwrap());
        let object = |name: &str, shape| Object {
            name: name.into(),
            shape,
            material: 0,
        };
        let objects = vec![
            object(
                "floor",
                Shape::Quad(
                    Quad::new(
                        Vec3A::new(-4.0, -1.0, 4.0),
                        Vec3A::new(8.0, 0.0, 0.0),
                        Vec3A::new(0.0, 0.0, -8.0),
                    )
                    .unwrap(),
                ),
            ),
            object(
                "ball",
                Shape::Sphere(Sphere {
                    center: Vec3A::new(2.0, 0.0, 0.0),
                    radius: 0.7,
                }),
            ),
            object(
                "octa 0",
                Shape::Mesh {
                    mesh: 0,
                    transform: Transform::from_srt(
                        Vec3::splat(0.8),
                        Vec3::new(10.0, 20.0, 30.0),
                        Vec3::new(-1.5, 0.0, 0.0),
                    )
                    .unwrap(),
                    smooth: false,
                },
            ),
            object(
                "octa 1",
                Shape::Mesh {
                    mesh: 0,
                    transform: Transform::from_srt(
                        Vec3::new(0.5, 1.0, 0.7),
                        Vec3::new(0.0, 45.0, 0.0),
                        Vec3::new(0.0, 0.5, -2.0),
                    )
                    .unwrap(),
                    smooth: true,
                },
            ),
        ];
        Scene {
            media: Default::default(),
            ambient: Vec3A::ZERO,
            water_medium: None,
            camera: Camera::new(Vec3A::new(0.0, 1.0, 6.0), Vec3A::ZERO, Vec3A::Y, 50.0).unwrap(),
            materials: vec![Material::diffuse("grey", Vec3A::splat(0.5))],
            lights: vec![Light::Area(
                AreaLight::new(Vec3A::new(0.0, 3.0, 0.0), Vec3A::X, Vec3A::Z, Vec3A::ONE, 4).unwrap(),
            )],
            meshes: vec![octa],
            objects,
        }
    }

    /// Brute force with one planted bug: for rays whose origin's x bit
    /// pattern has `(bits % modulus) == 0`, the closest hit's t is shifted by
    /// 1% or (on meshes) the primitive index is changed.
    struct Wrong {
        inner: BruteForce,
        modulus: u32,
        shift_t: bool,
    }

    impl Wrong {
        fn planted(&self, ray: &Ray) -> bool {
            ray.origin.x.to_bits().is_multiple_of(self.modulus)
        }
    }

    impl Accel for Wrong {
        fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
            let hit = self.inner.intersect(ray, t_max)?;
            if !self.planted(ray) {
                return Some(hit);
            }
            if self.shift_t {
                Some(Hit { t: hit.t * 0.99, ..hit })
            } else if hit.instance >= 2 {
                Some(Hit {
                    prim: (hit.prim + 3) % 8,
                    ..hit
                })
            } else {
                Some(hit)
            }
        }
        fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
            self.inner.occluded(ray, t_max)
        }
        fn stats(&self) -> AccelStats {
            AccelStats {
                name: "wrong".into(),
                ..Default::default()
            }
        }
    }

    pub(super) fn brute(scene: &Scene) -> BruteForce {
        BruteForce::new(scene, TriangleTest::Watertight)
    }

    #[test]
    fn identical_accelerators_agree_on_every_ray() {
        let scene = small_scene();
        let (a, b) = (brute(&scene), brute(&scene));
        let report = crosscheck(
            &scene,
            &a,
            &b,
            &CrosscheckOptions {
                rays: 8000,
                seed: 3,
                image: (64, 48),
            },
        );
        assert!(report.is_ok(), "{report}");
        let total = report.total();
        assert_eq!(total.rays, 8000);
        assert_eq!(total.agreements, 8000, "{report}");
        assert_eq!(total.occlusion_agreements, 8000, "{report}");
        for kind in RayKind::ALL {
            assert_eq!(report.kind(kind).rays, 2000);
        }
        // Shadow rays mostly reach the light; the others must mostly hit.
        for kind in [RayKind::Camera, RayKind::Bounds, RayKind::Feature] {
            assert!(report.kind(kind).hits > 800, "{kind:?} rays rarely hit: {report}");
        }
        assert!(
            report.kind(RayKind::Shadow).hits > 50,
            "no shadow ray is blocked: {report}"
        );
        assert_eq!(report.max_rel_dt, 0.0);
        assert!(report.agreeing_hits > 3000);
    }

    #[test]
    fn report_is_deterministic_across_thread_counts() {
        let scene = small_scene();
        let (a, b) = (brute(&scene), brute(&scene));
        let wrong = Wrong {
            inner: brute(&scene),
            modulus: 7,
            shift_t: true,
        };
        let opts = CrosscheckOptions {
            rays: 5000,
            seed: 11,
            image: (64, 48),
        };
        let run = |threads: usize, b: &dyn Accel| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| crosscheck(&scene, &a, b, &opts))
        };
        assert_eq!(run(1, &b), run(2, &b));
        assert_eq!(run(1, &wrong), run(3, &wrong));
    }

    #[test]
    fn shifted_t_is_reported_with_a_replayable_ray() {
        let scene = small_scene();
        let good = brute(&scene);
        let wrong = Wrong {
            inner: brute(&scene),
            modulus: 5,
            shift_t: true,
        };
        let report = crosscheck(
            &scene,
            &good,
            &wrong,
            &CrosscheckOptions {
                rays: 4000,
                seed: 1,
                image: (64, 48),
            },
        );
        assert!(!report.is_ok());
        assert!(report.total().disagreements > 100, "{report}");
        assert_eq!(report.disagreements.len(), MAX_REPORTED);
        let text = report.to_string();
        assert!(text.contains("FAILED"), "{text}");
        // Disagreements come in ray order; each printed ray replays to the
        // same verdict.
        assert!(report.disagreements.windows(2).all(|w| w[0].index <= w[1].index));
        for d in &report.disagreements {
            let replay = format_ray(&d.ray, d.t_max);
            assert!(text.contains(&replay), "{replay} not printed");
            let (ray, t_max) = parse_ray(&replay).unwrap();
            assert_eq!((ray, t_max.to_bits()), (d.ray, d.t_max.to_bits()));
            assert_eq!(d.query, Query::Closest);
            let again = compare_one(&scene, &good, &wrong, &ray, t_max);
            assert!(matches!(again.closest.verdict, Verdict::Disagree(_)), "{again:?}");
            assert!(!again.is_ok());
            let text = again.describe(&scene);
            assert!(text.contains(&replay) && text.contains("DISAGREE"), "{text}");
        }
    }

    #[test]
    fn wrong_primitive_is_reported() {
        let scene = small_scene();
        let good = brute(&scene);
        let wrong = Wrong {
            inner: brute(&scene),
            modulus: 3,
            shift_t: false,
        };
        let report = crosscheck(
            &scene,
            &wrong,
            &good,
            &CrosscheckOptions {
                rays: 4000,
                seed: 9,
                image: (64, 48),
            },
        );
        assert!(!report.is_ok(), "{report}");
        let d = &report.disagreements[0];
        let (a, b) = (d.a.unwrap(), d.b.unwrap());
        assert_eq!(a.instance, b.instance);
        assert_ne!(a.prim, b.prim);
    }

    #[test]
    fn occlusion_disagreement_is_reported() {
        struct NeverOccluded(BruteForce);
        impl Accel for NeverOccluded {
            fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
                self.0.intersect(ray, t_max)
            }
            fn occluded(&self, _: &Ray, _: f32) -> bool {
                false
            }
            fn stats(&self) -> AccelStats {
                AccelStats::default()
            }
        }
        let scene = small_scene();
        let good = brute(&scene);
        let wrong = NeverOccluded(brute(&scene));
        let report = crosscheck(
            &scene,
            &good,
            &wrong,
            &CrosscheckOptions {
                rays: 2000,
                seed: 4,
                image: (64, 48),
            },
        );
        let total = report.total();
        assert_eq!(total.disagreements, 0, "{report}");
        assert!(total.occlusion_disagreements > 200, "{report}");
        assert!(report.disagreements.iter().all(|d| d.query == Query::Occluded));
        assert_eq!(report.disagreements[0].occluded, Some((true, false)));
    }
}
