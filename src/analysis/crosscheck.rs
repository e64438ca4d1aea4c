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
//!   from the origin (the sphere's boundary). Origins: half on the outer
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
//!   1e-5 (DESIGN.md), plus an absolute term because the two backends move
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
//!   quad edge line, or of a sphere's silhouette. The distance is measured
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

use crate::accel::{Accel, Hit};
use crate::math::rng::{Domain, Rng};
use crate::math::sampling::uniform_sphere;
use crate::math::{offset_ray_origin, Aabb, Frame, Ray, Vec2, Vec3A};
use crate::scene::{Light, Scene, Shape};
use rayon::prelude::*;
use std::fmt;
use thiserror::Error;

/// Relative tolerance on t (DESIGN.md: "t within a relative 1e-5").
pub const REL_T: f32 = 1e-5;
/// Absolute tolerance per unit of coordinate magnitude `m` (≈ 8 f32 ulps).
pub const ABS_SCALE: f32 = 1e-6;
/// Tolerance on barycentric / quad coordinates of the same primitive.
pub const UV_TOL: f32 = 1e-4;
/// Distance from a primitive's boundary, per unit of `m`, within which a hit is on it.
pub const BOUNDARY_SCALE: f64 = 1e-6;
/// Disagreements kept (with their rays) in a report.
pub const MAX_REPORTED: usize = 20;
/// Ambiguous blockers walked through before an occlusion tie is refused.
const MAX_BLOCKERS: usize = 8;
/// Rays per rayon work item.
const CHUNK: u64 = 1024;

/// Settings of a cross-check run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CrosscheckOptions {
    /// Number of rays (split 25% per [`RayKind`]).
    pub rays: u64,
    /// Seed of the ray streams.
    pub seed: u64,
}

impl Default for CrosscheckOptions {
    fn default() -> Self {
        Self { rays: 100_000, seed: 0 }
    }
}

/// How a ray was generated (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RayKind {
    /// Camera rays over the image.
    Camera = 0,
    /// Random rays through the scene bounds.
    Bounds = 1,
    /// Rays aimed exactly at vertices, edges and silhouettes.
    Feature = 2,
    /// Shadow rays from surface points towards lights.
    Shadow = 3,
}

impl RayKind {
    /// All kinds, in the order rays cycle through them.
    pub const ALL: [RayKind; 4] = [RayKind::Camera, RayKind::Bounds, RayKind::Feature, RayKind::Shadow];

    /// The kind of ray `index`.
    pub fn of_ray(index: u64) -> RayKind {
        Self::ALL[(index % 4) as usize]
    }

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Bounds => "bounds",
            RayKind::Feature => "feature",
            RayKind::Shadow => "shadow",
        }
    }
}

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
    fn name(self) -> &'static str {
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

/// Which query disagreed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// `Accel::intersect`.
    Closest,
    /// `Accel::occluded`.
    Occluded,
}

/// One disagreeing ray, with what is needed to replay it.
#[derive(Clone, Debug, PartialEq)]
pub struct Disagreement {
    /// Ray index in the run.
    pub index: u64,
    /// How it was generated.
    pub kind: RayKind,
    /// The query that disagreed.
    pub query: Query,
    /// The ray.
    pub ray: Ray,
    /// The query's `t_max`.
    pub t_max: f32,
    /// `a`'s closest hit (for occlusion: the blocker when `a` reported occlusion).
    pub a: Option<Hit>,
    /// `b`'s closest hit (for occlusion: the blocker when `b` reported occlusion).
    pub b: Option<Hit>,
    /// Occlusion answers of `a` and `b` (occlusion queries only).
    pub occluded: Option<(bool, bool)>,
    /// Readable description of both hits and of the reason.
    pub reason: String,
}

