//! Case 6: grazing rays on spheres, checked against the analytic answer in
//! double precision.
//!
//! Four spheres (radius 1 at the origin, 0.01 off-centre, 20 at 100, 1 at
//! 1000 on each axis), each alone in its scene. A ray passes at distance
//! `h = r(1 + δ)` from the centre: exactly tangent (`δ = 0`, one ray in
//! five), or `|δ|` log-uniform in 1e-8 … 1e-2 with either sign, from an
//! origin 1.5–10 radii back along the ray.
//!
//! The reference is computed in f64 from the f32 ray and sphere actually
//! used (after rounding): the distance `h₆₄` of the centre to the ray line,
//! hit iff `h₆₄ < r`, entry `t₆₄ = (c−o)·d/|d|² − √(r² − h₆₄²)/|d|`.
//!
//! **Tolerance.** The f32 test (`Sphere::intersect`) computes the
//! perpendicular offset from `f = o − c`; its rounding moves `h` by a few
//! `ε|f|`. Rays with `|h₆₄ − r| ≤ band = 1e-6·r + 8ε|o − c|` (ε = 2⁻²³) may
//! hit or miss; outside the band the answer must match. A hit's `t` must be
//! within `√(2r·band) + 1e-5·t₆₄` of `t₆₄` (the square root is how an error
//! in `h` becomes an error in `t` at tangency; for rays in the band the
//! reference `t` is the tangent point's).
//!
//! **Failure:** wrong hit/miss outside the band, `t` out of tolerance, a hit
//! on nothing but the sphere's own scene impossible (wrong object), a NaN or
//! non-positive `t`.

use super::{guarded, log_uniform, random_unit, scene_of, share, tally, trial_rng, unavailable_row};
use super::{Backend, Role, StressOptions, StressRow, Tally};
use crate::math::{Ray, Vec3A};
use crate::scene::{Shape, Sphere};
use glam::DVec3;

const CASE: u64 = 6;

/// The spheres of the case.
pub fn spheres() -> [Sphere; 4] {
    [
        Sphere {
            center: Vec3A::ZERO,
            radius: 1.0,
        },
        Sphere {
            center: Vec3A::new(3.0, -2.0, 5.0),
            radius: 0.01,
        },
        Sphere {
            center: Vec3A::new(100.0, 50.0, -30.0),
            radius: 20.0,
        },
        Sphere {
            center: Vec3A::splat(1000.0),
            radius: 1.0,
        },
    ]
}

/// Verdict of one grazing ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// Agrees with the reference.
    Agrees,
    /// Within the band: either answer allowed.
    InBand,
    /// Hit where the reference misses, or the reverse.
    WrongHitMiss,
    /// Hit with `t` out of tolerance, NaN or ≤ 0.
    BadT,
}

/// A grazing ray at sphere `s` for trial `i`.
pub fn grazing_ray(s: &Sphere, seed: u64, i: u64) -> Ray {
    let mut rng = trial_rng(seed, CASE, i);
    let d = random_unit(&mut rng);
    let e = d.any_orthonormal_vector();
    let e = {
        // A random perpendicular: rotate e about d.
        let f = d.cross(e);
        let a = std::f32::consts::TAU * rng.f32();
        e * a.cos() + f * a.sin()
    };
    let delta = if rng.below(5) == 0 {
        0.0
    } else {
        let m = log_uniform(&mut rng, -8.0, -2.0);
        if rng.f32() < 0.5 {
            -m
        } else {
            m
        }
    };
    let h = s.radius * (1.0 + delta);
    let back = s.radius * (1.5 + 8.5 * rng.f32());
    Ray::new(s.center + e * h - d * back, d)
}

/// Judges `t` (the accelerator's closest hit on the sphere) against the f64 reference.
pub fn judge(s: &Sphere, ray: &Ray, t: Option<f32>) -> Verdict {
    let o = ray.origin.as_dvec3();
    let d = ray.dir.as_dvec3();
    let c = s.center.as_dvec3();
    let r = s.radius as f64;
    let f = c - o;
    let dd = d.length_squared();
    let t_mid = f.dot(d) / dd;
    let perp: DVec3 = f - d * t_mid;
    let h = perp.length();
    let eps = f32::EPSILON as f64;
    let band = 1e-6 * r + 8.0 * eps * f.length();
    let t_ref = if h < r {
        t_mid - (r * r - h * h).sqrt() / dd.sqrt()
    } else {
        t_mid
    };
    let in_band = (h - r).abs() <= band;
    match t {
        Some(t) if t.is_nan() || t <= 0.0 || t.is_infinite() => Verdict::BadT,
        Some(t) => {
            if !in_band && h > r {
                return Verdict::WrongHitMiss;
            }
            let tol = (2.0 * r * band).sqrt() / dd.sqrt() + 1e-5 * t_ref.abs();
            if (t as f64 - t_ref).abs() > tol {
                Verdict::BadT
            } else if in_band {
                Verdict::InBand
            } else {
                Verdict::Agrees
            }
        }
        None if in_band => Verdict::InBand,
        None if h < r => Verdict::WrongHitMiss,
        None => Verdict::Agrees,
    }
}

