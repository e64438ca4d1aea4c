//! The classification of one ray's answers: the tolerances on t, (u, v) and
//! the boundary distance, and the verdicts (agreement, tie, disagreement) of
//! the closest-hit and occlusion queries.

use super::replay::format_ray;
use crate::accel::{Accel, Hit};
use crate::math::{Ray, Vec3A};
use crate::scene::{Scene, Shape};
use std::fmt;

/// Relative tolerance on t (t within a relative 1e-5).
pub const REL_T: f32 = 1e-5;
/// Absolute tolerance per unit of coordinate magnitude `m` (≈ 8 f32 ulps).
pub const ABS_SCALE: f32 = 1e-6;
/// Tolerance on barycentric / quad coordinates of the same primitive.
pub const UV_TOL: f32 = 1e-4;
/// Distance from a primitive's boundary, per unit of `m`, within which a hit is on it.
pub const BOUNDARY_SCALE: f64 = 1e-6;
/// Ambiguous blockers walked through before an occlusion tie is refused.
const MAX_BLOCKERS: usize = 8;

/// Why two different answers are both accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TieReason {
    /// Different primitives at the same t within tolerance.
    SameDistance = 0,
    /// The deciding hit lies on its primitive's boundary.
    Boundary = 1,
    /// The deciding hit lies at an end of the query interval (0, t_max).
    IntervalEnd = 2,
}

impl TieReason {
    pub(super) fn name(self) -> &'static str {
        match self {
            TieReason::SameDistance => "same distance",
            TieReason::Boundary => "on a boundary",
            TieReason::IntervalEnd => "at an interval end",
        }
    }
}

/// The classification of one query answered by both accelerators.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Same answer within tolerance.
    Agree,
    /// Different answers, both right within floating-point precision.
    Tie(TieReason),
    /// A real disagreement, with the reason.
    Disagree(String),
}

/// Closest-hit answers of both accelerators for one ray.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosestComparison {
    /// Upper end of the query interval.
    pub t_max: f32,
    /// Accelerator `a`'s hit.
    pub a: Option<Hit>,
    /// Accelerator `b`'s hit.
    pub b: Option<Hit>,
    /// Classification.
    pub verdict: Verdict,
    /// |Δt| / t when both agree on a hit.
    pub rel_dt: Option<f32>,
    /// |Δt| / δt (the share of the tolerance used) when both agree on a hit.
    pub tolerance_used: Option<f32>,
}

/// Occlusion answers of both accelerators for one ray.
#[derive(Clone, Debug, PartialEq)]
pub struct OcclusionComparison {
    /// Upper end of the query interval.
    pub t_max: f32,
    /// Accelerator `a`'s answer.
    pub a: bool,
    /// Accelerator `b`'s answer.
    pub b: bool,
    /// When the answers differ: the nearest blocker found by the side that
    /// reported occlusion (or by the other side's closest-hit query).
    pub blocker: Option<Hit>,
    /// Classification.
    pub verdict: Verdict,
}

/// Both queries on one ray ([`compare_one`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// The ray.
    pub ray: Ray,
    /// Closest hit.
    pub closest: ClosestComparison,
    /// Any hit.
    pub occlusion: OcclusionComparison,
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Verdict::Agree => write!(f, "agree"),
            Verdict::Tie(reason) => write!(f, "tie ({})", reason.name()),
            Verdict::Disagree(why) => write!(f, "DISAGREE: {why}"),
        }
    }
}

impl Comparison {
    /// Both queries in words, hits named after the scene's objects, numbers
    /// at full precision (what `caustic crosscheck --replay` prints).
    pub fn describe(&self, scene: &Scene) -> String {
        let c = &self.closest;
        let o = &self.occlusion;
        format!(
            "ray \"{}\"\nclosest: a: {}; b: {}\n  {}\noccluded: a: {}; b: {}{}\n  {}",
            format_ray(&self.ray, c.t_max),
            describe(scene, c.a.as_ref()),
            describe(scene, c.b.as_ref()),
            c.verdict,
            o.a,
            o.b,
            o.blocker
                .map(|h| format!("; blocker: {}", describe(scene, Some(&h))))
                .unwrap_or_default(),
            o.verdict
        )
    }

