//! `<sensor>` (perspective, thinlens, orthographic) with its `<film>` (hdrfilm and its
//! `<rfilter>`) and `<sampler>`, and `<integrator>` (path, direct, and the
//! wrappers that only add outputs).

use super::props::Plugin;
use crate::film::filter::PixelFilter;
use crate::math::Vec3A;
use crate::scene::load::SceneError;
use crate::scene::{Camera, FovAxis, IntegratorKind, Projection, RenderSettings};
use glam::Mat4;

/// The film diagonal Mitsuba converts a `focal_length` with (35 mm film, mm).
const FILM_DIAGONAL_MM: f32 = 43.266_615;

/// Largest film side accepted (pixels).
pub const MAX_FILM_SIDE: i64 = 1 << 16;

/// What the sensor sets: the camera and the film's and sampler's settings.
pub struct SensorSettings {
    /// The camera.
    pub camera: Camera,
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Samples per pixel.
    pub spp: u32,
    /// The sampler's seed.
    pub seed: u64,
    /// Mitsuba's `far_clip`, checked against the scene once it is known.
    pub far_clip: f32,
}

/// Reads a `<sensor>`.
pub fn sensor(p: &Plugin) -> Result<SensorSettings, SceneError> {
    let (thin_lens, orthographic) = match p.kind {
        "perspective" => (false, false),
        "thinlens" => (true, false),
        "orthographic" => (false, true),
        other => {
            return Err(p.error(format!(
                "the sensor `{other}` is not supported: caustic renders `perspective`, `thinlens` and \
                 `orthographic` cameras"
            )))
        }
    };
    let film = p.single_child("film")?;
    let (width, height, filter) = match &film {
        Some(f) => film_settings(f)?,
        None => (768, 576, PixelFilter::gaussian(0.5)),
    };
    let (spp, seed) = match p.single_child("sampler")? {
        Some(s) => sampler(&s)?,
        None => (4, 0),
    };
    // An orthographic sensor has no field of view: it leaves `fov` and
    // `focal_length` unread, so that `finish` reports them.
    let fov = if orthographic { None } else { p.float("fov")? };
    let (fov_deg, fov_axis) = match fov {
        _ if orthographic => (45.0, FovAxis::X),
        Some(fov) => {
            if p.has("focal_length") {
                return Err(p.error("give `fov` or `focal_length`, not both"));
            }
            if !(fov > 0.0 && fov < 180.0) {
                return Err(p.error(format!("`fov` = {fov}: it must be in (0, 180) degrees")));
            }
            let axis = match p.choice("fov_axis", "x", &["x", "y", "diagonal", "smaller", "larger"])? {
                "x" => FovAxis::X,
                "y" => FovAxis::Y,
                "diagonal" => FovAxis::Diagonal,
                "smaller" => FovAxis::Smaller,
                _ => FovAxis::Larger,
            };
            (fov, axis)
        }
        None => {
            let text = p.string("focal_length")?.unwrap_or("50mm");
            let mm = text
                .trim()
                .strip_suffix("mm")
                .unwrap_or(text)
                .trim()
                .parse::<f32>()
                .ok()
                .filter(|f| f.is_finite() && *f > 0.0)
                .ok_or_else(|| p.error(format!("`focal_length` = `{text}` is not a length such as `50mm`")))?;
            (
                2.0 * (FILM_DIAGONAL_MM * 0.5 / mm).atan().to_degrees(),
                FovAxis::Diagonal,
            )
        }
    };
    for offset in ["principal_point_offset_x", "principal_point_offset_y"] {
        if orthographic {
            break;
        }
        if p.float(offset)?.is_some_and(|v| v != 0.0) {
            return Err(p.error(format!("`{offset}` (an off-centre lens) is not supported")));
        }
    }
    for shutter in ["shutter_open", "shutter_close"] {
        // Motion blur needs moving shapes, which caustic does not have: the time is irrelevant.
        p.float(shutter)?;
    }
    let near_clip = p.float_checked("near_clip", 0.01, "≥ 0", |v| v >= 0.0)?;
    let far_clip = p.float_checked("far_clip", 10_000.0, "greater than `near_clip`", |v| v > near_clip)?;
    let (aperture_radius, focus_distance) = if thin_lens {
        if !p.has("aperture_radius") {
            return Err(p.error("`aperture_radius` is required"));
        }
        (
            p.float_checked("aperture_radius", 0.0, "≥ 0", |v| v >= 0.0)?,
            p.float_checked("focus_distance", 10_000.0, "> 0", |v| v > 0.0)?,
        )
    } else {
        // A pinhole reads `focus_distance` only for interactive tools.
        if !orthographic {
            p.float("focus_distance")?;
        }
        (0.0, 1.0)
    };
    let to_world = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
    let (mut camera, scale) = camera_from(&to_world, p, orthographic)?;
    let mut near_clip = near_clip;
    if orthographic {
        // Mitsuba's `orthographic`: the film spans [−1, 1] across x (and
        // 1/aspect across y) in camera space, scaled by `to_world`; rays
        // start on the near plane, z = near_clip in camera space, which
        // `to_world`'s z scale stretches.
        camera.projection = Projection::Orthographic {
            half_width: scale.x,
            half_height: 0.0,
        };
        near_clip *= scale.z;
    }
    p.finish()?;
    Ok(SensorSettings {
        camera: Camera {
            fov_deg,
            fov_axis,
            aperture_radius,
            focus_distance,
            near_clip,
            filter,
            ..camera
        },
        size: (width, height),
        spp,
        seed: u64::from(seed),
        far_clip,
    })
}

