//! The error metrics (RMSE, relMSE, MAE) of an image against the reference,
//! and the reading of the reference EXR.

use super::ConvergeError;
use crate::film::Film;
use crate::limits::check_image_limits;
use crate::math::Vec3;
use std::path::Path;

/// Default ε of relMSE (Rousselle et al. 2011 use 1e-2 as well).
pub const RELMSE_EPSILON: f64 = 1e-2;

/// Errors of one image against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Root mean squared error.
    pub rmse: f64,
    /// Relative MSE, `(x − r)² / (r² + ε)` averaged.
    pub relmse: f64,
    /// Mean absolute error.
    pub mae: f64,
}

/// [`ConvergeError::SizeMismatch`] unless an image of `size` can be compared
/// with `reference`.
pub(super) fn check_same_size((width, height): (u32, u32), reference: &Film) -> Result<(), ConvergeError> {
    if (width, height) == (reference.width, reference.height) {
        Ok(())
    } else {
        Err(ConvergeError::SizeMismatch(
            width,
            height,
            reference.width,
            reference.height,
        ))
    }
}

/// Compares `image` with `reference` over all pixels and the three channels
/// (see the `converge` module documentation for the formulas).
pub fn error_metrics(image: &Film, reference: &Film, epsilon: f64) -> Result<ErrorMetrics, ConvergeError> {
    check_same_size((image.width, image.height), reference)?;
    let (mut se, mut rel, mut abs) = (0.0f64, 0.0f64, 0.0f64);
    for (x, r) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (x, r) = (x[c] as f64, r[c] as f64);
            let d = x - r;
            se += d * d;
            rel += d * d / (r * r + epsilon);
            abs += d.abs();
        }
    }
    let n = (image.pixels.len() * 3).max(1) as f64;
    Ok(ErrorMetrics {
        rmse: (se / n).sqrt(),
        relmse: rel / n,
        mae: abs / n,
    })
}