    /// True when neither query disagrees.
    pub fn is_ok(&self) -> bool {
        !matches!(self.closest.verdict, Verdict::Disagree(_)) && !matches!(self.occlusion.verdict, Verdict::Disagree(_))
    }
}

/// Runs both queries of both accelerators on one ray with the same `t_max`
/// and classifies the answers (the replay of a printed disagreement).
pub fn compare_one(scene: &Scene, a: &dyn Accel, b: &dyn Accel, ray: &Ray, t_max: f32) -> Comparison {
    let closest = compare_closest(scene, ray, t_max, a.intersect(ray, t_max), b.intersect(ray, t_max));
    let occlusion = compare_occlusion(scene, a, b, ray, t_max);
    Comparison {
        ray: *ray,
        closest,
        occlusion,
    }
}

/// A hit in words, with full-precision numbers.
pub(super) fn describe(scene: &Scene, hit: Option<&Hit>) -> String {
    match hit {
        None => "miss".into(),
        Some(h) => {
            let name = scene
                .objects
                .get(h.instance as usize)
                .map(|o| o.name.as_str())
                .unwrap_or("<out of range>");
            format!(
                "object {} \"{name}\" prim {} t={:e} u={:e} v={:e}",
                h.instance, h.prim, h.t, h.u, h.v
            )
        }
    }
}

/// Why `hit` cannot be a valid answer to a query with `t_max`, if it cannot.
pub(super) fn invalid_hit(scene: &Scene, ray: &Ray, t_max: f32, hit: &Hit) -> Option<String> {
    let Some(object) = scene.objects.get(hit.instance as usize) else {
        return Some(format!("instance {} out of range", hit.instance));
    };
    let prims = match &object.shape {
        Shape::Mesh { mesh, .. } => scene.meshes[*mesh as usize].triangles.len(),
        Shape::Sphere(_) | Shape::Quad(_) | Shape::Disk(_) | Shape::Cylinder(_) => 1,
    };
    if hit.prim as usize >= prims {
        return Some(format!("primitive {} out of range ({prims})", hit.prim));
    }
    // Both ends are accepted: Embree's interval is closed, the contract's
    // open; an end hit is then an interval-end tie, not an invalid answer.
    let in_query = hit.t >= 0.0 && hit.t <= t_max; // false for NaN too
    if !in_query || !hit.u.is_finite() || !hit.v.is_finite() {
        return Some(format!(
            "t = {:e}, u = {:e}, v = {:e} outside the query",
            hit.t, hit.u, hit.v
        ));
    }
    // The hit must be where it says: the point of the primitive at (u, v)
    // (the sphere's surface) within δt of the ray's point at t. A right t
    // with a wrong primitive or wrong (u, v) fails here.
    let g = hit_geometry(scene, ray, hit);
    let along = ray.at(hit.t);
    let off = match &object.shape {
        Shape::Sphere(s) => ((along - s.center).length() - s.radius).abs(),
        Shape::Cylinder(c) => {
            let rel = along - c.base;
            let radial = rel - c.axis * rel.dot(c.axis);
            (radial.length() - c.radius).abs()
        }
        _ => (g.p - along).length(),
    };
    // Plus the rounding bound of the reconstructed point itself, which scales
    // with the primitive's own coordinates (a quad corner 7 units away), not
    // with the ray's: `Scene::surface_interaction`'s `p_error`.
    let p_error = scene.surface_interaction(ray, hit).p_error.length();
    let tol = t_tolerance(ray, hit.t, &g) * ray.dir.length() + 2.0 * p_error;
    let consistent = off <= tol; // false for NaN too
    if !consistent {
        return Some(format!(
            "its point at (u, v) is {off:e} from the ray's point at t (tolerance {tol:e})"
        ));
    }
    None
}

