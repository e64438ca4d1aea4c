//! `[render]`, `[photons]` and `[camera]`: every setting that differs from
//! the loader's default, and the camera's exact frame.

use super::{int, num, string, unsupported, vec3, WriteError};
use crate::film::denoise::DenoiseQuality;
use crate::film::filter::PixelFilter;
use crate::film::ToneMap;
use crate::geometry::TriangleTest;
use crate::math::{SamplerKind, Vec3A};
use crate::scene::{
    AdaptiveGoal, Camera, CausticsMode, GatherMode, IntegratorKind, Media, PassThrough, PhotonSettings, Projection,
    RenderSettings, SampleSharing, Scene,
};
use toml::{Table, Value};

/// `[render]`; `integrator = "volpath"` when null surfaces are crossed as
/// Mitsuba's `volpath` crosses them.
pub(super) fn render(s: &RenderSettings, ambient: Vec3A, media: &Media) -> Result<Table, WriteError> {
    let d = RenderSettings::default();
    let mut t = Table::new();
    t.insert("width".into(), int(s.width));
    t.insert("height".into(), int(s.height));
    t.insert("spp".into(), int(s.spp));
    if let Some(depth) = s.max_depth {
        t.insert("max_depth".into(), int(depth));
    }
    t.insert(
        "seed".into(),
        Value::Integer(
            i64::try_from(s.seed)
                .map_err(|_| unsupported("[render] seed", format!("{} is beyond TOML's integers", s.seed)))?,
        ),
    );
    let integrator = match (s.integrator, media.pass_through) {
        (IntegratorKind::Path, PassThrough::Volumetric) => "volpath",
        (IntegratorKind::Whitted, PassThrough::Volumetric) => {
            return Err(unsupported(
                "[render] integrator",
                "the Whitted integrator with volumetric pass-through surfaces",
            ))
        }
        (kind, PassThrough::SurfaceBounce) => kind.name(),
    };
    t.insert("integrator".into(), string(integrator));
    if let Some(e) = s.noise_threshold {
        t.insert("noise_threshold".into(), num(e));
    }
    if s.min_spp != d.min_spp {
        t.insert("min_spp".into(), int(s.min_spp));
    }
    if s.adaptive_goal != d.adaptive_goal {
        let goal = match s.adaptive_goal {
            AdaptiveGoal::Pixel => "pixel",
            AdaptiveGoal::Image => "image",
        };
        t.insert("adaptive_goal".into(), string(goal));
    }
    if let Some(sampler) = s.sampler {
        let name = match sampler {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Independent => "independent",
        };
        t.insert("sampler".into(), string(name));
    }
    let tone_map = match s.output.tone_map {
        ToneMap::Aces => "aces",
        ToneMap::Clamp => "clamp",
    };
    t.insert("tone_map".into(), string(tone_map));
    t.insert("exposure".into(), num(s.output.exposure));
    if ambient != Vec3A::ZERO {
        t.insert("ambient".into(), vec3(ambient));
    }
    let test = match s.triangle_test {
        TriangleTest::Watertight => "watertight",
        TriangleTest::MollerTrumbore => "moller-trumbore",
    };
    t.insert("triangle_test".into(), string(test));
    let sharing = match s.sharing {
        SampleSharing::Spread => "spread",
        SampleSharing::Split => "split",
    };
    t.insert("sharing".into(), string(sharing));
    t.insert("hide_emitters".into(), Value::Boolean(s.hide_emitters));
    t.insert("denoise".into(), Value::Boolean(s.denoise));
    let quality = match s.denoise_quality {
        DenoiseQuality::High => "high",
        DenoiseQuality::Balanced => "balanced",
        DenoiseQuality::Fast => "fast",
    };
    t.insert("denoise_quality".into(), string(quality));
    Ok(t)
}

/// `[photons]`.
pub(super) fn photons(p: &PhotonSettings) -> Table {
    let mut t = Table::new();
    // Counts beyond i64 are refused by the photon limits long before.
    t.insert("count".into(), Value::Integer(p.count.min(i64::MAX as u64) as i64));
    t.insert("k".into(), int(p.k));
    if let Some(r) = p.max_radius {
        t.insert("max_radius".into(), num(r));
    }
    t.insert("cone_k".into(), num(p.cone_k));
    let gather = match p.gather {
        GatherMode::Direct => "direct",
        GatherMode::Precomputed => "precomputed",
    };
    t.insert("gather".into(), string(gather));
    let caustics = match p.caustics {
        CausticsMode::Path => "path",
        CausticsMode::Map => "map",
    };
    t.insert("caustics".into(), string(caustics));
    t.insert("progressive".into(), Value::Boolean(p.progressive));
    t.insert("alpha".into(), num(p.alpha));
    t
}

/// `[camera]`: its frame exactly (`forward`, `right`, `up`: `look_at`
/// would be rounded), the lens, the field of view, the pixel filter and
/// the camera's medium.
pub(super) fn camera(c: &Camera, scene: &Scene) -> Result<Table, WriteError> {
    let mut t = Table::new();
    t.insert("position".into(), vec3(c.position));
    t.insert("forward".into(), vec3(c.forward));
    t.insert("right".into(), vec3(c.right));
    t.insert("up".into(), vec3(c.up));
    match c.projection {
        Projection::Perspective => {
            t.insert("fov".into(), num(c.fov_deg));
            t.insert("fov_axis".into(), string(c.fov_axis.name()));
            t.insert("aperture_radius".into(), num(c.aperture_radius));
        }
        Projection::Orthographic {
            half_width,
            half_height,
        } => {
            t.insert("projection".into(), string(c.projection.name()));
            for (key, h) in [("half_width", half_width), ("half_height", half_height)] {
                if h > 0.0 {
                    t.insert(key.into(), num(h));
                }
            }
        }
    }
    t.insert("focus_distance".into(), num(c.focus_distance));
    t.insert("near_clip".into(), num(c.near_clip));
    match &c.filter {
        PixelFilter::Box { radius } => {
            t.insert("filter".into(), string("box"));
            t.insert("filter_radius".into(), num(*radius));
        }
        PixelFilter::Tent { radius } => {
            t.insert("filter".into(), string("tent"));
            t.insert("filter_radius".into(), num(*radius));
        }
        PixelFilter::Gaussian { stddev, .. } => {
            t.insert("filter".into(), string("gaussian"));
            t.insert("filter_stddev".into(), num(*stddev));
        }
    }
    if let Some(m) = scene.media.camera {
        t.insert("medium".into(), string(&scene.media.list[m as usize].name));
    }
    Ok(t)
}