/// The rows of case 6 (`extra`: `[in band, wrong hit/miss, bad t, wrong object]`).
pub fn run(options: &StressOptions) -> Vec<StressRow> {
    let case = "6 grazing rays on spheres";
    let spheres = spheres();
    let scenes: Vec<_> = spheres
        .iter()
        .map(|s| scene_of(vec![], vec![(Shape::Sphere(*s), 0)], vec![]))
        .collect();
    let mut rows = Vec::new();
    for backend in Backend::defaults() {
        rows.extend(guarded(case, backend.name(), Role::Default, || {
            let mut total = Tally::default();
            for (k, (s, scene)) in spheres.iter().zip(&scenes).enumerate() {
                let accel = match backend.build(scene) {
                    Ok(a) => a,
                    Err(e) => return vec![unavailable_row(case, backend, Role::Default, &e.to_string())],
                };
                let per = options.rays.div_ceil(4);
                total = total
                    + tally(per, |i| {
                        let index = k as u64 * per + i;
                        let ray = grazing_ray(s, options.seed, index);
                        let hit = accel.intersect(&ray, f32::INFINITY);
                        let mut extra = [0u64; 6];
                        if hit.is_some_and(|h| h.instance != 0) {
                            extra[3] += 1;
                        }
                        match judge(s, &ray, hit.map(|h| h.t)) {
                            Verdict::Agrees => {}
                            Verdict::InBand => extra[0] += 1,
                            Verdict::WrongHitMiss => extra[1] += 1,
                            Verdict::BadT => extra[2] += 1,
                        }
                        Tally {
                            trials: 1,
                            failures: u64::from(extra[1] + extra[2] + extra[3] > 0),
                            extra,
                        }
                    });
            }
            vec![
                StressRow::new(case, backend.name(), Role::Default, total.trials, total.failures).note(format!(
                    "{} — wrong hit/miss {}, bad t {}, wrong object {}; {} rays within the band (either answer)",
                    share(total.failures, total.trials),
                    total.extra[1],
                    total.extra[2],
                    total.extra[3],
                    total.extra[0]
                )),
            ]
        }));
    }
    for backend in [Backend::KdWatertight, Backend::Embree] {
        if !backend.available() {
            rows.push(unavailable_row(case, backend, Role::Default, "not compiled in"));
        }
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn judge_knows_clear_hits_and_misses() {
        let s = Sphere {
            center: Vec3A::ZERO,
            radius: 1.0,
        };
        let hit = Ray::new(Vec3A::new(0.5, 0.0, -5.0), Vec3A::Z);
        let t = s.intersect(&hit, f32::INFINITY);
        assert_eq!(judge(&s, &hit, t), Verdict::Agrees);
        assert_eq!(judge(&s, &hit, None), Verdict::WrongHitMiss);
        assert_eq!(judge(&s, &hit, Some(4.0)), Verdict::BadT);
        let miss = Ray::new(Vec3A::new(1.01, 0.0, -5.0), Vec3A::Z);
        assert_eq!(judge(&s, &miss, None), Verdict::Agrees);
        assert_eq!(judge(&s, &miss, Some(5.0)), Verdict::WrongHitMiss);
        let tangent = Ray::new(Vec3A::new(1.0, 0.0, -5.0), Vec3A::Z);
        assert_eq!(judge(&s, &tangent, None), Verdict::InBand);
    }

    #[test]
    fn grazing_rays_pass_near_the_silhouette() {
        let s = spheres()[2];
        for i in 0..100 {
            let r = grazing_ray(&s, 0, i);
            let f = (s.center - r.origin).as_dvec3();
            let d = r.dir.as_dvec3();
            let h = (f - d * f.dot(d) / d.length_squared()).length();
            assert!((h / s.radius as f64 - 1.0).abs() < 1.1e-2, "{h}");
        }
    }
}