/// What the tolerances need to know about a hit.
struct HitGeometry {
    /// World hit point, reconstructed from (u, v) (from t for spheres).
    p: Vec3A,
    /// |cos θ| between the ray and the geometric normal.
    cos: f32,
    /// `m = |o| + |p| + |T|` (see the `crosscheck` module documentation).
    magnitude: f32,
}

fn hit_geometry(scene: &Scene, ray: &Ray, hit: &Hit) -> HitGeometry {
    let si = scene.surface_interaction(ray, hit);
    let translation = match &scene.objects[hit.instance as usize].shape {
        Shape::Mesh { transform, .. } => transform.to_world.translation.length(),
        _ => 0.0,
    };
    let dir_len = ray.dir.length();
    HitGeometry {
        p: si.p,
        cos: (ray.dir.dot(si.ng) / dir_len).abs(),
        magnitude: ray.origin.length() + si.p.length() + translation,
    }
}

/// δt of the `crosscheck` module documentation for a hit at `t`.
fn t_tolerance(ray: &Ray, t: f32, g: &HitGeometry) -> f32 {
    let dir_len = ray.dir.length();
    // cos = 0 (the ray in the plane) gives δt = ∞: t is then undetermined.
    (REL_T * t * dir_len + ABS_SCALE * g.magnitude) / (dir_len * g.cos)
}

/// Distance between two lines `o + s·d` and `a + w·e`, perpendicular to `d`.
fn line_distance(o: glam::DVec3, d: glam::DVec3, a: glam::DVec3, e: glam::DVec3) -> f64 {
    let n = d.cross(e);
    let n2 = n.length_squared();
    if n2 > 1e-18 * d.length_squared() * e.length_squared() {
        (a - o).dot(n).abs() / n2.sqrt()
    } else {
        // Parallel (or a degenerate edge): distance of the point `a` from the ray line.
        (a - o).cross(d).length() / d.length()
    }
}

/// World distance, perpendicular to the ray, between the ray and the
/// boundary of the hit primitive (edges; a sphere's silhouette).
fn boundary_distance(scene: &Scene, ray: &Ray, hit: &Hit) -> f64 {
    let o = ray.origin.as_dvec3();
    let d = ray.dir.as_dvec3();
    let edges = |corners: &[glam::DVec3]| {
        (0..corners.len())
            .map(|i| {
                let a = corners[i];
                let b = corners[(i + 1) % corners.len()];
                line_distance(o, d, a, b - a)
            })
            .fold(f64::INFINITY, f64::min)
    };
    match &scene.objects[hit.instance as usize].shape {
        Shape::Mesh { mesh, transform, .. } => {
            let c = scene.meshes[*mesh as usize]
                .corners(hit.prim as usize)
                .map(|p| transform.point(p).as_dvec3());
            edges(&c)
        }
        Shape::Quad(q) => {
            let c0 = q.corner.as_dvec3();
            let (u, v) = (q.u.as_dvec3(), q.v.as_dvec3());
            edges(&[c0, c0 + u, c0 + u + v, c0 + v])
        }
        Shape::Sphere(s) => {
            let f = s.center.as_dvec3() - o;
            let perp = f.cross(d).length() / d.length();
            (perp - s.radius as f64).abs()
        }
        Shape::Disk(disk) => {
            // The rim: in the plane, |1 − ρ| times the radius along the
            // hit's direction from the centre.
            let (x, y) = (hit.u as f64, hit.v as f64);
            let rho = (x * x + y * y).sqrt();
            let (a, b) = (disk.a.as_dvec3(), disk.b.as_dvec3());
            let along = if rho > 0.0 { (a * x + b * y) / rho } else { a };
            (1.0 - rho).abs() * along.length()
        }
        Shape::Cylinder(c) => {
            // The silhouette (the ray's distance from the axis against the
            // radius, as the sphere's) and the two rims.
            let axis = c.axis.as_dvec3();
            let silhouette = (line_distance(o, d, c.base.as_dvec3(), axis) - c.radius as f64).abs();
            let z = (ray.at(hit.t) - c.base).dot(c.axis) as f64;
            silhouette.min(z.abs()).min((c.length as f64 - z).abs())
        }
    }
}