/// The camera frame of a sensor's `to_world` and its scale along each
/// axis: Mitsuba's camera looks down +z with +y up and +x to the image's
/// left. An orthographic camera's x and y scales are its extent and its z
/// scale only moves the near plane: those need only equal x and y scales.
fn camera_from(m: &Mat4, p: &Plugin, orthographic: bool) -> Result<(Camera, glam::Vec3), SceneError> {
    if m.row(3) != glam::Vec4::W {
        return Err(p.error("`to_world` is a projective matrix; a camera needs an affine one"));
    }
    let col = |i: usize| m.col(i).truncate();
    let (x, y, z) = (col(0), col(1), col(2));
    let (lx, ly, lz) = (x.length(), y.length(), z.length());
    let orthogonal =
        x.dot(y).abs() <= 1e-4 * lx * ly && y.dot(z).abs() <= 1e-4 * ly * lz && x.dot(z).abs() <= 1e-4 * lx * lz;
    let uniform = (lx - ly).abs() <= 1e-4 * lx && (orthographic || (lx - lz).abs() <= 1e-4 * lx);
    if !(orthogonal && uniform && lx > 0.0 && lz > 0.0) {
        return Err(p.error(
            "`to_world` shears or scales the camera unevenly, which would distort the image; caustic takes rotations, translations and uniform scales",
        ));
    }
    let position = Vec3A::from(col(3));
    let forward = Vec3A::from(z / lz);
    let up = Vec3A::from(y / ly);
    let right = -Vec3A::from(x / lx);
    let base = Camera::new(Vec3A::ZERO, Vec3A::Z, Vec3A::Y, 45.0).expect("a valid frame");
    Ok((
        Camera {
            position,
            forward,
            right,
            up,
            ..base
        },
        glam::Vec3::new(lx, ly, lz),
    ))
}

/// `(width, height, filter)` of an `<film type="hdrfilm">`.
fn film_settings(f: &Plugin) -> Result<(u32, u32, PixelFilter), SceneError> {
    if f.kind != "hdrfilm" {
        return Err(f.error(format!(
            "the film `{}` is not supported: caustic reads `hdrfilm`",
            f.kind
        )));
    }
    let side = |name: &str, default: i64| -> Result<u32, SceneError> {
        let v = f.int(name)?.unwrap_or(default);
        if (1..=MAX_FILM_SIDE).contains(&v) {
            Ok(v as u32)
        } else {
            Err(f.error(format!("`{name}` = {v}: it must be in 1‥{MAX_FILM_SIDE}")))
        }
    };
    let (width, height) = (side("width", 768)?, side("height", 576)?);
    // Output encodings: caustic writes its own PNG / EXR outputs.
    f.choice("pixel_format", "rgb", &["rgb", "rgba", "luminance", "luminance_alpha"])?;
    f.choice("component_format", "float16", &["float16", "float32", "uint32"])?;
    f.choice("file_format", "openexr", &["openexr", "exr", "rgbe", "pfm"])?;
    if f.boolean("sample_border")?.unwrap_or(false) {
        return Err(f.error("`sample_border` is not supported"));
    }
    let crop_w = f.int("crop_width")?;
    let crop_h = f.int("crop_height")?;
    let crop_x = f.int("crop_offset_x")?.unwrap_or(0);
    let crop_y = f.int("crop_offset_y")?.unwrap_or(0);
    if crop_w.is_some_and(|w| w != i64::from(width))
        || crop_h.is_some_and(|h| h != i64::from(height))
        || crop_x != 0
        || crop_y != 0
    {
        return Err(f.error("a crop window is not supported; render the whole film"));
    }
    let filter = match f.single_child("rfilter")? {
        None => PixelFilter::gaussian(0.5),
        Some(r) => {
            let filter = match r.kind {
                "box" => PixelFilter::Box {
                    radius: r.float_checked("radius", 0.5, "> 0", |v| v > 0.0)?,
                },
                "tent" => PixelFilter::Tent {
                    radius: r.float_checked("radius", 1.0, "> 0", |v| v > 0.0)?,
                },
                "gaussian" => PixelFilter::gaussian(r.float_checked("stddev", 0.5, "> 0", |v| v > 0.0 && v <= 16.0)?),
                other => {
                    return Err(r.error(format!(
                        "the reconstruction filter `{other}` is not supported: caustic has box, tent and gaussian"
                    )))
                }
            };
            r.finish()?;
            filter
        }
    };
    f.finish()?;
    Ok((width, height, filter))
}

