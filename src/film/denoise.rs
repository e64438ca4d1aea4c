//! Denoising with Intel Open Image Denoise (OIDN, feature `denoise`): its
//! `RT` filter on the linear HDR film, guided by the albedo and normal
//! images (see `integrator::aov`), followed by a correction that gives the
//! filtered image the raw image's local mean ([`preserve_local_mean`]):
//! the network removes outliers (caustic paths, the light's edges) with
//! their energy, which darkened whole images by 1–2 % (docs/denoise.md).
//! The guides are given as OIDN's ordinary (not `cleanAux`) auxiliaries:
//! below a few dozen samples their antialiasing is itself noisy, and the
//! clean-guide network measured a larger error there.
//!
//! OIDN's CPU device runs on TBB: Embree's when both are linked (the
//! dynamic linker binds OIDN's TBB calls to the first TBB loaded, see
//! docs/denoise.md), else the one beside OIDN. Its result may differ in the
//! last bits between machines (the kernels chosen depend on the instruction
//! set; on one machine it was the same bits for 1 and 2 cores); caustic's
//! determinism holds for the raw image, kept beside the denoised one.

use super::Film;
use crate::math::Vec3;
use std::time::{Duration, Instant};
use thiserror::Error;

/// Quality of the filter (OIDN's filter quality): `high` for final images,
/// `fast` trades detail for about half the time (docs/denoise.md has their
/// measured cost and error).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DenoiseQuality {
    /// OIDN's highest quality (the default).
    #[default]
    High,
    /// OIDN's balanced filter (on its CPU device the same image and time
    /// as `High`, measured in docs/benchmarks.md).
    Balanced,
    /// OIDN's fastest filter: about half the time of `High`; the viewer's.
    Fast,
}

impl DenoiseQuality {
    /// The name used on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Self::High => "high",
            Self::Balanced => "balanced",
            Self::Fast => "fast",
        }
    }

    /// Measured CPU seconds of the filter per million pixels, rounded up
    /// (high and balanced: 2.9 s at 1920×1080, 3.5 s at 256×256; fast:
    /// 1.7 s at 1920×1080; the mean correction adds about 0.3 s per million
    /// pixels): what a time budget keeps back.
    pub fn cpu_seconds_per_megapixel(self) -> f64 {
        match self {
            Self::High | Self::Balanced => 4.0,
            Self::Fast => 2.0,
        }
    }
}

/// The guides of the filter: per-pixel albedo in [0, 1] and unit shading
/// normals (zero where the camera ray escaped).
#[derive(Clone, Copy, Debug)]
pub struct Guides<'a> {
    /// First non-specular surface's reflectance.
    pub albedo: &'a Film,
    /// Its shading normal, facing the camera ray.
    pub normal: &'a Film,
}

/// What denoising cost.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DenoiseStats {
    /// Wall time (device creation included).
    pub time: Duration,
    /// Growth of the process's peak resident memory while denoising (`None`
    /// where the operating system does not report it).
    pub peak_memory: Option<u64>,
    /// The filter's quality.
    pub quality: DenoiseQuality,
}

/// Why an image could not be denoised.
#[derive(Debug, Error)]
pub enum DenoiseError {
    /// This build has no denoiser.
    #[error(
        "denoising needs the `denoise` feature (Intel Open Image Denoise), which this build of caustic lacks; \
         rebuild with `cargo build --release --features denoise`"
    )]
    Unavailable,
    /// OIDN refused or failed.
    #[error("Open Image Denoise failed: {0}")]
    Oidn(String),
    /// The guides are not the film's size.
    #[error("the albedo and normal images are {0}×{1}, the image {2}×{3}")]
    Size(u32, u32, u32, u32),
}

/// True when this build can denoise.
pub fn available() -> bool {
    cfg!(feature = "denoise")
}

/// The OIDN library this build links: `(version, where it came from)`.
pub fn library() -> Option<(&'static str, &'static str)> {
    #[cfg(feature = "denoise")]
    {
        Some((env!("CAUSTIC_OIDN_VERSION"), env!("CAUSTIC_OIDN_SOURCE")))
    }
    #[cfg(not(feature = "denoise"))]
    {
        None
    }
}

/// Fails with [`DenoiseError::Unavailable`] in a build without the feature
/// (for callers to refuse `--denoise` before rendering).
pub fn require() -> Result<(), DenoiseError> {
    if available() {
        Ok(())
    } else {
        Err(DenoiseError::Unavailable)
    }
}

fn flatten(film: &Film, clamp: fn(f32) -> f32) -> Vec<f32> {
    film.pixels
        .iter()
        .flat_map(|p| [clamp(p.x), clamp(p.y), clamp(p.z)])
        .collect()
}

