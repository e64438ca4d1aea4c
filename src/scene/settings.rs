//! Render settings: how a scene is rendered (image size, samples, the
//! integrator and its photon map, the output), apart from what the scene
//! holds. Every front end fills them from its file; the command line's
//! overrides (`job::Overrides::apply`) change them in one place.

use crate::film::denoise::DenoiseQuality;
use crate::film::OutputSettings;
use crate::geometry::TriangleTest;
use crate::math::SamplerKind;

/// How secondary work is shared between a pixel's samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleSharing {
    /// spp > 1: each sample takes one stratum of the area lights' shadow
    /// samples and one Fresnel-weighted branch at dielectrics.
    Spread,
    /// Every sample casts all shadow rays and follows both branches.
    Split,
}

/// Specular bounces the Whitted integrator follows when the scene sets no
/// `max_depth`.
pub const DEFAULT_WHITTED_DEPTH: u32 = 8;

/// What adaptive sampling's noise threshold `E` bounds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AdaptiveGoal {
    /// Every pixel: a pixel stops once its estimated relative error is at
    /// most `E` (equal error everywhere, as production renderers do).
    #[default]
    Pixel,
    /// The image's mean relative squared error per sample: a pixel with `n`
    /// samples stops once its error is at most `E·√(n / min_spp)`, which
    /// gives each pixel samples in proportion to its standard deviation,
    /// the allocation of least total variance for a given sample count
    /// (Neyman 1934). Fewer samples than `Pixel` for the same relMSE when
    /// a few pixels (caustics, glass edges) hold most of the noise.
    Image,
}

/// Samples every pixel takes before adaptive sampling may stop it.
pub const DEFAULT_MIN_SPP: u32 = 16;

/// The light transport algorithm (`[render] integrator`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorKind {
    /// The original report's model: direct light, mirrors and glass,
    /// photon-mapped caustics, an ambient term.
    #[default]
    Whitted,
    /// Physically based path tracing with next-event estimation and MIS.
    Path,
}

impl IntegratorKind {
    /// Name as in scene files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "whitted",
            IntegratorKind::Path => "path",
        }
    }
}

impl RenderSettings {
    /// The sampler this render uses.
    pub fn sampler_kind(&self) -> SamplerKind {
        self.sampler.unwrap_or(match self.integrator {
            IntegratorKind::Whitted => SamplerKind::Independent,
            IntegratorKind::Path => SamplerKind::Sobol,
        })
    }

    /// Specular bounces the Whitted integrator follows.
    pub fn whitted_depth(&self) -> u32 {
        self.max_depth.unwrap_or(DEFAULT_WHITTED_DEPTH)
    }
}

/// Render settings (the `[render]` table).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum number of bounces; `None`: the integrator's default
    /// ([`DEFAULT_WHITTED_DEPTH`] specular bounces for Whitted, unbounded with
    /// Russian roulette for path tracing).
    pub max_depth: Option<u32>,
    /// Light transport algorithm.
    pub integrator: IntegratorKind,
    /// Adaptive sampling: pixels stop once their estimated relative error
    /// is at most this (`spp` is then the most a pixel takes).
    pub noise_threshold: Option<f32>,
    /// Samples every pixel takes before adaptive sampling stops any.
    pub min_spp: u32,
    /// What adaptive sampling's threshold bounds.
    pub adaptive_goal: AdaptiveGoal,
    /// Sample generator; `None`: the integrator's default (Sobol for path
    /// tracing, independent for Whitted, whose own strata keep the original
    /// images).
    pub sampler: Option<SamplerKind>,
    /// Seed of every random stream.
    pub seed: u64,
    /// Tone mapping and exposure of the 8-bit output.
    pub output: OutputSettings,
    /// Ray–triangle test.
    pub triangle_test: TriangleTest,
    /// Sample sharing (spp > 1).
    pub sharing: SampleSharing,
    /// Photon map settings (the `[photons]` table).
    pub photons: PhotonSettings,
    /// Emitters seen directly by the camera are black: lights, emitting
    /// surfaces and the environment light the scene but do not appear in
    /// it (Mitsuba's `hide_emitters`; `[render] hide_emitters`). They still
    /// appear in reflections and refractions.
    pub hide_emitters: bool,
    /// Denoise the final image with Open Image Denoise (`[render] denoise`,
    /// `--denoise`): what is written, not what is sampled (not in the
    /// fingerprint).
    pub denoise: bool,
    /// The denoising filter's quality (`[render] denoise_quality`,
    /// `--denoise-quality`; not in the fingerprint).
    pub denoise_quality: DenoiseQuality,
}

