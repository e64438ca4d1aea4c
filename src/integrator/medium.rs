//! A homogeneous participating medium for the path integrator and the
//! photon tracer: free-flight distance sampling, transmittance, and the
//! Henyey–Greenstein phase function (pbrt-v3 §11.2 and §15.2).
//!
//! Coefficients differ per channel (water absorbs red first), so the
//! distance is sampled from one channel chosen uniformly and the density is
//! the average over the channels (the one-sample MIS of spectral tracking,
//! pbrt-v3 §15.2.2): `p(t) = (1/3) Σ_c σt_c exp(−σt_c t)`, and reaching the
//! next surface has probability `(1/3) Σ_c exp(−σt_c d)`. The weights below
//! keep every channel unbiased.

use crate::math::{Aabb, Frame, Ray, Vec2, Vec3A};
use crate::scene::medium::VolumeCoefficients;
use crate::scene::{HomogeneousMedium, Medium, Scene};
use std::f32::consts::PI;

/// The medium's coefficients, ready for sampling.
#[derive(Clone, Copy, Debug)]
pub struct Homogeneous {
    /// Scattering coefficient.
    pub sigma_s: Vec3A,
    /// Extinction coefficient (absorption + scattering).
    pub sigma_t: Vec3A,
    /// Henyey–Greenstein asymmetry.
    pub g: f32,
}

/// Where a free flight ended.
#[derive(Clone, Copy, Debug)]
pub enum Flight {
    /// Scattered at distance `t`; multiply the throughput by `weight`
    /// (`σs e^(−σt t) / p(t)`).
    Scatter {
        /// Distance along the ray.
        t: f32,
        /// Throughput factor.
        weight: Vec3A,
    },
    /// Reached the surface at the end of the segment; multiply the
    /// throughput by `weight` (`e^(−σt d) / P(no scattering)`).
    Surface {
        /// Throughput factor.
        weight: Vec3A,
    },
}

impl Homogeneous {
    /// From the scene's coefficients.
    pub fn new(c: &VolumeCoefficients) -> Self {
        Self {
            sigma_s: c.scattering,
            sigma_t: c.absorption + c.scattering,
            g: c.g,
        }
    }

    /// From a scene medium (Mitsuba's homogeneous medium: `σs = albedo σt`;
    /// the isotropic phase function is Henyey–Greenstein with `g = 0`).
    pub fn of_medium(m: &HomogeneousMedium) -> Self {
        Self {
            sigma_s: m.sigma_s(),
            sigma_t: m.sigma_t,
            g: m.phase.asymmetry(),
        }
    }

    /// Transmittance over `d`: `exp(−σt d)`.
    pub fn transmittance(&self, d: f32) -> Vec3A {
        if d.is_infinite() {
            return Vec3A::select(self.sigma_t.cmpgt(Vec3A::ZERO), Vec3A::ZERO, Vec3A::ONE);
        }
        (-self.sigma_t * d).exp()
    }

    /// Samples a free flight along a segment of length `d_max` from the
    /// numbers `u_channel` and `u_distance`.
    pub fn sample_flight(&self, d_max: f32, u_channel: f32, u_distance: f32) -> Flight {
        let channel = ((u_channel * 3.0) as usize).min(2);
        let st = self.sigma_t[channel];
        let t = if st > 0.0 {
            -(1.0 - u_distance).ln() / st
        } else {
            f32::INFINITY
        };
        if t < d_max {
            let tr = self.transmittance(t);
            let pdf = (self.sigma_t * tr).element_sum() / 3.0;
            if pdf > 0.0 {
                return Flight::Scatter {
                    t,
                    weight: self.sigma_s * tr / pdf,
                };
            }
        }
        let tr = self.transmittance(d_max);
        let p_surface = tr.element_sum() / 3.0;
        Flight::Surface {
            weight: if p_surface > 0.0 { tr / p_surface } else { Vec3A::ZERO },
        }
    }

    /// Henyey–Greenstein phase function for the angle between `wo` and
    /// `wi` (both pointing away from the scattering point): its value with
    /// `cos θ = −wo·wi` (forward scattering when `wi` continues `−wo`).
    pub fn phase(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        henyey_greenstein(-wo.dot(wi), self.g)
    }

    /// Samples `wi` from the phase function around the direction `−wo`;
    /// the phase function's value is its density.
    pub fn sample_phase(&self, wo: Vec3A, u: Vec2) -> (Vec3A, f32) {
        let g = self.g;
        // Inverting the HG CDF (pbrt-v3 §15.2.3) for the cosine with the
        // forward direction: u = 0 gives 1, u = 1 gives −1.
        let cos = if g.abs() < 1e-3 {
            1.0 - 2.0 * u.x
        } else {
            let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
            (1.0 + g * g - s * s) / (2.0 * g)
        };
        let cos = cos.clamp(-1.0, 1.0);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        // Around the forward direction −wo: cos θ = −wo·wi.
        let frame = Frame::from_normal(-wo);
        let wi = frame.to_world(Vec3A::new(sin * phi.cos(), sin * phi.sin(), cos));
        (wi, henyey_greenstein(cos, g))
    }
}