/// Denoises `color` (linear HDR), guided by `guides` when given.
pub fn denoise(
    color: &Film,
    guides: Option<Guides>,
    quality: DenoiseQuality,
) -> Result<(Film, DenoiseStats), DenoiseError> {
    if let Some(g) = guides {
        for f in [g.albedo, g.normal] {
            if (f.width, f.height) != (color.width, color.height) {
                return Err(DenoiseError::Size(f.width, f.height, color.width, color.height));
            }
        }
    }
    let begin = Instant::now();
    let before = crate::memory::reset_peak_rss()
        .then(crate::memory::current_rss_bytes)
        .flatten();
    // OIDN takes finite, non-negative HDR values; the film holds finite ones.
    let input = flatten(color, |v| if v.is_finite() { v.max(0.0) } else { 0.0 });
    let mut output = run(&input, color.width, color.height, guides, quality)?;
    preserve_local_mean(&mut output, &input, color.width as usize, color.height as usize);
    let peak_memory = match (before, crate::memory::peak_rss_bytes()) {
        (Some(b), Some(p)) => Some(p.saturating_sub(b)),
        _ => None,
    };
    let pixels = output.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
    Ok((
        Film {
            width: color.width,
            height: color.height,
            pixels,
        },
        DenoiseStats {
            time: begin.elapsed(),
            peak_memory,
            quality,
        },
    ))
}

/// Standard deviation, in pixels, of the window within which the denoised
/// image keeps the raw image's light: wide enough that sharing out the raw
/// image's outliers does not bring their noise back, narrow enough that the
/// light stays where it was rendered (docs/denoise.md has the figures).
pub const MEAN_WINDOW_SIGMA: f32 = 16.0;

/// Gives back to `denoised` (interleaved RGB, `width × height`) the light
/// the filter removed or added, where it was: each channel is multiplied by
/// the ratio of the raw to the denoised image's local means, `d ⊙ Kr ⊘ Kd`,
/// with `K` three box filters (a Gaussian of σ ≈ [`MEAN_WINDOW_SIGMA`]
/// pixels, Wells 1986) mirrored at the image's border, then by the ratio of
/// the channel's sums, which the local step leaves within a fraction of a
/// percent of 1, so that the image's mean is the raw one's exactly. An image
/// the filter left unbiased stays as it is; its detail stays in any case.
pub fn preserve_local_mean(denoised: &mut [f32], raw: &[f32], width: usize, height: usize) {
    use rayon::prelude::*;
    assert_eq!(denoised.len(), raw.len());
    assert_eq!(raw.len(), width * height * 3);
    if raw.is_empty() {
        return;
    }
    // Three boxes of 2r + 1 pixels: variance 3((2r + 1)² − 1)/12 = σ².
    let radius = (((4.0 * MEAN_WINDOW_SIGMA * MEAN_WINDOW_SIGMA + 1.0).sqrt() - 1.0) / 2.0).round() as usize;
    let channel = |v: &[f32], c: usize| v.iter().skip(c).step_by(3).map(|&x| f64::from(x)).collect::<Vec<f64>>();
    // The six smoothings (two images, three channels) are independent.
    let mut smoothed: Vec<Vec<f64>> = (0..6)
        .map(|k| channel(if k < 3 { denoised } else { raw }, k % 3))
        .collect();
    smoothed.par_iter_mut().for_each(|v| {
        for _ in 0..3 {
            box_sum(v, width, height, radius);
        }
    });
    for c in 0..3 {
        let (kd, kr) = (&smoothed[c], &smoothed[c + 3]);
        // Kd = 0: nothing lit in the window, the pixel itself included.
        let local: Vec<f64> = denoised
            .iter()
            .skip(c)
            .step_by(3)
            .zip(kd.iter().zip(kr))
            .map(|(&d, (&kd, &kr))| if kd > 0.0 { f64::from(d) * kr / kd } else { f64::from(d) })
            .collect();
        let total: f64 = local.iter().sum();
        let want: f64 = raw.iter().skip(c).step_by(3).map(|&x| f64::from(x)).sum();
        let global = if total > 0.0 { want / total } else { 1.0 };
        for (v, l) in denoised.iter_mut().skip(c).step_by(3).zip(local) {
            *v = (l * global) as f32;
        }
    }
}

/// Index `i` of a line of `len` pixels mirrored at its ends (pixel `−1 − i`
/// is pixel `i`); one reflection suffices for `−len ≤ i < 2 len`.
fn mirror(i: isize, len: usize) -> usize {
    let len = len as isize;
    (if i < 0 {
        -1 - i
    } else if i >= len {
        2 * len - 1 - i
    } else {
        i
    }) as usize
}