/// Why a lone or nearer hit is ambiguous, if it is.
fn ambiguity(scene: &Scene, ray: &Ray, t_max: f32, hit: &Hit) -> Option<TieReason> {
    let g = hit_geometry(scene, ray, hit);
    let dt = t_tolerance(ray, hit.t, &g);
    if hit.t <= dt || (t_max.is_finite() && t_max - hit.t <= dt) {
        return Some(TieReason::IntervalEnd);
    }
    if boundary_distance(scene, ray, hit) <= BOUNDARY_SCALE * g.magnitude as f64 {
        return Some(TieReason::Boundary);
    }
    None
}

/// Classifies the closest hits `a` and `b` of `ray` on `(0, t_max)`.
pub fn compare_closest(scene: &Scene, ray: &Ray, t_max: f32, a: Option<Hit>, b: Option<Hit>) -> ClosestComparison {
    let (verdict, agreement) = closest_verdict(scene, ray, t_max, a, b);
    ClosestComparison {
        t_max,
        a,
        b,
        verdict,
        rel_dt: agreement.map(|(rel, _)| rel),
        tolerance_used: agreement.map(|(_, used)| used),
    }
}

/// The verdict, and for agreeing hits (|Δt|/t, |Δt|/δt).
fn closest_verdict(
    scene: &Scene,
    ray: &Ray,
    t_max: f32,
    a: Option<Hit>,
    b: Option<Hit>,
) -> (Verdict, Option<(f32, f32)>) {
    for (name, h) in [("a", &a), ("b", &b)] {
        if let Some(why) = h.as_ref().and_then(|h| invalid_hit(scene, ray, t_max, h)) {
            return (
                Verdict::Disagree(format!("{name} returned an invalid hit: {why}")),
                None,
            );
        }
    }
    match (a, b) {
        (None, None) => (Verdict::Agree, None),
        (Some(x), Some(y)) if (x.instance, x.prim) == (y.instance, y.prim) => {
            let (gx, gy) = (hit_geometry(scene, ray, &x), hit_geometry(scene, ray, &y));
            let dir_len = ray.dir.length();
            let t = x.t.max(y.t);
            let magnitude = gx.magnitude.max(gy.magnitude);
            // The better-conditioned of the two normals: the stricter δt.
            let cos = gx.cos.max(gy.cos);
            let dist_tol = REL_T * t * dir_len + ABS_SCALE * magnitude;
            let t_tol = dist_tol / (dir_len * cos);
            let dt = (x.t - y.t).abs();
            let t_ok = dt <= t_tol;
            let uv_ok = matches!(
                scene.objects[x.instance as usize].shape,
                Shape::Sphere(_) | Shape::Cylinder(_)
            ) || ((x.u - y.u).abs() <= UV_TOL && (x.v - y.v).abs() <= UV_TOL)
                || (gx.p - gy.p).length() <= t_tol * dir_len;
            if t_ok && uv_ok {
                let rel = if t > 0.0 { dt / t } else { 0.0 };
                let used = if t_tol > 0.0 { dt / t_tol } else { 0.0 };
                return (Verdict::Agree, Some((rel, used)));
            }
            let near = if x.t <= y.t { x } else { y };
            if ambiguity(scene, ray, t_max, &near) == Some(TieReason::IntervalEnd) {
                return (Verdict::Tie(TieReason::IntervalEnd), None);
            }
            (
                Verdict::Disagree(format!(
                    "same primitive, |Δt| = {dt:e} (tolerance {t_tol:e}), |Δu| = {:e}, |Δv| = {:e}, |Δp| = {:e}",
                    (x.u - y.u).abs(),
                    (x.v - y.v).abs(),
                    (gx.p - gy.p).length()
                )),
                None,
            )
        }
        (Some(x), Some(y)) => {
            let (near, far, near_name) = if x.t <= y.t { (x, y, "a") } else { (y, x, "b") };
            let (gn, gf) = (hit_geometry(scene, ray, &near), hit_geometry(scene, ray, &far));
            let same_t_tol = t_tolerance(ray, near.t, &gn) + t_tolerance(ray, far.t, &gf);
            if far.t - near.t <= same_t_tol {
                return (Verdict::Tie(TieReason::SameDistance), None);
            }
            if let Some(reason) = ambiguity(scene, ray, t_max, &near) {
                return (Verdict::Tie(reason), None);
            }
            (
                Verdict::Disagree(format!(
                    "different primitives: {near_name}'s nearer hit is {:e} in front and {:e} from its boundary \
                     (tolerance {:e})",
                    far.t - near.t,
                    boundary_distance(scene, ray, &near),
                    BOUNDARY_SCALE * gn.magnitude as f64
                )),
                None,
            )
        }
        (Some(only), None) | (None, Some(only)) => {
            let who = if a.is_some() { "a" } else { "b" };
            if let Some(reason) = ambiguity(scene, ray, t_max, &only) {
                return (Verdict::Tie(reason), None);
            }
            let g = hit_geometry(scene, ray, &only);
            (
                Verdict::Disagree(format!(
                    "only {who} hits, {:e} from the primitive's boundary (tolerance {:e})",
                    boundary_distance(scene, ray, &only),
                    BOUNDARY_SCALE * g.magnitude as f64
                )),
                None,
            )
        }
    }
}

