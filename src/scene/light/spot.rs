//! The spot light: a point light whose intensity falls off inside a cone.

use crate::math::{Frame, Vec3A};
use std::f32::consts::PI;

/// A spot light with Mitsuba 3's `spot` falloff: full intensity within
/// `beam_width` of the axis, zero beyond `cutoff`, and linear in the angle
/// between them.
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
        if cos >= self.beam_width.cos() {
            return 1.0;
        }
        ((self.cutoff - cos.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width)).clamp(0.0, 1.0)
    }

    /// Total power `I ∫ falloff dω = 2π I ∫₀^cutoff falloff(θ) sin θ dθ`:
    /// the full cone to `beam_width`, plus the ramp, integrated exactly
    /// (`∫ (c − θ) sin θ dθ = (θ − c) cos θ − sin θ`).
    pub fn power(&self) -> Vec3A {
        let (b, c) = (self.beam_width, self.cutoff);
        let core = 1.0 - b.cos();
        let ramp = if c > b {
            // ∫_b^c (c − θ)/(c − b) sin θ dθ
            let g = |t: f32| (t - c) * t.cos() - t.sin();
            (g(c) - g(b)) / (c - b)
        } else {
            0.0
        };
        self.intensity * (2.0 * PI * (core + ramp))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_is_the_integral_of_the_falloff() {
        let s = SpotLight {
            position: Vec3A::ZERO,
            axis: Vec3A::Y,
            intensity: Vec3A::ONE,
            cutoff: 0.6,
            beam_width: 0.25,
        };
        // Midpoint rule over θ.
        let n = 20_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
            let d = Vec3A::new(t.sin() as f32, t.cos() as f32, 0.0);
            sum += f64::from(s.falloff(d)) * t.sin() * (std::f64::consts::FRAC_PI_2 / n as f64);
        }
        let expected = 2.0 * std::f64::consts::PI * sum;
        assert!(
            (f64::from(s.power().x) - expected).abs() < 1e-4 * expected,
            "{} {expected}",
            s.power().x
        );
        assert_eq!(s.falloff(Vec3A::Y), 1.0);
        assert_eq!(s.falloff(Vec3A::X), 0.0);
    }
}
