//! The `[render]`, `[photons]` and `[camera]` tables: render settings, photon
//! map settings and the camera, with their limits and defaults.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::film::denoise::DenoiseQuality;
use crate::film::filter::PixelFilter;
use crate::film::{OutputSettings, ToneMap};
use crate::geometry::TriangleTest;
use crate::limits::{check_image_limits, check_photon_count, ImageLimit, MAX_IMAGE_SIDE};
use crate::math::{SamplerKind, Vec3A};
use crate::scene::camera::{FovAxis, Projection};
use crate::scene::desc::{
    AdaptiveGoalName, CameraDesc, CausticsName, DenoiseQualityName, GatherName, IntegratorName, PhotonsDesc,
    RenderDesc, SamplerName, SharingName, Spanned, ToneMapName, TriangleTestName,
};
use crate::scene::{
    AdaptiveGoal, Camera, CausticsMode, GatherMode, IntegratorKind, PhotonSettings, RenderSettings, SampleSharing,
};

/// Largest `max_depth`.
pub const MAX_DEPTH: u32 = 64;
/// Largest magnitude of `exposure` in stops (2^64 is still finite in f32).
pub const MAX_EXPOSURE_STOPS: f64 = 64.0;
/// Largest `k` of the photon gather.
pub const MAX_PHOTON_GATHER: u32 = 100_000;

/// Default vertical field of view (degrees).
pub const DEFAULT_VFOV_DEG: f32 = 45.0;