/// Photon map settings (the `[photons]` table). The photon pass runs only
/// when the scene has a specular caster (see `integrator::plan`).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photons emitted (paths traced from the lights); 0 disables the pass.
    pub count: u64,
    /// Photons gathered per estimate (the `k` of the k-nearest search).
    pub k: u32,
    /// Largest gather radius; `None`: 2% of the scene bounds' diagonal.
    pub max_radius: Option<f32>,
    /// Jensen's cone-filter constant `k_c` (≥ 1): weight `1 − d/(k_c r)`.
    pub cone_k: f32,
    /// How shading points evaluate the estimate.
    pub gather: GatherMode,
    /// How the path integrator finds caustics (the Whitted integrator
    /// always uses the map).
    pub caustics: CausticsMode,
    /// Progressive photon mapping (Knaus & Zwicker 2011): every sample
    /// index of a pixel gathers from its own map of `count / spp` photons
    /// within a radius that shrinks from sample to sample
    /// (`integrator::photon::progressive`).
    pub progressive: bool,
    /// Knaus & Zwicker's `α ∈ (0, 1)`: the fraction of the photons within
    /// a radius kept by the next, `r_{i+1}² = r_i² (i + α)/(i + 1)`.
    pub alpha: f32,
}

/// How the path integrator finds caustics (`[photons] caustics`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CausticsMode {
    /// As paths: unbiased, slow to converge for small lights seen through
    /// glass or water.
    #[default]
    Path,
    /// From a photon map of light → specular → diffuse (L S+ D) paths,
    /// added at the camera path's non-specular vertices, plus a
    /// volumetric map of light scattered in the water after a specular
    /// bounce (L S+ V); path tracing then leaves those paths out.
    Map,
}

/// Default `[photons] alpha` of progressive photon mapping: 2/3, which
/// Knaus & Zwicker (2011, §4.3) find balances the bias and variance of the
/// estimate asymptotically.
pub const DEFAULT_PPM_ALPHA: f32 = 2.0 / 3.0;

/// How the caustic estimate is evaluated at shading points (`[photons] gather`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GatherMode {
    /// A k-nearest cone-filter gather at every shading point.
    Direct,
    /// The estimate precomputed once at every 8th stored photon; shading
    /// points interpolate their nearest sites (normal check, direct gather as
    /// fallback: Christensen 1999, "Faster Photon Map Global Illumination").
    #[default]
    Precomputed,
}

impl Default for PhotonSettings {
    fn default() -> Self {
        Self {
            count: 1_000_000,
            k: 64,
            max_radius: None,
            cone_k: 1.1,
            gather: GatherMode::Precomputed,
            caustics: CausticsMode::Path,
            progressive: false,
            alpha: DEFAULT_PPM_ALPHA,
        }
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            spp: 1,
            max_depth: None,
            integrator: IntegratorKind::Whitted,
            noise_threshold: None,
            min_spp: DEFAULT_MIN_SPP,
            adaptive_goal: AdaptiveGoal::Pixel,
            sampler: None,
            seed: 0,
            output: OutputSettings::default(),
            triangle_test: TriangleTest::Watertight,
            sharing: SampleSharing::Spread,
            photons: PhotonSettings::default(),
            hide_emitters: false,
            denoise: false,
            denoise_quality: DenoiseQuality::High,
        }
    }
}