/// Counts for one ray kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KindCounts {
    /// Rays cast.
    pub rays: u64,
    /// Rays on which at least one accelerator found a closest hit.
    pub hits: u64,
    /// Closest-hit agreements (both missing included).
    pub agreements: u64,
    /// Closest-hit ties.
    pub ties: u64,
    /// Closest-hit disagreements.
    pub disagreements: u64,
    /// Occlusion agreements.
    pub occlusion_agreements: u64,
    /// Occlusion ties.
    pub occlusion_ties: u64,
    /// Occlusion disagreements.
    pub occlusion_disagreements: u64,
}

impl KindCounts {
    fn add(&mut self, o: &KindCounts) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.agreements += o.agreements;
        self.ties += o.ties;
        self.disagreements += o.disagreements;
        self.occlusion_agreements += o.occlusion_agreements;
        self.occlusion_ties += o.occlusion_ties;
        self.occlusion_disagreements += o.occlusion_disagreements;
    }
}

/// The result of [`crosscheck`].
#[derive(Clone, Debug, PartialEq)]
pub struct CrosscheckReport {
    /// Name of accelerator `a` (`Accel::stats().name`).
    pub a_name: String,
    /// Name of accelerator `b`.
    pub b_name: String,
    /// Seed used.
    pub seed: u64,
    /// Counts per kind, indexed by `RayKind as usize`.
    pub per_kind: [KindCounts; 4],
    /// Ties (closest and occlusion) by reason, indexed by `TieReason as usize`.
    pub ties_by_reason: [u64; 3],
    /// Agreeing closest hits (both hit the same primitive).
    pub agreeing_hits: u64,
    /// Largest |Δt|/t over agreeing hits.
    pub max_rel_dt: f64,
    /// Sum of |Δt|/t over agreeing hits (for the mean).
    pub sum_rel_dt: f64,
    /// Largest |Δt|/δt over agreeing hits: how close the agreeing hits came
    /// to the tolerance (1 = at it). Unlike |Δt|/t it is not dominated by
    /// grazing hits, whose t is ill-conditioned.
    pub max_tolerance_used: f64,
    /// The first [`MAX_REPORTED`] disagreements in ray order.
    pub disagreements: Vec<Disagreement>,
}

impl CrosscheckReport {
    fn empty(a_name: String, b_name: String, seed: u64) -> Self {
        Self {
            a_name,
            b_name,
            seed,
            per_kind: [KindCounts::default(); 4],
            ties_by_reason: [0; 3],
            agreeing_hits: 0,
            max_rel_dt: 0.0,
            sum_rel_dt: 0.0,
            max_tolerance_used: 0.0,
            disagreements: Vec::new(),
        }
    }

    /// Counts of one kind.
    pub fn kind(&self, kind: RayKind) -> &KindCounts {
        &self.per_kind[kind as usize]
    }

    /// Counts over all kinds.
    pub fn total(&self) -> KindCounts {
        let mut t = KindCounts::default();
        for k in &self.per_kind {
            t.add(k);
        }
        t
    }

    /// Mean |Δt|/t over agreeing hits (0 without any).
    pub fn mean_rel_dt(&self) -> f64 {
        if self.agreeing_hits == 0 {
            0.0
        } else {
            self.sum_rel_dt / self.agreeing_hits as f64
        }
    }

    /// Disagreements of both queries (all of them, not only those kept).
    pub fn disagreement_count(&self) -> u64 {
        let t = self.total();
        t.disagreements + t.occlusion_disagreements
    }

    /// True when every difference is a tie.
    pub fn is_ok(&self) -> bool {
        self.disagreement_count() == 0
    }

    /// Appends `other` (the next rays in index order).
    fn merge(&mut self, other: CrosscheckReport) {
        for (k, o) in self.per_kind.iter_mut().zip(other.per_kind.iter()) {
            k.add(o);
        }
        for (t, o) in self.ties_by_reason.iter_mut().zip(other.ties_by_reason) {
            *t += o;
        }
        self.agreeing_hits += other.agreeing_hits;
        self.max_rel_dt = self.max_rel_dt.max(other.max_rel_dt);
        self.sum_rel_dt += other.sum_rel_dt;
        self.max_tolerance_used = self.max_tolerance_used.max(other.max_tolerance_used);
        let room = MAX_REPORTED.saturating_sub(self.disagreements.len());
        self.disagreements.extend(other.disagreements.into_iter().take(room));
    }
}