/// `(spp, seed)` of any `<sampler>`: caustic draws its own sequences
/// (Owen-scrambled Sobol for path tracing), which change the noise, not the
/// expected image.
fn sampler(s: &Plugin) -> Result<(u32, u32), SceneError> {
    match s.kind {
        "independent" | "stratified" | "multijitter" | "orthogonal" | "ldsampler" | "sobol" | "halton" => {}
        other => return Err(s.error(format!("the sampler `{other}` is unknown"))),
    }
    let spp = s.int("sample_count")?.unwrap_or(4);
    if !(1..=i64::from(crate::limits::MAX_SPP)).contains(&spp) {
        return Err(s.error(format!(
            "`sample_count` = {spp}: it must be in 1‥{}",
            crate::limits::MAX_SPP
        )));
    }
    let seed = s.int("seed")?.unwrap_or(0);
    if !(0..=i64::from(u32::MAX)).contains(&seed) {
        return Err(s.error(format!("`seed` = {seed}: it must be in 0‥{}", u32::MAX)));
    }
    // Parameters of the sampling pattern alone.
    s.boolean("jitter")?;
    s.float("strength")?;
    s.string("randomization")?;
    s.finish()?;
    Ok((spp as u32, seed as u32))
}

/// Whether an integrator renders participating media and null surfaces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MediaHandling {
    /// `volpath`, `volpathmis`: media scatter and absorb, shadow rays pass
    /// through null surfaces.
    Rendered,
    /// `path`, `direct`: Mitsuba ignores the media (rays travel as in
    /// vacuum), and a null surface is a delta bounce that blocks shadow rays.
    Ignored,
}

/// Applies an `<integrator>` to the settings; wrappers that only add
/// outputs (`moment`, `aov`) return a warning and apply their integrator.
pub fn integrator(
    p: &Plugin,
    settings: &mut RenderSettings,
    warnings: &mut Vec<String>,
) -> Result<MediaHandling, SceneError> {
    settings.integrator = IntegratorKind::Path;
    match p.kind {
        "path" | "volpath" | "volpathmis" => {
            // `volpathmis` samples distances with spectral MIS, which is what
            // caustic's volumetric path tracer does for every medium: the
            // same estimator as `volpath` in expectation.
            let media = if p.kind == "path" {
                MediaHandling::Ignored
            } else {
                MediaHandling::Rendered
            };
            let depth = p.int("max_depth")?.unwrap_or(-1);
            settings.max_depth = mitsuba_depth(depth, p)?;
            // Russian roulette starts at caustic's own depth: unbiased either way.
            p.int("rr_depth")?;
            settings.hide_emitters = p.boolean("hide_emitters")?.unwrap_or(false);
            p.finish()?;
            Ok(media)
        }
        "direct" => {
            // Direct light with MIS between light and BSDF samples is the
            // path integrator stopped after one bounce (Mitsuba's depth 2).
            settings.max_depth = Some(1);
            for count in ["emitter_samples", "bsdf_samples", "shading_samples"] {
                if let Some(n) = p.int(count)? {
                    if n < 1 {
                        return Err(p.error(format!("`{count}` = {n}: it must be ≥ 1")));
                    }
                }
            }
            settings.hide_emitters = p.boolean("hide_emitters")?.unwrap_or(false);
            p.finish()?;
            Ok(MediaHandling::Ignored)
        }
        "moment" | "aov" => {
            p.string("aovs")?;
            let inner = p.children_of("integrator")?;
            let Some((first, _)) = inner.first() else {
                if p.kind == "aov" {
                    return Err(p.error("an `aov` integrator without a nested integrator renders no image"));
                }
                return Err(p.error("needs a nested <integrator>"));
            };
            warnings.push(format!(
                "{}:{}: {} only adds outputs (moments or AOVs) that caustic does not write; rendering its nested integrator",
                p.origin().file.display(),
                p.origin().place,
                p.what()
            ));
            let media = integrator(first, settings, warnings)?;
            p.finish()?;
            Ok(media)
        }
        other => Err(p.error(format!(
            "the integrator `{other}` is not supported: caustic renders `path`, `volpath`, `volpathmis` and `direct`"
        ))),
    }
}

/// Mitsuba's `max_depth` (path length in segments, −1 unbounded) as
/// caustic's bounce cap (one less).
fn mitsuba_depth(depth: i64, p: &Plugin) -> Result<Option<u32>, SceneError> {
    match depth {
        -1 => Ok(None),
        0 => Err(p.error("`max_depth` = 0 renders nothing")),
        d if (1..=i64::from(crate::scene::load::MAX_DEPTH) + 1).contains(&d) => Ok(Some(d as u32 - 1)),
        d => Err(p.error(format!(
            "`max_depth` = {d}: it must be −1 (unbounded) or 1‥{}",
            crate::scene::load::MAX_DEPTH + 1
        ))),
    }
}