/// Reads the first RGB(A) layer of an EXR file as a linear film (alpha is
/// ignored). The header is read first: when `expected` is given and the
/// layer's size differs, [`ConvergeError::ResolutionMismatch`] is returned
/// before any pixel is allocated. NaN or infinite pixels are an error.
pub fn read_exr(path: &Path, expected: Option<(u32, u32)>) -> Result<Film, ConvergeError> {
    use exr::prelude::*;
    let read_error = |source| ConvergeError::ReadReference {
        path: path.to_path_buf(),
        source,
    };
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(read_error)?;
    let bad = |reason: String| ConvergeError::BadReference {
        path: path.to_path_buf(),
        reason,
    };
    let size = meta
        .headers
        .first()
        .map(|h| h.layer_size)
        .ok_or_else(|| bad("the file has no image layer".into()))?;
    if let Some((width, height)) = expected {
        if (size.width(), size.height()) != (width as usize, height as usize) {
            return Err(ConvergeError::ResolutionMismatch {
                path: path.to_path_buf(),
                ref_width: size.width(),
                ref_height: size.height(),
                width,
                height,
            });
        }
    }
    let too_large = || bad(format!("{}×{} pixels is too large", size.width(), size.height()));
    let width = u32::try_from(size.width()).map_err(|_| too_large())?;
    let height = u32::try_from(size.height()).map_err(|_| too_large())?;
    // The film is checked against the memory budget before it is allocated.
    check_image_limits(width, height, 1).map_err(|e| bad(format!("reference image: {e}")))?;
    let image = read_first_rgba_layer_from_file(
        path,
        |res: Vec2<usize>, _| Film::new(res.width() as u32, res.height() as u32),
        |film: &mut Film, pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
            film.set(pos.x() as u32, pos.y() as u32, Vec3::new(r, g, b));
        },
    )
    .map_err(read_error)?;
    let film = image.layer_data.channel_data.pixels;
    if let Some(i) = film.pixels.iter().position(|p| !p.is_finite()) {
        return Err(ConvergeError::NonFiniteReference {
            path: path.to_path_buf(),
            x: i as u32 % film.width,
            y: i as u32 / film.width,
            value: film.pixels[i].to_array(),
        });
    }
    Ok(film)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) -> Film {
        let mut film = Film::new(w, h);
        for y in 0..h {
            for x in 0..w {
                film.set(x, y, f(x, y));
            }
        }
        film
    }

    #[test]
    fn metrics_of_a_constant_offset() {
        let reference = film(4, 3, |_, _| Vec3::ONE);
        let image = film(4, 3, |_, _| Vec3::splat(1.5));
        let e = error_metrics(&image, &reference, 0.01).unwrap();
        assert!((e.rmse - 0.5).abs() < 1e-12, "{e:?}");
        assert!((e.mae - 0.5).abs() < 1e-12);
        assert!((e.relmse - 0.25 / 1.01).abs() < 1e-12);
        // Identical images: all zero.
        let z = error_metrics(&reference, &reference, 0.01).unwrap();
        assert_eq!((z.rmse, z.relmse, z.mae), (0.0, 0.0, 0.0));
    }

    #[test]
    fn metrics_per_channel_and_epsilon() {
        // Reference (2, 0, 0) everywhere, image off by (+1, −2, 0): squared
        // errors 1, 4, 0 → MSE 5/3; relMSE = (1/(4+ε) + 4/ε + 0)/3.
        let reference = film(3, 2, |_, _| Vec3::new(2.0, 0.0, 0.0));
        let image = film(3, 2, |_, _| Vec3::new(3.0, -2.0, 0.0));
        for eps in [1e-2, 1.0] {
            let e = error_metrics(&image, &reference, eps).unwrap();
            assert!((e.rmse - (5.0f64 / 3.0).sqrt()).abs() < 1e-12);
            assert!((e.mae - 1.0).abs() < 1e-12);
            let want = (1.0 / (4.0 + eps) + 4.0 / eps) / 3.0;
            assert!((e.relmse - want).abs() < 1e-9 * want, "{} vs {want}", e.relmse);
        }
        // Half the pixels off by 2: MSE 2, RMSE √2.
        let half = film(3, 2, |x, _| Vec3::splat(if x == 0 { 1.0 } else { 0.0 }));
        let zero = film(3, 2, |x, _| Vec3::splat(if x == 0 { 3.0 } else { 0.0 }));
        let e = error_metrics(&zero, &half, 0.01).unwrap();
        assert!((e.rmse - (4.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert!(matches!(
            error_metrics(&film(2, 2, |_, _| Vec3::ZERO), &half, 0.01),
            Err(ConvergeError::SizeMismatch(2, 2, 3, 2))
        ));
    }

    #[test]
    fn exr_reader_round_trips_and_checks_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ref.exr");
        let f = film(5, 3, |x, y| Vec3::new(x as f32 * 0.25, y as f32 + 0.5, 1e-4 * x as f32));
        crate::film::write_exr(&path, &f).unwrap();
        assert_eq!(read_exr(&path, Some((5, 3))).unwrap(), f);
        assert_eq!(read_exr(&path, None).unwrap(), f);
        let e = read_exr(&path, Some((4, 3))).unwrap_err().to_string();
        assert!(e.contains("5×3") && e.contains("4×3") && e.contains("ref.exr"), "{e}");
        // Not an EXR, and a missing file: the path is named.
        let junk = dir.path().join("junk.exr");
        std::fs::write(&junk, b"not an exr at all").unwrap();
        let e = read_exr(&junk, None).unwrap_err().to_string();
        assert!(e.contains("junk.exr"), "{e}");
        let e = read_exr(&dir.path().join("missing.exr"), None).unwrap_err().to_string();
        assert!(e.contains("missing.exr"), "{e}");
        // A NaN pixel is refused.
        let mut nan = f.clone();
        nan.set(2, 1, Vec3::new(0.0, f32::NAN, 0.0));
        crate::film::write_exr(&path, &nan).unwrap();
        let e = read_exr(&path, None).unwrap_err().to_string();
        assert!(e.contains("(2, 1)"), "{e}");
    }
}