impl fmt::Display for CrosscheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let total = self.total();
        writeln!(
            f,
            "crosscheck: a = {}, b = {}; {} rays, seed {}",
            self.a_name, self.b_name, total.rays, self.seed
        )?;
        writeln!(
            f,
            "{:<8} {:>9} {:>9} | {:>9} {:>6} {:>8} | {:>9} {:>6} {:>8}",
            "", "", "", "closest", "", "", "occluded", "", ""
        )?;
        writeln!(
            f,
            "{:<8} {:>9} {:>9} | {:>9} {:>6} {:>8} | {:>9} {:>6} {:>8}",
            "kind", "rays", "hits", "agree", "ties", "disagree", "agree", "ties", "disagree"
        )?;
        let row = |f: &mut fmt::Formatter<'_>, name: &str, k: &KindCounts| {
            writeln!(
                f,
                "{:<8} {:>9} {:>9} | {:>9} {:>6} {:>8} | {:>9} {:>6} {:>8}",
                name,
                k.rays,
                k.hits,
                k.agreements,
                k.ties,
                k.disagreements,
                k.occlusion_agreements,
                k.occlusion_ties,
                k.occlusion_disagreements
            )
        };
        for kind in RayKind::ALL {
            row(f, kind.name(), self.kind(kind))?;
        }
        row(f, "total", &total)?;
        writeln!(
            f,
            "|Δt|/t over {} agreeing hits: max {:.3e}, mean {:.3e} (max share of the tolerance used: {:.3})",
            self.agreeing_hits,
            self.max_rel_dt,
            self.mean_rel_dt(),
            self.max_tolerance_used
        )?;
        writeln!(
            f,
            "ties: {} {}, {} {}, {} {}",
            self.ties_by_reason[0],
            TieReason::SameDistance.name(),
            self.ties_by_reason[1],
            TieReason::Boundary.name(),
            self.ties_by_reason[2],
            TieReason::IntervalEnd.name()
        )?;
        let count = self.disagreement_count();
        if count == 0 {
            return writeln!(f, "OK: no disagreement that is not a tie");
        }
        writeln!(
            f,
            "FAILED: {count} disagreements (first {} below; replay string: ox,oy,oz,dx,dy,dz,t_max)",
            self.disagreements.len()
        )?;
        for d in &self.disagreements {
            writeln!(f, "{d}")?;
        }
        Ok(())
    }
}

impl fmt::Display for Disagreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let query = match self.query {
            Query::Closest => "closest",
            Query::Occluded => "occluded",
        };
        writeln!(
            f,
            "  ray {} ({}, {query}): replay \"{}\"",
            self.index,
            self.kind.name(),
            format_ray(&self.ray, self.t_max)
        )?;
        write!(f, "    {}", self.reason)
    }
}

/// The replay string of a ray: `ox,oy,oz,dx,dy,dz,t_max`, each f32 in Rust's
/// shortest round-trip `{:e}` notation (`inf` for an unbounded query).
pub fn format_ray(ray: &Ray, t_max: f32) -> String {
    let o = ray.origin;
    let d = ray.dir;
    format!(
        "{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
        o.x, o.y, o.z, d.x, d.y, d.z, t_max
    )
}

/// A replay string that cannot be read.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum ReplayParseError {
    /// Not 6 or 7 comma-separated values.
    #[error("expected \"ox,oy,oz,dx,dy,dz[,t_max]\", got {0} values")]
    Count(usize),
    /// A value is not a number.
    #[error("value {index} ('{text}') is not a number")]
    Number {
        /// 1-based position.
        index: usize,
        /// The text.
        text: String,
    },
    /// Non-finite origin or direction, zero direction, or t_max not > 0.
    #[error("{0}")]
    Invalid(&'static str),
}

