//! Radiance estimate from the photon map (Jensen 1996, "Global Illumination
//! using Photon Maps"; Jensen, *Realistic Image Synthesis Using Photon
//! Mapping*, §7.2): the `k` nearest photons within a maximum radius, weighted
//! by the cone filter `w(d) = 1 − d/(k_c r)` and normalised by the filter's
//! integral over the disk of radius `r`, `(1 − 2/(3 k_c)) π r²`:
//!
//! `E(x) ≈ Σ_p Φ_p w(d_p) / ((1 − 2/(3 k_c)) π r²)`
//!
//! is the irradiance; a Lambertian surface then reflects `ρ/π · E`.
//! `r` is the distance to the farthest gathered photon when `k` were found,
//! else the maximum radius (the search disk actually covered): taking the
//! farthest photon's distance when fewer than `k` exist would divide one
//! lone photon by a tiny area, a firefly.
//!
//! With a fixed radius (`GatherParams::fixed_radius`, progressive photon
//! mapping: Knaus & Zwicker 2011) every photon within `r` counts and `r` is
//! that radius, whatever the photon density: the same cone-filtered sum
//! over the same normalised disk, so that its expectation is the
//! irradiance convolved with a kernel of fixed support `r`, the quantity
//! whose bias Knaus & Zwicker's radius sequence drives to zero.

use super::chunked::Neighbour;
use super::map::{to_tree, PhotonMap, PhotonRecord};
use super::precomputed::{SiteCache, SiteSearch};
use crate::math::Vec3A;
use std::f32::consts::PI;
use std::num::NonZero;

/// Gather parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherParams {
    /// Photons gathered (k nearest).
    pub k: NonZero<usize>,
    /// Largest search radius.
    pub max_radius: f32,
    /// Cone-filter constant `k_c ≥ 1`.
    pub cone_k: f32,
    /// Gather every photon within this radius instead of the `k` nearest
    /// (progressive photon mapping's `r_i`, `photon::progressive`); `k` and
    /// `max_radius` are then unused, and a precomputed irradiance is not
    /// looked up (it was made for another radius).
    pub fixed_radius: Option<f32>,
}

impl GatherParams {
    /// The k-nearest gather within `max_radius`.
    pub fn k_nearest(k: NonZero<usize>, max_radius: f32, cone_k: f32) -> Self {
        Self {
            k,
            max_radius,
            cone_k,
            fixed_radius: None,
        }
    }
}

/// A direct surface estimate and the disk it divided by.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Estimate {
    /// Irradiance from the normal's side.
    pub irradiance: Vec3A,
    /// Radius of the disk (0 when nothing was found).
    pub radius: f32,
    /// Photons found in the disk, from either side: `π r² / photons` is
    /// the map's area per stored photon there.
    pub photons: usize,
}

impl Estimate {
    /// Nothing found.
    const NONE: Self = Self {
        irradiance: Vec3A::ZERO,
        radius: 0.0,
        photons: 0,
    };
}

/// Cone-filter weight of a photon at distance `d` in a disk of radius `r`.
#[inline]
pub fn cone_weight(d: f32, r: f32, cone_k: f32) -> f32 {
    (1.0 - d / (cone_k * r)).max(0.0)
}

/// Integral of the cone filter over the unit-area-normalised disk:
/// `∫_disk w dA / (π r²) = 1 − 2/(3 k_c)`.
#[inline]
pub fn cone_normalisation(cone_k: f32) -> f32 {
    1.0 - 2.0 / (3.0 * cone_k)
}

/// How many times fewer photons the path integrator's vertices after a
/// path's first non-specular one gather (their blur is hidden by the bounce).
pub const INDIRECT_GATHER_DIVISOR: usize = 4;

/// How much larger than the surface gather's radius the path integrator's
/// volume gather's is: photons that scatter fill a volume, so they lie
/// much farther apart.
pub const VOLUME_RADIUS_SCALE: f32 = 4.0;

