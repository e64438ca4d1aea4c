//! The cross-check report: counts per ray kind, ties by reason, the first
//! disagreements with their replay strings, and its printed table.

use super::compare::TieReason;
use super::rays::RayKind;
use super::replay::format_ray;
use crate::accel::Hit;
use crate::math::Ray;
use std::fmt;

/// Disagreements kept (with their rays) in a report.
pub const MAX_REPORTED: usize = 20;

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

/// The result of [`crosscheck`](super::crosscheck).
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
    pub(super) fn empty(a_name: String, b_name: String, seed: u64) -> Self {
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
    pub(super) fn merge(&mut self, other: CrosscheckReport) {
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
