//! Display transform: exposure, then a tone curve (ACES filmic or a clamp),
//! then the sRGB transfer function and 8-bit quantisation.

use super::Film;
use crate::math::{Mat3A, Vec3, Vec3A};

/// sRGB (linear, D65) → the ACES fit's working space: Stephen Hill's
/// `ACESInputMat` (sRGB → XYZ → D65→D60 → AP1 → RRT_SAT), from his fit
/// published in MJP's BakingLab (`ACES.hlsl`, 2016). Rows as in the HLSL
/// source, hence `from_cols(..).transpose()`.
fn aces_input_matrix() -> Mat3A {
    Mat3A::from_cols(
        Vec3A::new(0.59719, 0.35458, 0.04823),
        Vec3A::new(0.07600, 0.90834, 0.01566),
        Vec3A::new(0.02840, 0.13383, 0.83777),
    )
    .transpose()
}

/// Hill's `ACESOutputMat` (ODT_SAT → XYZ → D60→D65 → sRGB), rows as in the source.
fn aces_output_matrix() -> Mat3A {
    Mat3A::from_cols(
        Vec3A::new(1.60475, -0.53108, -0.07367),
        Vec3A::new(-0.10208, 1.10813, -0.00605),
        Vec3A::new(-0.00327, -0.07276, 1.07602),
    )
    .transpose()
}

/// Hill's rational fit of the ACES RRT + sRGB ODT curve (`RRTAndODTFit`).
#[inline]
fn rrt_and_odt_fit(v: Vec3A) -> Vec3A {
    let a = v * (v + 0.0245786) - 0.000090537;
    let b = v * (0.983729 * v + 0.432951) + 0.238081;
    a / b
}

/// ACES filmic tone curve, **Stephen Hill's fitted RRT + ODT** ("ACESFitted",
/// BakingLab 2016): input matrix, per-channel rational fit, output matrix,
/// saturate. Takes scene-linear sRGB, returns display-linear sRGB in [0, 1]
/// (the sRGB OETF is applied afterwards by [`srgb_oetf`]). Chosen over
/// Narkowicz's 2015 one-line fit because it keeps the RRT's hue and
/// saturation handling (the "sweeteners") that Narkowicz drops.
pub fn aces_fitted(c: Vec3) -> Vec3 {
    let v = aces_input_matrix() * Vec3A::from(c);
    let v = aces_output_matrix() * rrt_and_odt_fit(v);
    Vec3::from(v.clamp(Vec3A::ZERO, Vec3A::ONE))
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) of one
/// display-linear value in [0, 1] (values outside are clamped first).
#[inline]
pub fn srgb_oetf(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Display-linear value in [0, 1] of a scene-linear pixel: exposure
/// (`2^stops`) first, then the tone curve. NaN inputs become 0.
pub fn tone_map(c: Vec3, tone: ToneMap, exposure_stops: f32) -> Vec3 {
    let c = c * exposure_stops.exp2();
    let c = Vec3::select(c.cmpeq(c), c, Vec3::ZERO); // NaN → 0
    match tone {
        ToneMap::Aces => aces_fitted(c),
        ToneMap::Clamp => c.clamp(Vec3::ZERO, Vec3::ONE),
    }
}

/// Quantises a display-linear value in [0, 1] to 8-bit sRGB (rounding to nearest).
#[inline]
pub fn encode_srgb8(c: Vec3) -> [u8; 3] {
    let q = |x: f32| (srgb_oetf(x) * 255.0 + 0.5) as u8;
    [q(c.x), q(c.y), q(c.z)]
}

/// Tone mapping applied before 8-bit output.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneMap {
    /// ACES filmic curve.
    #[default]
    Aces,
    /// Clamp to [0, 1].
    Clamp,
}

/// How the linear film becomes a displayable image (the scene's
/// `tone_map` and `exposure`): display only, never part of a render's
/// fingerprint.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutputSettings {
    /// Tone curve for 8-bit output.
    pub tone_map: ToneMap,
    /// Exposure in stops (scales linear radiance by 2^exposure before tone mapping).
    pub exposure: f32,
}

/// The whole film as interleaved 8-bit sRGB, with the settings' tone
/// mapping and exposure.
pub fn tonemap_to_srgb8(film: &Film, settings: &OutputSettings) -> Vec<u8> {
    film.pixels
        .iter()
        .flat_map(|&p| encode_srgb8(tone_map(p, settings.tone_map, settings.exposure)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aces_maps_black_to_black_and_saturates_toward_white() {
        assert_eq!(aces_fitted(Vec3::ZERO), Vec3::ZERO);
        let bright = aces_fitted(Vec3::splat(1.0e4));
        assert!(bright.min_element() > 0.99, "{bright}");
        // Middle grey 0.18 lands in the lower-middle of the display range
        // (Hill's fit gives ≈ 0.106), not clamped, not crushed.
        let grey = aces_fitted(Vec3::splat(0.18));
        assert!(grey.x > 0.08 && grey.x < 0.3, "{grey}");
        assert!((grey.x - grey.y).abs() < 1e-3 && (grey.y - grey.z).abs() < 1e-3);
    }

    #[test]
    fn aces_is_monotone_and_bounded() {
        // Grey ramp and scaled colours over 8 decades: never decreasing, in [0, 1].
        let colours = [
            Vec3::ONE,
            Vec3::new(1.0, 0.2, 0.1),
            Vec3::new(0.1, 0.9, 0.3),
            Vec3::new(0.2, 0.3, 1.0),
        ];
        for base in colours {
            let mut prev = aces_fitted(Vec3::ZERO);
            for i in 0..=400 {
                let k = 10f32.powf(-4.0 + 8.0 * i as f32 / 400.0);
                let out = aces_fitted(base * k);
                assert!(out.min_element() >= 0.0 && out.max_element() <= 1.0, "{out}");
                // Luminance-like sum is monotone for every colour; each
                // channel too for the grey ramp.
                assert!(out.element_sum() >= prev.element_sum() - 1e-6, "{base} × {k}");
                if base == Vec3::ONE {
                    assert!(out.cmpge(prev - Vec3::splat(1e-6)).all(), "{k}: {out} < {prev}");
                }
                prev = out;
            }
        }
    }

    #[test]
    fn srgb_endpoints_and_linear_toe() {
        assert_eq!(srgb_oetf(0.0), 0.0);
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_oetf(0.002) - 0.02584).abs() < 1e-6);
        // Continuous at the break point.
        let below = srgb_oetf(0.003_130_8);
        let above = srgb_oetf(0.003_130_9);
        assert!((above - below).abs() < 1e-4);
        assert!((srgb_oetf(0.18) - 0.4613).abs() < 1e-3);
        assert_eq!(encode_srgb8(Vec3::ZERO), [0, 0, 0]);
        assert_eq!(encode_srgb8(Vec3::ONE), [255, 255, 255]);
        assert_eq!(encode_srgb8(Vec3::splat(2.0)), [255, 255, 255]);
    }

    #[test]
    fn exposure_is_applied_before_the_curve_and_nan_is_black() {
        let c = Vec3::splat(0.25);
        assert_eq!(tone_map(c, ToneMap::Clamp, 2.0), Vec3::ONE);
        assert_eq!(tone_map(c, ToneMap::Clamp, -1.0), Vec3::splat(0.125));
        assert_eq!(tone_map(c * 4.0, ToneMap::Aces, -2.0), aces_fitted(c));
        assert_eq!(tone_map(Vec3::splat(f32::NAN), ToneMap::Aces, 0.0), Vec3::ZERO);
    }
}