/// Integral of the cone filter over the volume-normalised ball:
/// `∫_ball w dV / (4/3 π r³) = 3 ∫0^1 (1 − x/k_c) x² dx = 1 − 3/(4 k_c)`.
#[inline]
pub fn ball_cone_normalisation(cone_k: f32) -> f32 {
    1.0 - 3.0 / (4.0 * cone_k)
}

/// What a density estimate divides the gathered power by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// The disk `π r²` of a surface estimate.
    Disk,
    /// The ball `4/3 π r³` of a volume estimate.
    Ball,
}

impl PhotonMap {
    /// `Σ weight(photon) · cone(d) / (normalisation · measure)` over the k
    /// nearest photons within the largest radius: with the BSDF as weight
    /// on a surface, the reflected radiance `Σ f(ωo, ωp) Φp / (π r²)`
    /// (Jensen 1996); with the phase function in a medium, the in-scattered
    /// radiance per unit length `Σ p(ωo, ωp) Φp / (4/3 π r³)` (Jensen &
    /// Christensen 1998, §3.2), the scattering coefficient being already in
    /// the stored powers.
    pub fn weighted_estimate(
        &self,
        p: Vec3A,
        g: &GatherParams,
        kernel: Kernel,
        weight: impl Fn(&PhotonRecord) -> Vec3A,
    ) -> Vec3A {
        let reach = g.fixed_radius.unwrap_or(g.max_radius);
        if self.is_empty() || !self.near_bounds(p, reach) {
            return Vec3A::ZERO;
        }
        let q = to_tree(&self.rotation, p);
        let found = self.find(&q, g);
        if found.is_empty() {
            return Vec3A::ZERO;
        }
        // The k-th photon defines the radius, so it always lies on the disk's
        // edge: counting it biases the estimate up by about
        // (1 − 1/k_c) / ((1 − 2/(3k_c))(k − 1)) (+0.4 % at k = 64, +3 % at
        // k = 8). Left out, the other k − 1 are spread over the disk as the
        // density is, and the estimate is unbiased where it is uniform.
        let (r2, edge) = if let Some(r) = g.fixed_radius {
            (r * r, None)
        } else if found.len() >= g.k.get() {
            let far = (0..found.len())
                .max_by(|&a, &b| found[a].distance.total_cmp(&found[b].distance))
                .expect("not empty");
            (found[far].distance, Some(far))
        } else {
            (g.max_radius * g.max_radius, None)
        };
        if r2.is_nan() || r2 <= 0.0 {
            return Vec3A::ZERO;
        }
        let r = r2.sqrt();
        let mut sum = Vec3A::ZERO;
        for (i, nb) in found.iter().enumerate() {
            if Some(i) == edge {
                continue;
            }
            let w = cone_weight(nb.distance.sqrt(), r, g.cone_k);
            if w > 0.0 {
                sum += weight(&self.records[nb.item as usize]) * w;
            }
        }
        let measure = match kernel {
            Kernel::Disk => cone_normalisation(g.cone_k) * PI * r2,
            Kernel::Ball => ball_cone_normalisation(g.cone_k) * (4.0 / 3.0) * PI * r2 * r,
        };
        sum / measure
    }

    /// Irradiance at `p` on a surface whose normal, turned toward the
    /// viewer, is `n`: only photons that arrived from that side count (a
    /// thin wall's other side, or the floor under a table, stay separate).
    /// Always the full k-nearest gather (the `direct` mode).
    pub fn irradiance(&self, p: Vec3A, n: Vec3A, g: &GatherParams) -> Vec3A {
        self.gather(p, n, g).irradiance
    }

    /// The caustic irradiance the renderer uses: the precomputed estimate
    /// when [`PhotonMap::precompute_irradiance`] ran, else
    /// [`PhotonMap::irradiance`].
    #[inline]
    pub fn caustic_irradiance(&self, p: Vec3A, n: Vec3A, g: &GatherParams) -> Vec3A {
        self.caustic_irradiance_with(p, n, g, SiteSearch::Uncached, &mut SiteCache::default())
    }

