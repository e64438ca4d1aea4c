//! The numerical stress cases (`caustic stress`) at test size: every row of
//! a default configuration must show zero failures, and the checks must be
//! able to fail (a leaky accelerator and a NaN-producing scene are caught).

use caustic::accel::{Accel, AccelStats, Hit};
use caustic::analysis::stress::{self, Backend, Role, StressOptions, StressRow};
use caustic::geometry::generate::icosphere;
use caustic::math::Ray;

fn options() -> StressOptions {
    StressOptions {
        seed: 7,
        rays: 6_000,
        // The smallest dragon, when present locally (never fetched).
        dragon: Some("dragon_vrip_res4.ply.gz".into()),
        render_width: 32,
        progress: false,
    }
}

fn assert_default_rows_pass(rows: &[StressRow]) {
    assert!(!rows.is_empty());
    for r in rows {
        eprintln!(
            "{} | {} | {:?} | {} | {} | {}",
            r.case, r.config, r.role, r.trials, r.failures, r.note
        );
    }
    for r in rows.iter().filter(|r| r.role == Role::Default) {
        // Embree's rows are empty only in a build without it.
        let not_built = !cfg!(feature = "embree") && r.config.starts_with("embree") && r.note == "not compiled in";
        assert!(r.trials > 0 || not_built, "default row without trials: {r:?}");
        assert_eq!(r.failures, 0, "default configuration failed: {r:?}");
    }
}

#[test]
fn case1_watertight_default_configs_never_miss() {
    assert_default_rows_pass(&stress::watertight::run(&options()));
}

#[test]
fn case2_no_false_rehits_at_scales_1e_minus_4_to_1e5() {
    assert_default_rows_pass(&stress::spawn::run_scales(&options()));
}

#[test]
fn case3_translated_scene_no_rehits_no_leaks() {
    assert_default_rows_pass(&stress::spawn::run_translated(&options()));
}

#[test]
fn case4_kdtree_agrees_with_brute_force_on_split_plane_rays() {
    assert_default_rows_pass(&stress::parallel::run(&options()));
}

#[test]
fn case5_degenerate_and_needle_triangles() {
    assert_default_rows_pass(&stress::degenerate::run(&options()));
}

#[test]
fn case6_grazing_rays_match_the_f64_answer() {
    assert_default_rows_pass(&stress::grazing::run(&options()));
}

#[test]
fn case7_tir_chains_and_no_nan_on_the_film() {
    assert_default_rows_pass(&stress::tir::run(&options()));
}

/// Forwards to an accelerator but loses every hit on one triangle: the
/// watertightness check must see the hole.
struct Leaky {
    inner: Box<dyn Accel>,
    hole: u32,
}

impl Accel for Leaky {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.inner.intersect(ray, t_max).filter(|h| h.prim != self.hole)
    }
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.intersect(ray, t_max).is_some()
    }
    fn stats(&self) -> AccelStats {
        self.inner.stats()
    }
}

#[test]
fn the_watertight_check_catches_a_hole() {
    use caustic::analysis::stress::watertight::{aimed_rays, count_misses, Topology};
    let mesh = icosphere(1);
    let topo = Topology::new(&mesh);
    let rays = aimed_rays(&mesh, &topo, 3_000, 1);
    let scene = stress::scene_of(
        vec![std::sync::Arc::new(mesh.clone())],
        vec![(
            caustic::scene::Shape::Mesh {
                mesh: 0,
                transform: caustic::math::Transform::IDENTITY,
                smooth: false,
            },
            0,
        )],
        vec![],
    );
    let good = Backend::KdWatertight.build(&scene).unwrap();
    assert_eq!(count_misses(good.as_ref(), &rays, 2.0).failures, 0);
    let leaky = Leaky {
        inner: Backend::KdWatertight.build(&scene).unwrap(),
        hole: 3,
    };
    // Rays at the hole's 3 edges and 3 vertices miss (80 triangles, 3 000 rays).
    assert!(count_misses(&leaky, &rays, 2.0).failures > 20);
}

#[test]
fn nan_samples_are_dropped_and_overflow_is_not_put_on_the_film() {
    let (bad, dropped, samples) = stress::tir::render_injected("area light radiance NaN", 24).unwrap();
    assert_eq!(bad, 0, "non-finite pixels reached the film");
    assert!(dropped > 0 && dropped <= samples, "{dropped} of {samples}");
    // Finite samples near f32::MAX: their f32 sum overflowed; each sample is now clamped
    // at render::SAMPLE_RADIANCE_LIMIT, so the sum stays finite.
    let (bad, _, _) = stress::tir::render_injected("area light radiance f32::MAX", 24).unwrap();
    assert_eq!(bad, 0, "an overflowing pixel sum reached the film");
}