/// Classifies the `occluded` answers of `a` and `b` for `ray` on `(0, t_max)`.
pub fn compare_occlusion(scene: &Scene, a: &dyn Accel, b: &dyn Accel, ray: &Ray, t_max: f32) -> OcclusionComparison {
    let (oa, ob) = (a.occluded(ray, t_max), b.occluded(ray, t_max));
    let mut result = OcclusionComparison {
        t_max,
        a: oa,
        b: ob,
        blocker: None,
        verdict: Verdict::Agree,
    };
    if oa == ob {
        return result;
    }
    let (yes, no) = if oa { (a, b) } else { (b, a) };
    let yes_name = if oa { "a" } else { "b" };
    // The side that reported no occlusion claims there is nothing in
    // (0, t_max): every blocker the other side finds must be ambiguous.
    let Some(first) = yes.intersect(ray, t_max).or_else(|| no.intersect(ray, t_max)) else {
        result.verdict = Verdict::Disagree(format!(
            "{yes_name} reports occlusion but no closest-hit query finds anything below t_max"
        ));
        return result;
    };
    result.blocker = Some(first);
    if let Some(why) = invalid_hit(scene, ray, t_max, &first) {
        result.verdict = Verdict::Disagree(format!("invalid blocker: {why}"));
        return result;
    }
    let mut blocker = first;
    let mut first_reason = None;
    for _ in 0..MAX_BLOCKERS {
        match ambiguity(scene, ray, t_max, &blocker) {
            None => {
                result.verdict = Verdict::Disagree(format!(
                    "blocker {} at t = {:e} is neither on its boundary nor at an interval end",
                    describe(scene, Some(&blocker)),
                    blocker.t
                ));
                return result;
            }
            Some(reason) => {
                first_reason.get_or_insert(reason);
            }
        }
        // Look for a further blocker past this one (and past anything within
        // its tolerance, which would be equally ambiguous).
        let g = hit_geometry(scene, ray, &blocker);
        let t_skip = blocker.t + t_tolerance(ray, blocker.t, &g).min(t_max);
        let room_left = t_skip < t_max;
        if !room_left {
            result.verdict = Verdict::Tie(first_reason.unwrap_or(TieReason::Boundary));
            return result;
        }
        let rest = Ray::new(ray.at(t_skip), ray.dir);
        match yes.intersect(&rest, t_max - t_skip) {
            None => {
                result.verdict = Verdict::Tie(first_reason.unwrap_or(TieReason::Boundary));
                return result;
            }
            Some(h) => {
                blocker = Hit { t: h.t + t_skip, ..h };
                if invalid_hit(scene, ray, t_max, &blocker).is_some() {
                    result.verdict =
                        Verdict::Disagree(format!("invalid further blocker {}", describe(scene, Some(&blocker))));
                    return result;
                }
            }
        }
    }
    result.verdict = Verdict::Disagree(format!(
        "more than {MAX_BLOCKERS} ambiguous blockers before t_max: cannot classify"
    ));
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::crosscheck::tests::{brute, small_scene};

    #[test]
    fn ties_are_recognised() {
        let scene = small_scene();
        // The octahedron "octa 0" vertex +x, seen straight on: every face
        // around the vertex is hit at the same t.
        let Shape::Mesh { transform, .. } = &scene.objects[2].shape else {
            unreachable!()
        };
        let vertex = transform.point(Vec3A::X);
        // Looking at the vertex nearly head-on, so that the ray enters the
        // solid there (a vertex seen from the side would be on the silhouette).
        let centre = transform.point(Vec3A::ZERO);
        let origin = centre + (vertex - centre) * 6.0 + Vec3A::new(0.0, 0.2, 0.1);
        let ray = Ray::new(origin, (vertex - origin).normalize());
        let hit = brute(&scene).intersect(&ray, f32::INFINITY).unwrap();
        assert_eq!(hit.instance, 2);
        // Another face around vertex 0, hit at that vertex: its (u, v) put
        // all the weight on the corner holding vertex 0.
        let tris = &scene.meshes[0].triangles;
        let prim = (0..8)
            .find(|&p| p != hit.prim && tris[p as usize].contains(&0))
            .unwrap();
        let (u, v) = match tris[prim as usize].iter().position(|&i| i == 0) {
            Some(0) => (0.0, 0.0),
            Some(1) => (1.0, 0.0),
            _ => (0.0, 1.0),
        };
        let other = Hit { prim, u, v, ..hit };
        let c = compare_closest(&scene, &ray, f32::INFINITY, Some(hit), Some(other));
        assert_eq!(c.verdict, Verdict::Tie(TieReason::SameDistance));
        // Hit against miss at the vertex: a boundary tie.
        let c = compare_closest(&scene, &ray, f32::INFINITY, Some(hit), None);
        assert_eq!(c.verdict, Verdict::Tie(TieReason::Boundary));
        // Hit against miss in the middle of the floor: a disagreement.
        let down = Ray::new(Vec3A::new(0.3, 2.0, 1.0), -Vec3A::Y);
        let floor = brute(&scene).intersect(&down, f32::INFINITY).unwrap();
        assert_eq!(floor.instance, 0);
        let c = compare_closest(&scene, &down, f32::INFINITY, Some(floor), None);
        assert!(matches!(c.verdict, Verdict::Disagree(_)), "{c:?}");
        // ... unless the query ends at the floor (t_max = its distance).
        let c = compare_closest(&scene, &down, floor.t, Some(floor), None);
        assert_eq!(c.verdict, Verdict::Tie(TieReason::IntervalEnd));
        // An out-of-range instance is a disagreement, not a panic.
        let bad = Hit { instance: 99, ..floor };
        let c = compare_closest(&scene, &down, f32::INFINITY, Some(floor), Some(bad));
        assert!(
            matches!(c.verdict, Verdict::Disagree(ref m) if m.contains("invalid")),
            "{c:?}"
        );
    }
}