    /// [`caustic_irradiance`](Self::caustic_irradiance) with the sites
    /// found by `search` (see [`SiteSearch`]); `cache` holds the search's
    /// buffers and, for [`SiteSearch::Cached`], the neighbourhoods of
    /// earlier lookups. Without precomputed sites, or for a fixed-radius
    /// gather, the direct gather.
    #[inline]
    pub fn caustic_irradiance_with(
        &self,
        p: Vec3A,
        n: Vec3A,
        g: &GatherParams,
        search: SiteSearch,
        cache: &mut SiteCache,
    ) -> Vec3A {
        match &self.precomputed {
            Some(pre) if g.fixed_radius.is_none() => pre.lookup(self, (p, n), g, cache, search),
            _ => self.irradiance(p, n, g),
        }
    }

    /// The direct estimate, with the disk it divided by.
    pub(super) fn gather(&self, p: Vec3A, n: Vec3A, g: &GatherParams) -> Estimate {
        if let Some(r) = g.fixed_radius {
            return self.gather_within(p, n, r, g.cone_k);
        }
        // Early out: no photon can lie within the radius of a point farther
        // than it from the map's bounds (most of an image, for caustics).
        if self.is_empty() || !self.near_bounds(p, g.max_radius) {
            return Estimate::NONE;
        }
        let found = self.find(&to_tree(&self.rotation, p), g);
        self.estimate(&found, n, g)
    }

    /// The k-nearest estimate at the position of one of the stored photons,
    /// that photon left out. A gather centred on a photon always holds it,
    /// at the cone filter's peak weight, so the estimate at a photon is
    /// biased upward (by about `1/(k·(1 − 2/(3 k_c)))`, +4 % at k = 64):
    /// leaving it out makes the other `k` an ordinary sample of the
    /// density around the point (the leave-one-out estimate of
    /// nonparametric density estimation). At a point where no photon lies
    /// this is [`gather`](Self::gather).
    pub(super) fn gather_at_photon(&self, p: Vec3A, n: Vec3A, g: &GatherParams) -> Estimate {
        if g.fixed_radius.is_some() || self.is_empty() || !self.near_bounds(p, g.max_radius) {
            return self.gather(p, n, g);
        }
        let one_more = GatherParams {
            k: g.k.saturating_add(1),
            ..*g
        };
        let mut found = self.find(&to_tree(&self.rotation, p), &one_more);
        let left_out = match found.iter().position(|nb| nb.distance == 0.0) {
            Some(own) => Some(own),
            // No photon here: the k nearest, as `gather` finds them.
            None if found.len() > g.k.get() => found
                .iter()
                .enumerate()
                .max_by_key(|(_, nb)| nb.order_key())
                .map(|(i, _)| i),
            None => None,
        };
        if let Some(i) = left_out {
            found.swap_remove(i);
        }
        self.estimate(&found, n, g)
    }

    /// Every photon within the fixed radius `r` that arrived from `n`'s
    /// side, cone-filtered and divided by the filter's integral over the
    /// disk of radius `r` (0 when `r` is not positive).
    fn gather_within(&self, p: Vec3A, n: Vec3A, r: f32, cone_k: f32) -> Estimate {
        let r2 = r * r;
        if self.is_empty() || r2.is_nan() || r2 <= 0.0 || !self.near_bounds(p, r) {
            return Estimate::NONE;
        }
        let found = self.find(
            &to_tree(&self.rotation, p),
            &GatherParams {
                k: NonZero::<usize>::MIN,
                max_radius: r,
                cone_k,
                fixed_radius: Some(r),
            },
        );
        if found.is_empty() {
            return Estimate::NONE;
        }
        let mut sum = Vec3A::ZERO;
        for nb in &found {
            let rec = self.records[nb.item as usize];
            if rec.arrives_from_side_of(n) {
                sum += rec.power() * cone_weight(nb.distance.sqrt(), r, cone_k);
            }
        }
        Estimate {
            irradiance: sum / (cone_normalisation(cone_k) * PI * r2),
            radius: r,
            photons: found.len(),
        }
    }