impl Ctx<'_> {
    /// The `[render]` table's `ambient` light (black when absent).
    pub(super) fn ambient(&self, r: &RenderDesc) -> Result<Vec3A, SceneError> {
        match &r.ambient {
            None => Ok(Vec3A::ZERO),
            Some(s) => self.colour(s, "ambient"),
        }
    }

    pub(super) fn render(&self, r: &RenderDesc) -> Result<RenderSettings, SceneError> {
        let d = RenderSettings::default();
        let int = |s: &Option<Spanned<u32>>, default: u32, key: &str, min: u32, max: u32| match s {
            None => Ok(default),
            Some(s) if (min..=max).contains(s.get_ref()) => Ok(*s.get_ref()),
            Some(s) => Err(self.invalid(
                s.span(),
                format!("`{key}` = {} is out of range: it must be in {min}..={max}", s.get_ref()),
            )),
        };
        let width = int(&r.width, d.width, "width", 1, MAX_IMAGE_SIDE)?;
        let height = int(&r.height, d.height, "height", 1, MAX_IMAGE_SIDE)?;
        let spp = int(&r.spp, d.spp, "spp", 1, u32::MAX)?;
        let noise_threshold = match &r.noise_threshold {
            None => None,
            Some(s) => {
                let e = self.number(s, "noise_threshold")?;
                if e <= 0.0 || e >= 1.0 {
                    return Err(self.invalid(
                        s.span(),
                        format!("`noise_threshold` = {e} must be in (0, 1): a relative error such as 0.02"),
                    ));
                }
                Some(e)
            }
        };
        let min_spp = int(&r.min_spp, d.min_spp, "min_spp", 2, spp.max(2))?;
        let max_depth = match &r.max_depth {
            None => None,
            Some(_) => Some(int(&r.max_depth, 0, "max_depth", 0, MAX_DEPTH)?),
        };
        // Point at the key that makes the product too large (the first given).
        let size_span = [&r.width, &r.height, &r.spp]
            .into_iter()
            .flatten()
            .map(|s| s.span())
            .next()
            .unwrap_or(0..0);
        if let Err(e) = check_image_limits(width, height, spp) {
            let span = match e {
                ImageLimit::Samples(_) => r.spp.as_ref().map_or(size_span, |s| s.span()),
                ImageLimit::Film(_) => size_span,
            };
            return Err(self.invalid(span, e.to_string()));
        }
        let exposure = match &r.exposure {
            None => d.output.exposure,
            Some(s) => {
                let e = self.number(s, "exposure")?;
                if f64::from(e).abs() > MAX_EXPOSURE_STOPS {
                    return Err(self.invalid(
                        s.span(),
                        format!("`exposure` = {e} stops is out of range (±{MAX_EXPOSURE_STOPS})"),
                    ));
                }
                e
            }
        };
        Ok(RenderSettings {
            width,
            height,
            spp,
            max_depth,
            seed: r.seed.unwrap_or(d.seed),
            output: OutputSettings {
                tone_map: match r.tone_map {
                    None => d.output.tone_map,
                    Some(ToneMapName::Aces) => ToneMap::Aces,
                    Some(ToneMapName::Clamp) => ToneMap::Clamp,
                },
                exposure,
            },
            triangle_test: match r.triangle_test {
                None => d.triangle_test,
                Some(TriangleTestName::Watertight) => TriangleTest::Watertight,
                Some(TriangleTestName::MollerTrumbore) => TriangleTest::MollerTrumbore,
            },
            sharing: match r.sharing {
                None => d.sharing,
                Some(SharingName::Spread) => SampleSharing::Spread,
                Some(SharingName::Split) => SampleSharing::Split,
            },
            photons: d.photons,
            hide_emitters: r.hide_emitters.unwrap_or(d.hide_emitters),
            denoise: r.denoise.unwrap_or(d.denoise),
            denoise_quality: match r.denoise_quality {
                None => d.denoise_quality,
                Some(DenoiseQualityName::High) => DenoiseQuality::High,
                Some(DenoiseQualityName::Balanced) => DenoiseQuality::Balanced,
                Some(DenoiseQualityName::Fast) => DenoiseQuality::Fast,
            },
            noise_threshold,
            min_spp,
            adaptive_goal: match r.adaptive_goal {
                None | Some(AdaptiveGoalName::Pixel) => AdaptiveGoal::Pixel,
                Some(AdaptiveGoalName::Image) => AdaptiveGoal::Image,
            },
            sampler: r.sampler.map(|s| match s {
                SamplerName::Sobol => SamplerKind::Sobol,
                SamplerName::Independent => SamplerKind::Independent,
            }),
            integrator: match r.integrator {
                None | Some(IntegratorName::Whitted) => IntegratorKind::Whitted,
                Some(IntegratorName::Path | IntegratorName::Volpath) => IntegratorKind::Path,
            },
        })
    }

    pub(super) fn camera(&self, c: &CameraDesc, table: std::ops::Range<usize>) -> Result<Camera, SceneError> {
        let position = self.vec3(&c.position, "position")?;
        let look_at_desc = match (&c.look_at, &c.forward) {
            (Some(l), None) => {
                if let Some(r) = &c.right {
                    return Err(self.invalid(r.span(), "`right` goes with `forward` (instead of `look_at`)"));
                }
                l
            }
            (Some(_), Some(f)) => {
                return Err(self.invalid(
                    f.span(),
                    "give `look_at` or `forward` (with `right` and `up`), not both",
                ))
            }
            (None, Some(f)) => return self.camera_frame(c, position, f),
            (None, None) => {
                return Err(self.invalid(
                    table,
                    "missing field `look_at` in `[camera]` (or give its exact frame: `forward`, `right` and `up`)",
                ))
            }
        };
        let look_at = self.vec3(look_at_desc, "look_at")?;
        let forward = (look_at - position).try_normalize().ok_or_else(|| {
            self.invalid(
                look_at_desc.span(),
                "`look_at` equals the camera `position`: the camera has no viewing direction",
            )
        })?;
        let up = match &c.up {
            Some(s) => self.direction(s, "up")?,
            None => Vec3A::Y,
        };
        // Parallel when the sine of the angle is below ~1e-4 (0.006°): the
        // right vector would then be dominated by rounding.
        if forward.cross(up.normalize()).length() < 1e-4 {
            let (span, what) = match &c.up {
                Some(s) => (s.span(), "`up`"),
                None => (look_at_desc.span(), "the default `up` [0, 1, 0]"),
            };
            return Err(self.invalid(
                span,
                format!("{what} is parallel to the viewing direction (`look_at` − `position`): choose another `up`"),
            ));
        }
        let (fov_deg, fov_axis) = self.field_of_view(c)?;
        let camera = Camera::new(position, look_at, up, fov_deg)
            .ok_or_else(|| self.invalid(c.position.span(), "the camera is degenerate"))?;
        self.camera_optics(c, camera, fov_deg, fov_axis)
    }

    /// A camera given by its exact frame: `forward`, `right` and `up`, unit
    /// and orthogonal (within 1e-4), taken as written (the frame
    /// `caustic convert` writes, which `look_at` would round).
    fn camera_frame(
        &self,
        c: &CameraDesc,
        position: Vec3A,
        forward_desc: &Spanned<crate::scene::desc::Vec3Desc>,
    ) -> Result<Camera, SceneError> {
        let what = "a camera given by `forward`";
        let forward = self.vec3(forward_desc, "forward")?;
        let right_desc = self.required(&c.right, "right", what, forward_desc.span())?;
        let right = self.vec3(right_desc, "right")?;
        let up_desc = self.required(&c.up, "up", what, forward_desc.span())?;
        let up = self.vec3(up_desc, "up")?;
        for (v, s, key) in [
            (forward, forward_desc, "forward"),
            (right, right_desc, "right"),
            (up, up_desc, "up"),
        ] {
            if (v.length() - 1.0).abs() > 1e-4 {
                return Err(self.invalid(s.span(), format!("`{key}` = {v} must be a unit vector")));
            }
        }
        let orthogonal =
            forward.dot(right).abs() <= 1e-4 && forward.dot(up).abs() <= 1e-4 && right.dot(up).abs() <= 1e-4;
        if !orthogonal {
            return Err(self.invalid(right_desc.span(), "`forward`, `right` and `up` must be orthogonal"));
        }
        let (fov_deg, fov_axis) = self.field_of_view(c)?;
        let camera = Camera {
            position,
            forward,
            right,
            up,
            // A focus distance of 1 unless given (there is no point looked at).
            ..Camera::new(Vec3A::ZERO, Vec3A::Z, Vec3A::Y, fov_deg).expect("a valid frame")
        };
        self.camera_optics(c, camera, fov_deg, fov_axis)
    }

    /// The field of view (`vfov`, or `fov` with `fov_axis`).
    fn field_of_view(&self, c: &CameraDesc) -> Result<(f32, FovAxis), SceneError> {
        let (fov_key, fov) = match (&c.vfov, &c.fov) {
            (Some(_), Some(f)) => {
                return Err(self.invalid(
                    f.span(),
                    "give the field of view once: `vfov` (vertical) or `fov` (with `fov_axis`)",
                ))
            }
            (Some(s), None) => ("vfov", Some(s)),
            (None, f) => ("fov", f.as_ref()),
        };
        let fov_deg = match fov {
            None => DEFAULT_VFOV_DEG,
            Some(s) => {
                let v = self.number(s, fov_key)?;
                if !(v > 0.0 && v < 180.0) {
                    return Err(self.invalid(s.span(), format!("`{fov_key}` = {v}° must be in (0, 180) degrees")));
                }
                v
            }
        };
        let fov_axis = match &c.fov_axis {
            None => FovAxis::Y,
            Some(a) if c.fov.is_none() => {
                return Err(self.invalid(a.span(), "`fov_axis` goes with `fov` (`vfov` is vertical)"))
            }
            Some(a) => FovAxis::from_name(a.get_ref()).ok_or_else(|| {
                self.invalid(
                    a.span(),
                    format!(
                        "unknown `fov_axis` `{}`: expected x, y, diagonal, smaller or larger",
                        a.get_ref()
                    ),
                )
            })?,
        };
        Ok((fov_deg, fov_axis))
    }

    /// The lens, the near clip and the pixel filter of `camera`, and its field of view.
    fn camera_optics(
        &self,
        c: &CameraDesc,
        mut camera: Camera,
        fov_deg: f32,
        fov_axis: FovAxis,
    ) -> Result<Camera, SceneError> {
        camera.fov_deg = fov_deg;
        camera.fov_axis = fov_axis;
        let non_negative = |s: &Option<Spanned<f64>>, key: &str| -> Result<Option<f32>, SceneError> {
            let Some(s) = s else { return Ok(None) };
            let x = self.number(s, key)?;
            if x < 0.0 {
                return Err(self.invalid(s.span(), format!("`{key}` = {x} must be ≥ 0")));
            }
            Ok(Some(x))
        };
        if let Some(r) = non_negative(&c.aperture_radius, "aperture_radius")? {
            camera.aperture_radius = r;
        }
        if let Some(d) = &c.focus_distance {
            let x = self.number(d, "focus_distance")?;
            if x <= 0.0 {
                return Err(self.invalid(d.span(), format!("`focus_distance` = {x} must be > 0")));
            }
            camera.focus_distance = x;
        }
        if let Some(n) = non_negative(&c.near_clip, "near_clip")? {
            camera.near_clip = n;
        }
        camera.projection = self.projection(c)?;
        camera.filter = self.pixel_filter(c)?;
        Ok(camera)
    }

    /// `projection` and, for an orthographic camera, its `half_width`
    /// and `half_height`.
    fn projection(&self, c: &CameraDesc) -> Result<Projection, SceneError> {
        let name = c.projection.as_ref().map_or("perspective", |p| p.get_ref().as_str());
        let halves = [("half_width", &c.half_width), ("half_height", &c.half_height)];
        match name {
            "perspective" => match halves.iter().find_map(|(k, v)| v.as_ref().map(|v| (k, v))) {
                Some((key, v)) => Err(self.invalid(
                    v.span(),
                    format!(
                        "`{key}` is an orthographic camera's: give `projection = \"orthographic\"` \
                         (a perspective camera has `vfov` or `fov`)"
                    ),
                )),
                None => Ok(Projection::Perspective),
            },
            "orthographic" => {
                let at = c.projection.as_ref().expect("named").span();
                let mut half = [0.0f32; 2];
                for (h, (key, v)) in half.iter_mut().zip(halves) {
                    if let Some(v) = v {
                        *h = self.number(v, key)?;
                        if *h <= 0.0 {
                            return Err(self.invalid(v.span(), format!("`{key}` = {h} must be > 0")));
                        }
                    }
                }
                if half == [0.0, 0.0] {
                    return Err(self.invalid(
                        at,
                        "an orthographic camera needs `half_width` or `half_height` (or both: the image shows \
                         at least that rectangle)",
                    ));
                }
                for (key, v) in [("vfov", &c.vfov), ("fov", &c.fov)] {
                    if let Some(v) = v {
                        return Err(self.invalid(
                            v.span(),
                            format!(
                                "`{key}` is a perspective camera's: an orthographic camera's extent is \
                                 `half_width` or `half_height`"
                            ),
                        ));
                    }
                }
                if let Some(r) = c.aperture_radius.as_ref().filter(|r| *r.get_ref() != 0.0) {
                    return Err(self.invalid(
                        r.span(),
                        "an orthographic camera has no lens: `aperture_radius` must be 0 or absent",
                    ));
                }
                Ok(Projection::Orthographic {
                    half_width: half[0],
                    half_height: half[1],
                })
            }
            other => Err(self.invalid(
                c.projection.as_ref().expect("named").span(),
                format!("unknown `projection` `{other}`: expected perspective or orthographic"),
            )),
        }
    }

    /// The camera's `filter`, `filter_radius` and `filter_stddev`.
    fn pixel_filter(&self, c: &CameraDesc) -> Result<PixelFilter, SceneError> {
        // Beyond this a filter averages over a large part of any image.
        const MAX_RADIUS: f32 = 64.0;
        let name = c.filter.as_ref().map_or("box", |f| f.get_ref().as_str());
        let positive = |s: &Spanned<f64>, key: &str, max: f32| -> Result<f32, SceneError> {
            let x = self.number(s, key)?;
            if !(x > 0.0 && x <= max) {
                return Err(self.invalid(s.span(), format!("`{key}` = {x} must be in (0, {max}] pixels")));
            }
            Ok(x)
        };
        let radius = |default: f32| -> Result<f32, SceneError> {
            c.filter_radius
                .as_ref()
                .map_or(Ok(default), |r| positive(r, "filter_radius", MAX_RADIUS))
        };
        let misplaced = |s: &Option<Spanned<f64>>, key: &str, why: &str| match s {
            Some(s) => Err(self.invalid(s.span(), format!("`{key}` {why}"))),
            None => Ok(()),
        };
        match name {
            "box" | "tent" => {
                misplaced(
                    &c.filter_stddev,
                    "filter_stddev",
                    "applies to `filter = \"gaussian\"` only",
                )?;
                Ok(if name == "box" {
                    PixelFilter::Box {
                        radius: radius(PixelFilter::DEFAULT_BOX_RADIUS)?,
                    }
                } else {
                    PixelFilter::Tent {
                        radius: radius(PixelFilter::DEFAULT_TENT_RADIUS)?,
                    }
                })
            }
            "gaussian" => {
                misplaced(
                    &c.filter_radius,
                    "filter_radius",
                    "does not apply to a Gaussian, whose radius is 4 × `filter_stddev`",
                )?;
                let stddev = c.filter_stddev.as_ref().map_or(Ok(PixelFilter::DEFAULT_STDDEV), |s| {
                    positive(s, "filter_stddev", MAX_RADIUS / 4.0)
                })?;
                Ok(PixelFilter::gaussian(stddev))
            }
            other => {
                let span = c.filter.as_ref().map(|f| f.span()).unwrap_or_default();
                Err(self.invalid(
                    span,
                    format!("unknown `filter` `{other}`: expected box, tent or gaussian"),
                ))
            }
        }
    }

    /// `[photons]`.
    pub(super) fn photons(&self, p: &PhotonsDesc) -> Result<PhotonSettings, SceneError> {
        let d = PhotonSettings::default();
        let count = match &p.count {
            None => d.count,
            Some(c) => {
                let n = *c.get_ref();
                if n < 0 {
                    return Err(self.invalid(c.span(), format!("photon `count` = {n} must be ≥ 0")));
                }
                check_photon_count(n as u64).map_err(|e| self.invalid(c.span(), e))?;
                n as u64
            }
        };
        let k = match &p.k {
            None => d.k,
            Some(k) if (1..=MAX_PHOTON_GATHER as i64).contains(k.get_ref()) => *k.get_ref() as u32,
            Some(k) => {
                return Err(self.invalid(
                    k.span(),
                    format!("photon `k` = {} must be in 1..={MAX_PHOTON_GATHER}", k.get_ref()),
                ))
            }
        };
        let max_radius = match &p.max_radius {
            None => d.max_radius,
            Some(r) => {
                let x = self.number(r, "max_radius")?;
                if x <= 0.0 {
                    return Err(self.invalid(r.span(), format!("`max_radius` = {x} must be > 0")));
                }
                Some(x)
            }
        };
        let cone_k = match &p.cone_k {
            None => d.cone_k,
            Some(c) => {
                let x = self.number(c, "cone_k")?;
                if x < 1.0 {
                    return Err(self.invalid(
                        c.span(),
                        format!("`cone_k` = {x} must be ≥ 1 (the cone filter's weight 1 − d/(k·r) must stay ≥ 0)"),
                    ));
                }
                x
            }
        };
        let alpha = match &p.alpha {
            None => d.alpha,
            Some(a) => {
                let x = self.number(a, "alpha")?;
                if !(x > 0.0 && x < 1.0) {
                    return Err(self.invalid(
                        a.span(),
                        format!(
                            "`alpha` = {x} must be in (0, 1) (the fraction of photons each progressive pass keeps; \
                             Knaus & Zwicker suggest 2/3)"
                        ),
                    ));
                }
                x
            }
        };
        Ok(PhotonSettings {
            count,
            k,
            max_radius,
            cone_k,
            progressive: p.progressive.unwrap_or(d.progressive),
            alpha,
            gather: match p.gather {
                None => d.gather,
                Some(GatherName::Precomputed) => GatherMode::Precomputed,
                Some(GatherName::Direct) => GatherMode::Direct,
            },
            caustics: match p.caustics {
                None => d.caustics,
                Some(CausticsName::Path) => CausticsMode::Path,
                Some(CausticsName::Map) => CausticsMode::Map,
            },
        })
    }
}
