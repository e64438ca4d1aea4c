//! Spectra in Mitsuba scenes reduced to linear sRGB the way Mitsuba 3's RGB
//! variants reduce them, so that a scene written with `<spectrum>` values
//! renders with the colours Mitsuba gives it.

use super::cie::{CIE_MAX, CIE_MIN, CIE_STEP, CIE_TABLE};
use crate::math::Vec3A;

/// What a spectrum stands for: Mitsuba reduces reflectances under D65 and
/// clamps them to [0, 1], and emission as it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumUse {
    /// An albedo or transmittance in [0, 1].
    Reflectance,
    /// Radiance, intensity or irradiance.
    Emission,
    /// Any other unbounded value (an index of refraction).
    Unbounded,
}

/// Mitsuba's `MI_CIE_Y_NORMALIZATION`: `1 / ∫ ȳ(λ) dλ` over its table.
const CIE_Y_NORMALIZATION: f32 = 0.009_367_659;

/// A uniform spectrum of value 1 as Mitsuba 3.9's RGB variants read it on an
/// emitter: an equal-energy spectrum in sRGB (not grey). Measured with
/// `mi.traverse` on a point light of `<spectrum value="1">`.
const UNIFORM_EMISSION: Vec3A = Vec3A::new(1.204_793_9, 0.948_291, 0.908_916_06);

/// The colour matching functions and D65 at `w` nm (linear between the
/// nodes, zero outside the table, as `mi.cie1931_xyz` and `mi.cie_d65`).
fn cie(w: f32) -> [f32; 4] {
    if !(CIE_MIN..=CIE_MAX).contains(&w) {
        return [0.0; 4];
    }
    let t = (w - CIE_MIN) / CIE_STEP;
    let i = (t.floor() as usize).min(CIE_TABLE.len() - 2);
    let f = t - i as f32;
    let (a, b) = (CIE_TABLE[i], CIE_TABLE[i + 1]);
    std::array::from_fn(|k| a[k] * (1.0 - f) + b[k] * f)
}

/// CIE XYZ to linear sRGB (Mitsuba's `xyz_to_srgb`).
fn xyz_to_srgb(xyz: [f32; 3]) -> Vec3A {
    let [x, y, z] = xyz;
    Vec3A::new(
        3.240_479 * x - 1.53715 * y - 0.498_535 * z,
        -0.969_256 * x + 1.875_991 * y + 0.041_556 * z,
        0.055_648 * x - 0.204_043 * y + 1.057_311 * z,
    )
}

/// The sRGB colour of a piecewise-linear spectrum given at increasing
/// `wavelengths` (nm), as Mitsuba's `spectrum_list_to_srgb`: 1000 samples
/// over [360, 830] nm, zero outside the given range, reflectances weighted
/// by D65 and clamped to [0, 1], negative components clamped to 0.
/// `wavelengths` has at least two values, strictly increasing.
pub fn spectrum_to_srgb(wavelengths: &[f32], values: &[f32], usage: SpectrumUse) -> Vec3A {
    const STEPS: usize = 1000;
    let d65 = usage == SpectrumUse::Reflectance;
    let (first, last) = (wavelengths[0], wavelengths[wavelengths.len() - 1]);
    let mut xyz = [0.0f32; 3];
    for i in 0..STEPS {
        let w = CIE_MIN + (i as f32 / (STEPS - 1) as f32) * (CIE_MAX - CIE_MIN);
        if w < first || w > last {
            continue;
        }
        // The last interval whose start is at most `w`.
        let index = wavelengths.partition_point(|&x| x <= w).clamp(1, wavelengths.len() - 1) - 1;
        let (w0, w1, v0, v1) = (
            wavelengths[index],
            wavelengths[index + 1],
            values[index],
            values[index + 1],
        );
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let c = cie(w);
        let weight = v * if d65 { c[3] } else { 1.0 };
        for k in 0..3 {
            xyz[k] += c[k] * weight;
        }
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f32 * CIE_Y_NORMALIZATION;
    let rgb = xyz_to_srgb(xyz.map(|c| c * scale)).max(Vec3A::ZERO);
    if usage == SpectrumUse::Reflectance {
        rgb.min(Vec3A::ONE)
    } else {
        rgb
    }
}

/// The sRGB colour of a uniform spectrum `value`.
pub fn uniform_to_srgb(value: f32, usage: SpectrumUse) -> Vec3A {
    match usage {
        SpectrumUse::Emission => UNIFORM_EMISSION * value,
        SpectrumUse::Reflectance | SpectrumUse::Unbounded => Vec3A::splat(value),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3A, b: [f32; 3]) -> bool {
        (a - Vec3A::from(b)).abs().max_element() <= 2e-5 * Vec3A::from(b).abs().max_element().max(1.0)
    }

    /// Values printed by `mi.spectrum_list_to_srgb` (mitsuba 3.9.1).
    #[test]
    fn lists_reduce_as_mitsuba_reduces_them() {
        let w = [400.0, 500.0, 600.0, 700.0];
        let emission = spectrum_to_srgb(&w, &[0.0, 8.0, 15.6, 18.4], SpectrumUse::Emission);
        assert!(close(emission, [20.7108, 10.8546, 2.77115]), "{emission}");
        let albedo = spectrum_to_srgb(&w, &[0.04, 0.5, 0.8, 0.642], SpectrumUse::Reflectance);
        assert!(close(albedo, [0.822203, 0.642173, 0.240009]), "{albedo}");
        let flat = spectrum_to_srgb(&[360.0, 830.0], &[1.0, 1.0], SpectrumUse::Emission);
        assert!(close(flat, [1.20488, 0.948229, 0.909267]), "{flat}");
        let grey = spectrum_to_srgb(&[400.0, 700.0], &[0.5, 0.5], SpectrumUse::Reflectance);
        assert!(close(grey, [0.497671, 0.499878, 0.497455]), "{grey}");
    }

    #[test]
    fn reflectances_are_clamped_and_uniform_values_follow_their_use() {
        let bright = spectrum_to_srgb(&[400.0, 700.0], &[3.0, 3.0], SpectrumUse::Reflectance);
        assert_eq!(bright.max_element(), 1.0);
        assert_eq!(uniform_to_srgb(0.3, SpectrumUse::Reflectance), Vec3A::splat(0.3));
        assert!(close(
            uniform_to_srgb(5.0, SpectrumUse::Emission),
            [6.02397, 4.74146, 4.54458]
        ));
    }
}