    /// The cone-filtered estimate from the gathered `found` photons.
    fn estimate(&self, found: &[Neighbour], n: Vec3A, g: &GatherParams) -> Estimate {
        if found.is_empty() {
            return Estimate::NONE;
        }
        let r2 = if found.len() >= g.k.get() {
            found.iter().fold(0.0f32, |m, nb| m.max(nb.distance))
        } else {
            g.max_radius * g.max_radius
        };
        if r2.is_nan() || r2 <= 0.0 {
            return Estimate::NONE;
        }
        let r = r2.sqrt();
        let mut sum = Vec3A::ZERO;
        for nb in found {
            let rec = self.records[nb.item as usize];
            if !rec.arrives_from_side_of(n) {
                continue;
            }
            sum += rec.power() * cone_weight(nb.distance.sqrt(), r, g.cone_k);
        }
        Estimate {
            irradiance: sum / (cone_normalisation(g.cone_k) * PI * r2),
            radius: r,
            photons: found.len(),
        }
    }

    /// The photons a gather at `q` (tree coordinates) sums: every one
    /// within the fixed radius, or the `k` nearest within the largest
    /// radius; from the grid when the map has one, else from the tree.
    fn find(&self, q: &[f32; 3], g: &GatherParams) -> Vec<Neighbour> {
        match (&self.grid, g.fixed_radius) {
            (Some(grid), Some(r)) => {
                let mut found = Vec::with_capacity(256);
                grid.within(q, r * r, &mut found);
                found
            }
            (Some(grid), None) => {
                let mut found = Vec::with_capacity(4 * g.k.get());
                grid.nearest_n_within(q, g.max_radius * g.max_radius, g.k, &mut found);
                found
            }
            (None, Some(r)) => self.tree.within(q, r * r),
            (None, None) => self.tree.nearest_n_within(q, g.max_radius * g.max_radius, g.k),
        }
    }

    /// True when `p` is within `radius` of the map's bounds.
    #[inline]
    pub(super) fn near_bounds(&self, p: Vec3A, radius: f32) -> bool {
        let b = self.bounds();
        let d = (b.min - p).max(p - b.max).max(Vec3A::ZERO);
        d.length_squared() <= radius * radius
    }
}

#[cfg(test)]
mod tests {
    use super::super::map::Photon;
    use super::*;
    use crate::math::rng::{Domain, Rng};

    #[test]
    fn cone_kernel_integrates_to_one_over_the_disk() {
        for cone_k in [1.0f32, 1.1, 2.0, 10.0] {
            let r = 0.7f64;
            let steps = 20_000;
            // ∫_0^r w(d) 2π d dd, midpoint rule.
            let mut integral = 0.0f64;
            for i in 0..steps {
                let d = (i as f64 + 0.5) / steps as f64 * r;
                integral += cone_weight(d as f32, r as f32, cone_k) as f64 * 2.0 * std::f64::consts::PI * d;
            }
            integral *= r / steps as f64;
            let normalised = integral / (cone_normalisation(cone_k) as f64 * std::f64::consts::PI * r * r);
            assert!((normalised - 1.0).abs() < 1e-4, "k_c = {cone_k}: {normalised}");
        }
    }

    #[test]
    fn ball_cone_kernel_integrates_to_one() {
        for cone_k in [1.0f32, 1.1, 3.0] {
            let steps = 20_000;
            // 3 ∫_0^1 w(x) x² dx over the unit ball, midpoint rule.
            let integral: f64 = (0..steps)
                .map(|i| {
                    let x = (i as f64 + 0.5) / steps as f64;
                    cone_weight(x as f32, 1.0, cone_k) as f64 * 3.0 * x * x / steps as f64
                })
                .sum();
            assert!((integral / ball_cone_normalisation(cone_k) as f64 - 1.0).abs() < 1e-4);
        }
    }

