//! Resource limits checked before anything large is allocated: image size,
//! samples and photon counts against fixed bounds and the memory budget
//! ([`crate::memory::budget`]). Shared by the scene loader, the
//! command-line overrides, checkpoints and the analysis commands.

use crate::memory;
use thiserror::Error;

/// Largest image width or height.
pub const MAX_IMAGE_SIDE: u32 = 65536;
/// Largest `width × height × spp` (camera samples of one render).
pub const MAX_CAMERA_SAMPLES: u64 = 1 << 40;
/// Most samples per pixel (2^20): beyond it a render never ends in practice,
/// whatever the image size.
pub const MAX_SPP: u32 = 1 << 20;
/// Film memory budgeted per pixel (linear RGB sums and sums of squares in
/// f64 plus a sample count, rounded up): used to refuse images whose film
/// alone could not be allocated.
pub const FILM_BYTES_PER_PIXEL: u64 = 64;
/// Largest film memory accepted (bytes): 16 GiB, i.e. 268 million pixels.
pub const MAX_FILM_BYTES: u64 = 16 << 30;
/// Largest photon count: photon indices are u32 in the k-d tree.
pub const MAX_PHOTONS: u64 = u32::MAX as u64;
/// Bytes per photon at the peak of the photon map's build, rounded up: the
/// chunks' positions (12), kiddo's leaves and `usize` sort index (24), the
/// chunk order (4), records (8) and, for the debug overlay, coarse positions
/// (6), plus slack for the reordering of records and coarse positions that
/// follows (`integrator::photon::map`).
pub const PEAK_BYTES_PER_PHOTON: u64 = 56;

/// An image size beyond the limits (memory is checked before any allocation).
#[derive(Debug, Error, PartialEq)]
pub enum ImageLimit {
    /// The film would not fit the memory limit.
    #[error("{0}")]
    Film(String),
    /// Too many camera samples.
    #[error("{0}")]
    Samples(String),
}

/// Checks `width × height × spp` against the film-memory and sample limits;
/// shared by the scene loader and the CLI's overrides.
pub fn check_image_limits(width: u32, height: u32, spp: u32) -> Result<(), ImageLimit> {
    if spp > MAX_SPP {
        return Err(ImageLimit::Samples(format!(
            "{spp} spp: at most {MAX_SPP} samples per pixel"
        )));
    }
    if width == 0 || height == 0 || spp == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(ImageLimit::Film(format!(
            "{width}×{height} pixels, {spp} spp: width and height must be in 1..={MAX_IMAGE_SIDE} and spp ≥ 1"
        )));
    }
    let pixels = width as u64 * height as u64;
    let film_bytes = pixels * FILM_BYTES_PER_PIXEL;
    if film_bytes > MAX_FILM_BYTES {
        return Err(ImageLimit::Film(format!(
            "{width}×{height} pixels need {:.1} GiB of film ({FILM_BYTES_PER_PIXEL} bytes per pixel), \
             more than the {} GiB limit",
            film_bytes as f64 / (1u64 << 30) as f64,
            MAX_FILM_BYTES >> 30
        )));
    }
    // Before allocating: the film must fit the memory budget (CAUSTIC_MEMORY_LIMIT or MemAvailable).
    if let Ok(Some(budget)) = memory::budget() {
        if film_bytes > budget.bytes {
            return Err(ImageLimit::Film(format!(
                "{width}×{height} pixels need {} of film ({FILM_BYTES_PER_PIXEL} bytes per pixel), {budget}",
                memory::format_bytes(film_bytes)
            )));
        }
    }
    let samples = pixels * spp as u64;
    if samples > MAX_CAMERA_SAMPLES {
        return Err(ImageLimit::Samples(format!(
            "{width}×{height} pixels × {spp} spp = {samples} camera samples, more than the limit of 2^40"
        )));
    }
    Ok(())
}

/// Checks a photon count against [`MAX_PHOTONS`] and against the memory
/// budget (the photon map's peak while it is built, [`PEAK_BYTES_PER_PHOTON`]
/// per photon, must fit); shared by the loader and the command-line overrides.
pub fn check_photon_count(count: u64) -> Result<(), String> {
    if count > MAX_PHOTONS {
        return Err(format!(
            "{count} photons: at most {MAX_PHOTONS} (photon indices are 32-bit)"
        ));
    }
    let per = PEAK_BYTES_PER_PHOTON;
    let needed = count.saturating_mul(per);
    if let Ok(Some(budget)) = memory::budget() {
        if needed > budget.bytes {
            return Err(format!(
                "{count} photons need up to {} while the photon map is built ({per} bytes per photon), {budget}",
                memory::format_bytes(needed)
            ));
        }
    }
    Ok(())
}
