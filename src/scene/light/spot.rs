//! The spot light: a point light whose intensity falls off inside a cone,
//! with Mitsuba's falloff or glTF's.

use crate::math::{Frame, Vec3A};
use std::f32::consts::PI;

/// How a spot light's intensity falls from `beam_width` to `cutoff`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SpotFalloff {
    /// Mitsuba 3's `spot`: linear in the angle θ, `(cutoff − θ) / (cutoff − beam_width)`.
    #[default]
    Mitsuba,
    /// glTF's `KHR_lights_punctual`: linear in cos θ between cos(outer) and
    /// cos(inner), squared: `t = (cos θ − cos outer) / (cos inner − cos outer)`, `t²`.
    Gltf,
}

impl SpotFalloff {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            SpotFalloff::Mitsuba => "mitsuba",
            SpotFalloff::Gltf => "gltf",
        }
    }

    /// The falloff named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [SpotFalloff::Mitsuba, SpotFalloff::Gltf]
            .into_iter()
            .find(|f| f.name() == name)
    }
}

/// A spot light: full intensity within `beam_width` of the axis, zero
/// beyond `cutoff`, and its [`SpotFalloff`] between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3A,
    /// Unit axis of the cone (the direction the light points in).
    pub axis: Vec3A,
    /// Colour × intensity on the axis (W/sr per channel).
    pub intensity: Vec3A,
    /// Half-angle of the cone, radians, in (0, π/2].
    pub cutoff: f32,
    /// Half-angle of full intensity, radians, in [0, cutoff].
    pub beam_width: f32,
    /// The ramp between `beam_width` and `cutoff`.
    pub falloff: SpotFalloff,
}

impl SpotLight {
    /// Cosine of the cutoff angle.
    #[inline]
    pub fn cos_cutoff(&self) -> f32 {
        self.cutoff.cos()
    }

    /// The frame whose z is the axis.
    pub fn frame(&self) -> Frame {
        Frame::from_normal(self.axis)
    }

    /// The falloff toward unit direction `d` leaving the light, in [0, 1].
    #[inline]
    pub fn falloff(&self, d: Vec3A) -> f32 {
        let cos = d.dot(self.axis);
        if cos <= self.cos_cutoff() {
            return 0.0;
        }
        let cos_inner = self.beam_width.cos();
        if cos >= cos_inner {
            return 1.0;
        }
        match self.falloff {
            SpotFalloff::Mitsuba => {
                ((self.cutoff - cos.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width)).clamp(0.0, 1.0)
            }
            SpotFalloff::Gltf => {
                // KHR_lights_punctual's recommended angular attenuation.
                let cos_outer = self.cos_cutoff();
                let t = ((cos - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
                t * t
            }
        }
    }

    /// Total power `I ∫ falloff dω = 2π I ∫₀^cutoff falloff(θ) sin θ dθ`:
    /// the full cone to `beam_width`, plus the ramp, integrated exactly.
    /// Mitsuba's: `∫ (c − θ) sin θ dθ = (θ − c) cos θ − sin θ`; glTF's, in
    /// μ = cos θ: `∫_{μo}^{μi} ((μ − μo)/(μi − μo))² dμ = (μi − μo)/3`.
    pub fn power(&self) -> Vec3A {
        let (b, c) = (self.beam_width, self.cutoff);
        let core = 1.0 - b.cos();
        let ramp = if c > b {
            match self.falloff {
                SpotFalloff::Mitsuba => {
                    // ∫_b^c (c − θ)/(c − b) sin θ dθ
                    let g = |t: f32| (t - c) * t.cos() - t.sin();
                    (g(c) - g(b)) / (c - b)
                }
                SpotFalloff::Gltf => ((b.cos() - c.cos()) / 3.0).max(0.0),
            }
        } else {
            0.0
        };
        self.intensity * (2.0 * PI * (core + ramp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `2π ∫₀^{π/2} falloff(θ) sin θ dθ` by the midpoint rule.
    fn integrated(s: &SpotLight) -> f64 {
        let n = 20_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
            let d = Vec3A::new(t.sin() as f32, t.cos() as f32, 0.0);
            sum += f64::from(s.falloff(d)) * t.sin() * (std::f64::consts::FRAC_PI_2 / n as f64);
        }
        2.0 * std::f64::consts::PI * sum
    }

    #[test]
    fn power_is_the_integral_of_the_falloff() {
        for falloff in [SpotFalloff::Mitsuba, SpotFalloff::Gltf] {
            for (cutoff, beam_width) in [(0.6, 0.25), (1.5, 0.0), (0.3, 0.29)] {
                let s = SpotLight {
                    position: Vec3A::ZERO,
                    axis: Vec3A::Y,
                    intensity: Vec3A::ONE,
                    cutoff,
                    beam_width,
                    falloff,
                };
                let expected = integrated(&s);
                assert!(
                    (f64::from(s.power().x) - expected).abs() < 1e-4 * expected,
                    "{falloff:?} {cutoff} {beam_width}: {} {expected}",
                    s.power().x
                );
                assert_eq!(s.falloff(Vec3A::Y), 1.0);
                assert_eq!(s.falloff(Vec3A::X), 0.0);
            }
        }
    }

    #[test]
    fn gltf_falloff_is_the_squared_ramp_in_cosine() {
        let s = SpotLight {
            position: Vec3A::ZERO,
            axis: Vec3A::Y,
            intensity: Vec3A::ONE,
            cutoff: 0.8,
            beam_width: 0.4,
            falloff: SpotFalloff::Gltf,
        };
        // Halfway in cos θ between cos 0.8 and cos 0.4: a quarter.
        let mid = 0.5 * (0.8f32.cos() + 0.4f32.cos());
        let d = Vec3A::new((1.0 - mid * mid).sqrt(), mid, 0.0);
        assert!((s.falloff(d) - 0.25).abs() < 1e-5, "{}", s.falloff(d));
        // Mitsuba's is linear in the angle: a different value there.
        let m = SpotLight {
            falloff: SpotFalloff::Mitsuba,
            ..s
        };
        assert!((m.falloff(d) - (0.8 - mid.acos()) / 0.4).abs() < 1e-5);
    }
}
