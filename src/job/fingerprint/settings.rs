//! The render settings' encoding: what changes samples (not the tone map,
//! exposure or denoising, which act on the finished image).

use super::encoder::{Encoder, Fingerprint};
use crate::geometry::{TriangleTest, WaterSurface, Wave};
use crate::math::{SamplerKind, Vec3A};
use crate::scene::medium::VolumeCoefficients;
use crate::scene::{
    AdaptiveGoal, CausticsMode, GatherMode, IntegratorKind, Medium, PhotonSettings, RenderSettings, SampleSharing,
};

/// Encodes `settings` with the scene's `ambient` light and water
/// `medium`, in the order the settings held them before they moved to the
/// scene (the encoding, and so every fingerprint, is unchanged).
pub(super) fn encode_settings(e: &mut Encoder, settings: &RenderSettings, ambient: Vec3A, medium: Option<&Medium>) {
    {
        let RenderSettings {
            width,
            height,
            spp,
            max_depth,
            integrator,
            noise_threshold,
            min_spp,
            adaptive_goal,
            sampler: _,
            seed,
            // Display only: they act on the finished image.
            output: _,
            denoise: _,
            denoise_quality: _,
            triangle_test,
            sharing,
            photons,
            hide_emitters,
        } = settings;
        e.tag("settings");
        e.u32(*width);
        e.u32(*height);
        e.u32(*spp);
        e.option(max_depth.as_ref(), |e, d| e.u32(*d));
        e.u8(match integrator {
            IntegratorKind::Whitted => 0,
            IntegratorKind::Path => 1,
        });
        e.option(noise_threshold.as_ref(), |e, t| e.f32(*t));
        e.u32(*min_spp);
        e.u8(match adaptive_goal {
            AdaptiveGoal::Pixel => 0,
            AdaptiveGoal::Image => 1,
        });
        // The sampler in effect (an unset one is the integrator's default).
        e.u8(match settings.sampler_kind() {
            SamplerKind::Independent => 0,
            SamplerKind::Sobol => 1,
        });
        e.u64(*seed);
        e.put(&ambient);
        e.u8(match triangle_test {
            TriangleTest::Watertight => 0,
            TriangleTest::MollerTrumbore => 1,
        });
        e.u8(match sharing {
            SampleSharing::Spread => 0,
            SampleSharing::Split => 1,
        });
        e.put(photons);
        e.option(medium, |e, m| e.put(m));
        e.bool(*hide_emitters);
    }
}

impl Fingerprint for PhotonSettings {
    fn encode(&self, e: &mut Encoder) {
        let PhotonSettings {
            count,
            k,
            max_radius,
            cone_k,
            gather,
            caustics,
            progressive,
            alpha,
        } = self;
        e.tag("photons");
        e.u64(*count);
        e.u32(*k);
        e.option(max_radius.as_ref(), |e, r| e.f32(*r));
        e.f32(*cone_k);
        e.u8(match gather {
            GatherMode::Direct => 0,
            GatherMode::Precomputed => 1,
        });
        e.u8(match caustics {
            CausticsMode::Path => 0,
            CausticsMode::Map => 1,
        });
        // α shrinks the radius only in progressive photon mapping.
        e.option(progressive.then_some(alpha), |e, a| e.f32(*a));
    }
}

/// The TOML water's fog and medium.
impl Fingerprint for Medium {
    fn encode(&self, e: &mut Encoder) {
        let Medium {
            density,
            colour,
            region,
            volume,
            surface,
            boundary,
        } = self;
        e.tag("water medium");
        e.f32(*density);
        e.put(colour);
        e.put(&region.min);
        e.put(&region.max);
        e.option(volume.as_ref(), |e, v| {
            let VolumeCoefficients {
                absorption,
                scattering,
                g,
            } = v;
            e.put(absorption);
            e.put(scattering);
            e.f32(*g);
        });
        e.put(surface);
        e.u32(*boundary);
    }
}

impl Fingerprint for WaterSurface {
    fn encode(&self, e: &mut Encoder) {
        let WaterSurface {
            center,
            size,
            resolution,
            waves,
        } = self;
        e.tag("water surface");
        e.put(center);
        e.put(size);
        e.u32(resolution.0);
        e.u32(resolution.1);
        e.u64(waves.len() as u64);
        for w in waves {
            let Wave {
                amplitude,
                wavelength,
                direction,
                phase,
            } = w;
            e.f32(*amplitude);
            e.f32(*wavelength);
            e.put(direction);
            e.f32(*phase);
        }
    }
}