/// Reads a replay string (see [`format_ray`]); `t_max` defaults to ∞.
pub fn parse_ray(text: &str) -> Result<(Ray, f32), ReplayParseError> {
    let parts: Vec<&str> = text.trim().trim_matches('"').split(',').map(str::trim).collect();
    if parts.len() != 6 && parts.len() != 7 {
        return Err(ReplayParseError::Count(parts.len()));
    }
    let mut v = [f32::INFINITY; 7];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p.parse::<f32>().map_err(|_| ReplayParseError::Number {
            index: i + 1,
            text: (*p).to_string(),
        })?;
    }
    let origin = Vec3A::new(v[0], v[1], v[2]);
    let dir = Vec3A::new(v[3], v[4], v[5]);
    if !origin.is_finite() || !dir.is_finite() {
        return Err(ReplayParseError::Invalid("origin and direction must be finite"));
    }
    if dir == Vec3A::ZERO {
        return Err(ReplayParseError::Invalid("the direction is zero"));
    }
    let positive = v[6] > 0.0; // false for NaN too
    if !positive {
        return Err(ReplayParseError::Invalid("t_max must be > 0"));
    }
    Ok((Ray::new(origin, dir), v[6]))
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

/// Casts `opts.rays` seeded rays through `a` and `b` and reports how they compare.
pub fn crosscheck(scene: &Scene, a: &dyn Accel, b: &dyn Accel, opts: &CrosscheckOptions) -> CrosscheckReport {
    let generator = RayGenerator::new(scene, opts.seed);
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

/// A hit in words, with full-precision numbers.
fn describe(scene: &Scene, hit: Option<&Hit>) -> String {
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
fn invalid_hit(scene: &Scene, ray: &Ray, t_max: f32, hit: &Hit) -> Option<String> {
    let Some(object) = scene.objects.get(hit.instance as usize) else {
        return Some(format!("instance {} out of range", hit.instance));
    };
    let prims = match &object.shape {
        Shape::Mesh { mesh, .. } => scene.meshes[*mesh as usize].triangles.len(),
        Shape::Sphere(_) | Shape::Quad(_) => 1,
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
    /// `m = |o| + |p| + |T|` (see the module documentation).
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

/// δt of the module documentation for a hit at `t`.
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
            let uv_ok = matches!(scene.objects[x.instance as usize].shape, Shape::Sphere(_))
                || ((x.u - y.u).abs() <= UV_TOL && (x.v - y.v).abs() <= UV_TOL)
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

/// Seeded ray generation (see the module documentation).
struct RayGenerator<'s> {
    scene: &'s Scene,
    seed: u64,
    bounds: Aabb,
    center: Vec3A,
    outer_radius: f32,
}

impl<'s> RayGenerator<'s> {
    fn new(scene: &'s Scene, seed: u64) -> Self {
        let mut bounds = scene.bounds();
        if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
            bounds = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        }
        let center = bounds.center();
        let half_diagonal = (bounds.extent().length() * 0.5).max(1e-3 * (1.0 + center.length()));
        Self {
            scene,
            seed,
            bounds,
            center,
            outer_radius: 1.5 * half_diagonal,
        }
    }

    fn in_box(b: &Aabb, rng: &mut Rng) -> Vec3A {
        b.min + b.extent() * Vec3A::new(rng.f32(), rng.f32(), rng.f32())
    }

    fn on_outer_sphere(&self, rng: &mut Rng) -> Vec3A {
        self.center + uniform_sphere(Vec2::new(rng.f32(), rng.f32())) * self.outer_radius
    }

    fn towards(origin: Vec3A, target: Vec3A) -> Ray {
        Ray::new(origin, (target - origin).normalize_or(Vec3A::Z))
    }

    /// Ray and closest-hit `t_max` of the given kind.
    fn ray(&self, kind: RayKind, rng: &mut Rng, a: &dyn Accel) -> (Ray, f32) {
        match kind {
            RayKind::Camera => {
                let s = &self.scene.settings;
                let (w, h) = (s.width.max(1), s.height.max(1));
                let ray = self.scene.camera.ray(rng.f32() * w as f32, rng.f32() * h as f32, w, h);
                (ray, f32::INFINITY)
            }
            RayKind::Bounds => (self.bounds_ray(rng), f32::INFINITY),
            RayKind::Feature => (self.feature_ray(rng), f32::INFINITY),
            RayKind::Shadow => self.shadow_ray(rng, a),
        }
    }

    fn bounds_ray(&self, rng: &mut Rng) -> Ray {
        if rng.below(2) == 0 {
            let origin = self.on_outer_sphere(rng);
            Self::towards(origin, Self::in_box(&self.bounds, rng))
        } else {
            let origin = Self::in_box(&self.bounds, rng);
            Ray::new(origin, uniform_sphere(Vec2::new(rng.f32(), rng.f32())))
        }
    }

    fn feature_ray(&self, rng: &mut Rng) -> Ray {
        let scene = self.scene;
        if scene.objects.is_empty() {
            return self.bounds_ray(rng);
        }
        let k = rng.below(scene.objects.len() as u32) as usize;
        let origin = if rng.below(2) == 0 {
            self.on_outer_sphere(rng)
        } else {
            let ob = scene.object_bounds(k);
            let c = ob.center();
            let half = ob.extent() * 1.5;
            Self::in_box(&Aabb::new(c - half, c + half), rng)
        };
        let on_edge = |rng: &mut Rng, corners: &[Vec3A]| {
            let n = corners.len() as u32;
            let i = rng.below(n) as usize;
            if rng.below(3) == 0 {
                corners[i]
            } else {
                let (p, q) = (corners[i], corners[(i + 1) % corners.len()]);
                p + (q - p) * rng.f32()
            }
        };
        let target = match &scene.objects[k].shape {
            Shape::Mesh { mesh, transform, .. } => {
                let mesh = &scene.meshes[*mesh as usize];
                let tri = rng.below(mesh.triangles.len() as u32) as usize;
                transform.point(on_edge(rng, &mesh.corners(tri)))
            }
            Shape::Quad(q) => on_edge(rng, &[q.corner, q.corner + q.u, q.corner + q.u + q.v, q.corner + q.v]),
            Shape::Sphere(s) => {
                let f = origin - s.center;
                let dist = f.length();
                if dist <= s.radius * 1.0001 {
                    s.center + uniform_sphere(Vec2::new(rng.f32(), rng.f32())) * s.radius
                } else {
                    // The tangent points from `origin` form a circle at angle
                    // acos(r/D) from the direction to the origin.
                    let w = f / dist;
                    let frame = Frame::from_normal(w);
                    let cos_a = s.radius / dist;
                    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                    let phi = rng.f32() * std::f32::consts::TAU;
                    let around = frame.s * phi.cos() + frame.t * phi.sin();
                    s.center + (w * cos_a + around * sin_a) * s.radius
                }
            }
        };
        Self::towards(origin, target)
    }

    fn light_target(&self, rng: &mut Rng) -> Vec3A {
        let lights = &self.scene.lights;
        if lights.is_empty() {
            return Self::in_box(&self.bounds, rng);
        }
        match &lights[rng.below(lights.len() as u32) as usize] {
            Light::Point { position, .. } => *position,
            Light::Area(area) => area.point(Vec2::new(rng.f32(), rng.f32())),
        }
    }

    fn shadow_ray(&self, rng: &mut Rng, a: &dyn Accel) -> (Ray, f32) {
        const ATTEMPTS: usize = 4;
        for _ in 0..ATTEMPTS {
            let origin = self.on_outer_sphere(rng);
            let primary = Self::towards(origin, Self::in_box(&self.bounds, rng));
            let Some(hit) = a.intersect(&primary, f32::INFINITY) else {
                continue;
            };
            if invalid_hit(self.scene, &primary, f32::INFINITY, &hit).is_some() {
                continue;
            }
            let si = self.scene.surface_interaction(&primary, &hit);
            let target = self.light_target(rng);
            let origin = offset_ray_origin(si.p, si.p_error, si.ng, target - si.p);
            let to_light = target - origin;
            let dist = to_light.length();
            if dist > 0.0 && dist.is_finite() {
                return (Ray::new(origin, to_light / dist), dist);
            }
        }
        // Nothing hit: a segment from inside the bounds to a light.
        let origin = Self::in_box(&self.bounds, rng);
        let target = self.light_target(rng);
        let dist = (target - origin).length();
        if dist > 0.0 && dist.is_finite() {
            (Ray::new(origin, (target - origin) / dist), dist)
        } else {
            (self.bounds_ray(rng), f32::INFINITY)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::brute::BruteForce;
    use crate::accel::{AccelStats, TriangleTest};
    use crate::math::{Transform, Vec3};
    use crate::scene::{AreaLight, Camera, Material, Mesh, Object, Quad, RenderSettings, Sphere};
    use std::sync::Arc;

    /// A closed octahedron (instanced twice), a floor quad, a sphere, an area light.
    fn small_scene() -> Scene {
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
            settings: RenderSettings {
                width: 64,
                height: 48,
                ..Default::default()
            },
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
            ray.origin.x.to_bits() % self.modulus == 0
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

    fn brute(scene: &Scene) -> BruteForce {
        BruteForce::new(scene, TriangleTest::Watertight)
    }

    #[test]
    fn identical_accelerators_agree_on_every_ray() {
        let scene = small_scene();
        let (a, b) = (brute(&scene), brute(&scene));
        let report = crosscheck(&scene, &a, &b, &CrosscheckOptions { rays: 8000, seed: 3 });
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
        let opts = CrosscheckOptions { rays: 5000, seed: 11 };
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
        let report = crosscheck(&scene, &good, &wrong, &CrosscheckOptions { rays: 4000, seed: 1 });
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
        let report = crosscheck(&scene, &wrong, &good, &CrosscheckOptions { rays: 4000, seed: 9 });
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
        let report = crosscheck(&scene, &good, &wrong, &CrosscheckOptions { rays: 2000, seed: 4 });
        let total = report.total();
        assert_eq!(total.disagreements, 0, "{report}");
        assert!(total.occlusion_disagreements > 200, "{report}");
        assert!(report.disagreements.iter().all(|d| d.query == Query::Occluded));
        assert_eq!(report.disagreements[0].occluded, Some((true, false)));
    }

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

    #[test]
    fn replay_strings_round_trip_and_reject_garbage() {
        let ray = Ray::new(Vec3A::new(0.1, -1e-30, 3.4028235e38), Vec3A::new(1.0 / 3.0, 0.0, -0.7));
        for t_max in [f32::INFINITY, 1.1754944e-38, 2.5] {
            let s = format_ray(&ray, t_max);
            let (back, t) = parse_ray(&s).unwrap();
            assert_eq!(back, ray);
            assert_eq!(t.to_bits(), t_max.to_bits());
        }
        assert_eq!(parse_ray("1,2,3,0,0,1").unwrap().1, f32::INFINITY);
        assert_eq!(parse_ray("1,2,3"), Err(ReplayParseError::Count(3)));
        assert!(matches!(
            parse_ray("1,2,x,0,0,1"),
            Err(ReplayParseError::Number { index: 3, .. })
        ));
        assert!(matches!(parse_ray("1,2,3,0,0,0"), Err(ReplayParseError::Invalid(_))));
        assert!(matches!(parse_ray("1,2,NaN,0,0,1"), Err(ReplayParseError::Invalid(_))));
        assert!(matches!(parse_ray("1,2,3,0,0,1,-1"), Err(ReplayParseError::Invalid(_))));
    }
}