/// Sum over the `(2r + 1)²` box around each pixel, in place, the image
/// mirrored at its border: a symmetric operator whose rows all sum to
/// `(2r + 1)²`, so a uniform image stays uniform up to the border. Running
/// sums along each row, then over whole rows.
fn box_sum(v: &mut [f64], width: usize, height: usize, r: usize) {
    let rx = r.min(width - 1);
    let mut line = vec![0.0; width + 2 * rx];
    for row in v.chunks_exact_mut(width) {
        for (i, l) in line.iter_mut().enumerate() {
            *l = row[mirror(i as isize - rx as isize, width)];
        }
        let mut sum: f64 = line[..2 * rx + 1].iter().sum();
        for x in 0..width {
            row[x] = sum;
            if x + 1 < width {
                sum += line[x + 2 * rx + 1] - line[x];
            }
        }
    }
    let ry = r.min(height - 1) as isize;
    let source = v.to_vec();
    let row = |y: isize| &source[mirror(y, height) * width..][..width];
    let mut sum = vec![0.0; width];
    for y in -ry..=ry {
        sum.iter_mut().zip(row(y)).for_each(|(s, x)| *s += x);
    }
    for (y, out) in v.chunks_exact_mut(width).enumerate() {
        out.copy_from_slice(&sum);
        let y = y as isize;
        if y + 1 < height as isize {
            for ((s, add), sub) in sum.iter_mut().zip(row(y + ry + 1)).zip(row(y - ry)) {
                *s += add - sub;
            }
        }
    }
}

#[cfg(feature = "denoise")]
fn run(
    input: &[f32],
    width: u32,
    height: u32,
    guides: Option<Guides>,
    quality: DenoiseQuality,
) -> Result<Vec<f32>, DenoiseError> {
    use std::sync::{Mutex, PoisonError};
    // One CPU device for the process: creating it took about 0.1 s here,
    // more than filtering 256×256 pixels, which the viewer and `caustic
    // converge` would otherwise pay at every image. A caller holds it while filtering
    // (OIDN devices are not to be used by two threads at once).
    static DEVICE: Mutex<Option<oidn::Device>> = Mutex::new(None);
    let fail = |e: oidn::Error| DenoiseError::Oidn(format!("{}: {}", e.kind().as_str(), e.message()));
    let mut cached = DEVICE.lock().unwrap_or_else(PoisonError::into_inner);
    let device = match cached.take() {
        Some(device) => device,
        None => oidn::Device::cpu().map_err(fail)?,
    };
    let output = filter_with(&device, input, width, height, guides, quality).map_err(fail);
    *cached = Some(device);
    output
}

#[cfg(feature = "denoise")]
fn filter_with(
    device: &oidn::Device,
    input: &[f32],
    width: u32,
    height: u32,
    guides: Option<Guides>,
    quality: DenoiseQuality,
) -> Result<Vec<f32>, oidn::Error> {
    let mut filter = oidn::RayTracing::try_new(device)?;
    filter
        .hdr(true)
        .filter_quality(match quality {
            DenoiseQuality::High => oidn::Quality::High,
            DenoiseQuality::Balanced => oidn::Quality::Balanced,
            DenoiseQuality::Fast => oidn::Quality::Fast,
        })
        .image_dimensions(width as usize, height as usize);
    let aux = guides.map(|g| {
        (
            flatten(g.albedo, |v| if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 }),
            flatten(g.normal, |v| if v.is_finite() { v.clamp(-1.0, 1.0) } else { 0.0 }),
        )
    });
    if let Some((albedo, normal)) = &aux {
        // Not `clean_aux`: the crate passes it under a name OIDN ignores
        // ("clean_aux" for "cleanAux"), and the clean-guide network measured
        // more error on caustic's guides below a few dozen spp (module doc).
        filter.albedo_normal(albedo, normal);
    }
    let mut output = vec![0.0f32; input.len()];
    filter.filter(input, &mut output)?;
    Ok(output)
}