/// The Henyey–Greenstein phase function (1941), normalised over the sphere:
/// `(1 − g²) / (4π (1 + g² − 2g cos θ)^(3/2))`.
pub fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(1e-12).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};
    use crate::math::sampling::uniform_sphere;

    fn water() -> Homogeneous {
        Homogeneous::new(&VolumeCoefficients {
            absorption: Vec3A::new(0.45, 0.06, 0.02),
            scattering: Vec3A::new(0.1, 0.12, 0.14),
            g: 0.8,
        })
    }

    #[test]
    fn phase_function_is_normalised_and_sampled_by_its_density() {
        let mut rng = Rng::new(1, Domain::Analysis, 0, 0);
        for g in [-0.5f32, 0.0, 0.3, 0.85] {
            let m = Homogeneous { g, ..water() };
            let wo = Vec3A::new(0.3, -0.4, 0.866).normalize();
            // ∫ p dω = 1 by uniform sphere sampling.
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|_| (m.phase(wo, uniform_sphere(rng.vec2())) * 4.0 * PI) as f64)
                .sum::<f64>()
                / n as f64;
            assert!((integral - 1.0).abs() < 0.03, "g {g}: {integral}");
            // Sampled directions: mean cosine with the forward direction is g.
            let mean_cos: f64 = (0..n)
                .map(|_| {
                    let (wi, pdf) = m.sample_phase(wo, rng.vec2());
                    assert!((pdf - m.phase(wo, wi)).abs() <= 1e-3 * pdf.max(1.0));
                    (-wo).dot(wi) as f64
                })
                .sum::<f64>()
                / n as f64;
            assert!((mean_cos - g as f64).abs() < 0.01, "g {g}: mean cos {mean_cos}");
        }
    }

    #[test]
    fn free_flight_weights_estimate_transmittance_and_scattering() {
        // E[weight on reaching the surface] = exp(−σt d) per channel, and
        // E[Σ scatter weights / σs] = ∫0^d e^(−σt t) dt.
        let m = water();
        let d = 3.0;
        let mut rng = Rng::new(2, Domain::Analysis, 0, 0);
        let n = 400_000;
        let (mut surface, mut scatter) = (Vec3A::ZERO, Vec3A::ZERO);
        for _ in 0..n {
            match m.sample_flight(d, rng.f32(), rng.f32()) {
                Flight::Surface { weight } => surface += weight,
                Flight::Scatter { weight, .. } => scatter += weight / m.sigma_s,
            }
        }
        let (surface, scatter) = (surface / n as f32, scatter / n as f32);
        let tr = m.transmittance(d);
        let integral = (Vec3A::ONE - tr) / m.sigma_t;
        for c in 0..3 {
            assert!((surface[c] - tr[c]).abs() < 0.01 * tr[c].max(0.05), "{surface} vs {tr}");
            assert!(
                (scatter[c] - integral[c]).abs() < 0.02 * integral[c],
                "{scatter} vs {integral}"
            );
        }
    }
}

/// The water volume as the path integrator and the photon tracer see it:
/// the scene's `[medium]` coefficients and where the water is.
#[derive(Clone, Debug)]
pub struct WaterVolume<'a> {
    /// The scene's medium.
    pub medium: &'a Medium,
    /// Its coefficients.
    pub coefficients: Homogeneous,
    /// The box the water cannot leave: the surface's (x, z) extent, from the
    /// floor of the scene up to the highest crest.
    bounds: Aabb,
}

impl<'a> WaterVolume<'a> {
    /// The scene's water, when it has a medium with coefficients.
    pub fn of(scene: &'a Scene) -> Option<Self> {
        let medium = scene.water_medium.as_ref()?;
        let coefficients = Homogeneous::new(medium.volume.as_ref()?);
        let mut bounds = medium.region;
        bounds.max.y = medium.surface.center.y + medium.surface.max_amplitude();
        Some(Self {
            medium,
            coefficients,
            bounds,
        })
    }

    /// True when `p` is in the water.
    pub fn contains(&self, p: Vec3A) -> bool {
        self.medium.contains(p)
    }

    /// Distance along `ray` (unit direction) at which it leaves the water's
    /// box (the surface is met as a hit before; the box's sides and floor
    /// end the medium where no geometry does).
    pub fn exit_distance(&self, ray: &Ray) -> f32 {
        let inv = Vec3A::ONE / ray.dir;
        match self.bounds.intersect_interval(ray, inv, f32::INFINITY) {
            Some((_, t1)) => t1.max(0.0),
            None => 0.0,
        }
    }
}

/// Whether a path is in the water, across the interfaces it crosses: the
/// water object's surface toggles it; entering another refracting object
/// (glass in the water) leaves the water until the path leaves that object.
#[derive(Clone, Copy, Debug)]
pub struct MediumTracker {
    inside: bool,
    saved: [bool; 8],
    depth: usize,
}

impl MediumTracker {
    /// A path starting in the water (`inside`) or not.
    pub fn new(inside: bool) -> Self {
        Self {
            inside,
            saved: [false; 8],
            depth: 0,
        }
    }

    /// True while the path is in the water.
    pub fn inside(&self) -> bool {
        self.inside
    }

    /// The path refracted through `object`, entering it (travelling against
    /// its outward geometric normal) or leaving it.
    pub fn transmit(&mut self, object: u32, water: u32, entering: bool) {
        if object == water {
            self.inside = entering;
        } else if entering {
            if self.depth < self.saved.len() {
                self.saved[self.depth] = self.inside;
            }
            self.depth += 1;
            self.inside = false;
        } else if self.depth > 0 {
            self.depth -= 1;
            self.inside = self.saved.get(self.depth).copied().unwrap_or(false);
        }
    }
}