    /// Photons spread uniformly in a cube with total power P: the volume
    /// estimate with a constant weight recovers P / V.
    #[test]
    fn uniform_volume_density_is_recovered() {
        let side = 2.0f32;
        let n = 300_000;
        let power = Vec3A::new(3.0, 2.0, 1.0);
        let mut rng = Rng::new(6, Domain::Analysis, 0, 0);
        let photons: Vec<Photon> = (0..n)
            .map(|_| Photon {
                position: (Vec3A::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * side,
                incoming: Vec3A::Y,
                normal: Vec3A::ZERO,
                power: power / n as f32,
            })
            .collect();
        let map = PhotonMap::from_photons(&photons);
        let g = GatherParams::k_nearest(NonZero::new(400).unwrap(), 0.6, 1.1);
        let want = power / (side * side * side);
        let mut mean = Vec3A::ZERO;
        for i in 0..27 {
            let p = Vec3A::new((i % 3) as f32, ((i / 3) % 3) as f32, (i / 9) as f32) * 0.3 - 0.3;
            let est = map.weighted_estimate(p, &g, Kernel::Ball, |r| r.power());
            assert!((est / want - Vec3A::ONE).abs().max_element() < 0.2, "{est} vs {want}");
            mean += est / 27.0;
        }
        assert!(
            (mean / want - Vec3A::ONE).abs().max_element() < 0.04,
            "{mean} vs {want}"
        );
    }

    /// A map whose gathers a grid answers gives a tree map's estimates
    /// (the same photons with the same distances, summed in another
    /// order): fixed-radius and k-nearest, weighted and irradiance.
    #[test]
    fn grid_map_gathers_as_the_tree_map() {
        let n = 50_000;
        let mut rng = Rng::new(11, Domain::Analysis, 0, 0);
        let photons: Vec<Photon> = (0..n)
            .map(|_| {
                let (a, b) = rng.f32x2();
                Photon {
                    position: Vec3A::new((a - 0.5) * 4.0, 0.2 * a * a, (b - 0.5) * 4.0),
                    incoming: Vec3A::new(0.3, 0.9, 0.1 - b).normalize(),
                    normal: Vec3A::Y,
                    power: Vec3A::new(1.0, 0.5, 0.25) * (rng.f32() / n as f32),
                }
            })
            .collect();
        let positions: Vec<[f32; 3]> = photons.iter().map(|p| p.position.to_array()).collect();
        let records: Vec<PhotonRecord> = photons.iter().map(|p| PhotonRecord::new(p.power, p.incoming)).collect();
        let tree = PhotonMap::build(positions.clone(), records.clone(), false);
        let radius = 0.15;
        let grid = PhotonMap::build_with_grid(positions, records, false, Some(radius));
        assert!(grid.memory_bytes() < tree.memory_bytes() * 3 / 2);
        let close = |a: Vec3A, b: Vec3A| (a - b).abs().max_element() <= 1e-5 * a.max_element();
        for fixed in [Some(radius), Some(radius * 0.4), None] {
            let g = GatherParams {
                k: NonZero::new(32).unwrap(),
                max_radius: radius,
                cone_k: 1.1,
                fixed_radius: fixed,
            };
            for _ in 0..300 {
                let (a, b) = rng.f32x2();
                let p = Vec3A::new(a * 4.6 - 2.3, 0.1, b * 4.6 - 2.3);
                let (t, s) = (
                    tree.weighted_estimate(p, &g, Kernel::Disk, |r| r.power()),
                    grid.weighted_estimate(p, &g, Kernel::Disk, |r| r.power()),
                );
                assert!(close(t, s), "{fixed:?} at {p}: {t} vs {s}");
                let (t, s) = (tree.irradiance(p, Vec3A::Y, &g), grid.irradiance(p, Vec3A::Y, &g));
                assert!(close(t, s), "{fixed:?} at {p}: {t} vs {s}");
            }
        }
    }

    /// With few photons per gather the k-th photon, which sets the radius,
    /// would bias the estimate by +3 % at k = 8 (cone k_c = 1.1); left out,
    /// the mean over many gathers of a uniform density is the density.
    #[test]
    fn small_k_nearest_estimates_are_unbiased_on_a_uniform_density() {
        let side = 4.0f32;
        let n = 200_000;
        let mut rng = Rng::new(8, Domain::Analysis, 0, 0);
        let photons: Vec<Photon> = (0..n)
            .map(|_| Photon {
                position: Vec3A::new((rng.f32() - 0.5) * side, 0.0, (rng.f32() - 0.5) * side),
                incoming: Vec3A::Y,
                normal: Vec3A::Y,
                power: Vec3A::ONE / n as f32,
            })
            .collect();
        let map = PhotonMap::from_photons(&photons);
        let g = GatherParams::k_nearest(NonZero::new(8).unwrap(), 1.0, 1.1);
        let want = 1.0 / (side * side) as f64;
        let queries = 20_000;
        let mean: f64 = (0..queries)
            .map(|_| {
                let p = Vec3A::new((rng.f32() - 0.5) * 3.0, 0.0, (rng.f32() - 0.5) * 3.0);
                map.weighted_estimate(p, &g, Kernel::Disk, |r| r.power()).x as f64
            })
            .sum::<f64>()
            / queries as f64;
        assert!((mean / want - 1.0).abs() < 0.01, "mean {mean} vs {want}");
    }

    /// Photons spread uniformly over a plane with known irradiance E:
    /// N photons of power E·A/N on area A.
    #[test]
    fn uniform_irradiance_is_recovered() {
        let side = 4.0f32;
        let n = 400_000;
        let e = Vec3A::new(2.0, 1.0, 0.5);
        let power = e * (side * side / n as f32);
        let mut rng = Rng::new(5, Domain::Analysis, 0, 0);
        let photons: Vec<Photon> = (0..n)
            .map(|_| {
                let (a, b) = rng.f32x2();
                Photon {
                    position: Vec3A::new((a - 0.5) * side, 0.0, (b - 0.5) * side),
                    incoming: Vec3A::new(0.3, 0.9, 0.1).normalize(),
                    normal: Vec3A::Y,
                    power,
                }
            })
            .collect();
        let map = PhotonMap::from_photons(&photons);
        let g = GatherParams {
            k: NonZero::new(200).unwrap(),
            max_radius: 0.5,
            cone_k: 1.1,
            fixed_radius: None,
        };
        let mut mean = Vec3A::ZERO;
        let queries = 50;
        for i in 0..queries {
            let p = Vec3A::new((i % 7) as f32 * 0.3 - 1.0, 0.0, (i / 7) as f32 * 0.25 - 0.9);
            let est = map.irradiance(p, Vec3A::Y, &g);
            assert!((est.x / e.x - 1.0).abs() < 0.2, "single estimate {est}");
            mean += est / queries as f32;
        }
        assert!((mean / e - Vec3A::ONE).abs().max_element() < 0.03, "mean {mean} vs {e}");
        // From below, no photon arrived: nothing.
        assert_eq!(map.irradiance(Vec3A::ZERO, -Vec3A::Y, &g), Vec3A::ZERO);
        // Far away: nothing within the radius.
        assert_eq!(map.irradiance(Vec3A::new(0.0, 5.0, 0.0), Vec3A::Y, &g), Vec3A::ZERO);
        // The fixed-radius gather of progressive photon mapping recovers it
        // too, and counts exactly the photons within the radius.
        let fixed = GatherParams {
            fixed_radius: Some(0.3),
            ..g
        };
        let mut mean = Vec3A::ZERO;
        for i in 0..queries {
            let p = Vec3A::new((i % 7) as f32 * 0.3 - 1.0, 0.0, (i / 7) as f32 * 0.25 - 0.9);
            mean += map.irradiance(p, Vec3A::Y, &fixed) / queries as f32;
        }
        assert!(
            (mean / e - Vec3A::ONE).abs().max_element() < 0.03,
            "fixed radius: mean {mean} vs {e}"
        );
        assert_eq!(map.irradiance(Vec3A::ZERO, -Vec3A::Y, &fixed), Vec3A::ZERO);
        assert_eq!(map.gather(Vec3A::ZERO, Vec3A::Y, &fixed).radius, 0.3);
        let q = Vec3A::new(0.1, 0.0, -0.2);
        let inside = photons
            .iter()
            .filter(|p| (p.position - q).length_squared() <= 0.09)
            .count();
        let found = map.tree.within(&to_tree(&map.rotation, q), 0.09);
        assert!(
            inside.abs_diff(found.len()) <= 2,
            "{inside} within, {} found",
            found.len()
        );
    }
}