#[cfg(not(feature = "denoise"))]
fn run(_: &[f32], _: u32, _: u32, _: Option<Guides>, _: DenoiseQuality) -> Result<Vec<f32>, DenoiseError> {
    Err(DenoiseError::Unavailable)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Rng;

    /// A smooth gradient with strong per-pixel noise: the denoised image
    /// must be much closer to the clean one than the noisy input.
    #[cfg(feature = "denoise")]
    #[test]
    fn denoising_removes_most_of_synthetic_noise() {
        let (w, h) = (64u32, 48u32);
        let mut clean = Film::new(w, h);
        let mut noisy = Film::new(w, h);
        let mut rng = Rng::new(7, crate::math::rng::Domain::Analysis, 0, 0);
        for y in 0..h {
            for x in 0..w {
                let v = Vec3::new(0.2 + 0.6 * x as f32 / w as f32, 0.5, 0.3 + 0.4 * y as f32 / h as f32);
                clean.set(x, y, v);
                // Multiplicative noise with mean 1 (an estimator's kind).
                let n = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0;
                noisy.set(x, y, v * n);
            }
        }
        let albedo = Film {
            width: w,
            height: h,
            pixels: vec![Vec3::splat(0.8); (w * h) as usize],
        };
        let normal = Film {
            width: w,
            height: h,
            pixels: vec![Vec3::Z; (w * h) as usize],
        };
        let mse = |a: &Film| {
            a.pixels
                .iter()
                .zip(&clean.pixels)
                .map(|(p, q)| (*p - *q).length_squared())
                .sum::<f32>()
                / a.pixels.len() as f32
        };
        let guided = Some(Guides {
            albedo: &albedo,
            normal: &normal,
        });
        for (guides, quality) in [
            (None, DenoiseQuality::High),
            (guided, DenoiseQuality::High),
            (guided, DenoiseQuality::Balanced),
            (guided, DenoiseQuality::Fast),
        ] {
            let (out, stats) = denoise(&noisy, guides, quality).unwrap();
            assert_eq!(stats.quality, quality);
            // The process's one device gives the same image again.
            let (again, _) = denoise(&noisy, guides, quality).unwrap();
            assert_eq!(out.pixels, again.pixels, "{quality:?}");
            assert_eq!((out.width, out.height), (w, h));
            assert!(out.pixels.iter().all(|p| p.is_finite()));
            let (before, after) = (mse(&noisy), mse(&out));
            assert!(
                after < before / 10.0,
                "MSE {before} → {after} (guides: {}, {quality:?})",
                guides.is_some()
            );
            assert!(stats.time > Duration::ZERO);
        }
    }

    #[cfg(not(feature = "denoise"))]
    #[test]
    fn without_the_feature_denoising_names_it() {
        let film = Film::new(2, 2);
        let e = denoise(&film, None, DenoiseQuality::High).unwrap_err();
        assert!(e.to_string().contains("`denoise` feature"), "{e}");
        assert!(require().is_err() && !available() && library().is_none());
        let _ = Rng::new(1, crate::math::rng::Domain::Analysis, 0, 0);
    }

    /// An image the filter left as it was comes back unchanged.
    #[test]
    fn the_mean_correction_leaves_an_unbiased_image_alone() {
        let (w, h) = (70usize, 50usize);
        let mut rng = Rng::new(5, crate::math::rng::Domain::Analysis, 0, 0);
        let raw: Vec<f32> = (0..w * h * 3).map(|_| rng.f32() * 3.0).collect();
        let mut out = raw.clone();
        preserve_local_mean(&mut out, &raw, w, h);
        for (a, b) in out.iter().zip(&raw) {
            assert!((a - b).abs() <= 1e-5 * b.max(1.0), "{a} ≠ {b}");
        }
    }

    /// A firefly the filter removed gives its light back around its place:
    /// the sums are the raw ones, pixels beyond the window (3 × 16 px) keep
    /// their value, and the light went to the firefly's neighbourhood.
    #[test]
    fn the_mean_correction_gives_a_removed_fireflys_light_back_where_it_was() {
        let (w, h) = (160usize, 120usize);
        let at = |x: usize, y: usize| (y * w + x) * 3;
        let mut raw = vec![0.5f32; w * h * 3];
        for c in 0..3 {
            raw[at(30, 40) + c] = 500.0 * (c + 1) as f32;
        }
        let mut out = vec![0.5f32; w * h * 3];
        preserve_local_mean(&mut out, &raw, w, h);
        for c in 0..3 {
            let sum = |v: &[f32]| v.iter().skip(c).step_by(3).map(|&x| f64::from(x)).sum::<f64>();
            let (want, got) = (sum(&raw), sum(&out));
            assert!((got / want - 1.0).abs() < 1e-6, "channel {c}: sum {got}, raw {want}");
            // Far away: as denoised (the global step moves it by < 0.1 %).
            assert!((out[at(150, 110) + c] - 0.5).abs() < 5e-4, "{}", out[at(150, 110) + c]);
            // Near: brighter, smoothly (no firefly comes back).
            let (centre, beside) = (out[at(30, 40) + c], out[at(40, 40) + c]);
            assert!(
                centre > beside && beside > 0.5 && centre < 0.5 + (c + 1) as f32,
                "{centre}, {beside}"
            );
        }
    }

    #[test]
    fn guides_of_another_size_are_refused() {
        let film = Film::new(4, 4);
        let small = Film::new(2, 2);
        let guides = Guides {
            albedo: &small,
            normal: &small,
        };
        assert!(matches!(
            denoise(&film, Some(guides), DenoiseQuality::High),
            Err(DenoiseError::Size(2, 2, 4, 4))
        ));
    }
}
