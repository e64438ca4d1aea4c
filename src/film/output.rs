//! Image output. Both writers are atomic: the image is written to a temporary
//! file in the target's directory, flushed and fsynced, then renamed over the
//! target, so a crash or a full disk never leaves a truncated image behind and
//! readers see either the old file or the new one.

use super::tonemap::{tonemap_to_srgb8, OutputSettings};
use super::Film;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// An image could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// A file-system operation failed.
    #[error("{}: {what}: {source}", path.display())]
    Io {
        /// The file or directory concerned.
        path: PathBuf,
        /// What was being done.
        what: &'static str,
        /// The cause.
        source: std::io::Error,
    },
    /// The PNG encoder failed.
    #[error("{}: PNG encoding failed: {source}", path.display())]
    Png {
        /// The target file.
        path: PathBuf,
        /// The cause.
        source: image::ImageError,
    },
    /// The EXR encoder failed.
    #[error("{}: EXR encoding failed: {source}", path.display())]
    Exr {
        /// The target file.
        path: PathBuf,
        /// The cause.
        source: exr::error::Error,
    },
    /// The target cannot be written (checked before rendering).
    #[error("{}: cannot write output: {reason}", path.display())]
    NotWritable {
        /// The target file.
        path: PathBuf,
        /// Why.
        reason: String,
    },
}

/// Directory a file will be created in (`.` for a bare file name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Checks before a render that `path` can be written: its directory exists,
/// is a directory, and accepts a new file (a temporary file is created and
/// removed), and `path` itself is not a directory.
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    let dir = parent_dir(path);
    let not_writable = |reason: String| OutputError::NotWritable {
        path: path.to_path_buf(),
        reason,
    };
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(not_writable(format!("{} is not a directory", dir.display()))),
        Err(e) => return Err(not_writable(format!("directory {}: {e}", dir.display()))),
    }
    if path.is_dir() {
        return Err(not_writable("is a directory".into()));
    }
    let probe = tempfile::Builder::new()
        .prefix(".caustic-write-check-")
        .tempfile_in(&dir)
        .map_err(|e| not_writable(format!("directory {} is not writable: {e}", dir.display())))?;
    probe
        .close()
        .map_err(|e| not_writable(format!("removing the probe file in {}: {e}", dir.display())))
}

/// Creates the temporary file next to `path`, lets `write` fill it, fsyncs it
/// and renames it over `path` (then fsyncs the directory on Unix so the rename
/// itself is durable). On error the temporary file is removed.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&File>) -> Result<(), OutputError>,
) -> Result<(), OutputError> {
    let io = |what: &'static str| {
        move |source: std::io::Error| OutputError::Io {
            path: path.to_path_buf(),
            what,
            source,
        }
    };
    let dir = parent_dir(path);
    let mut builder = tempfile::Builder::new();
    builder.prefix(".caustic-").suffix(".tmp");
    #[cfg(unix)]
    {
        // The usual mode of a new file (0666 minus the umask, applied by
        // open(2)), not tempfile's private 0600: the mode survives the rename.
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(&dir)
        .map_err(io("creating a temporary file in the output directory"))?;
    {
        // 1 MiB: multi-GiB files (photon maps) in few system calls.
        let mut buffered = BufWriter::with_capacity(1 << 20, tmp.as_file());
        write(&mut buffered)?;
        buffered.flush().map_err(io("writing"))?;
    }
    tmp.as_file().sync_all().map_err(io("syncing"))?;
    tmp.persist(path).map_err(|e| OutputError::Io {
        path: path.to_path_buf(),
        what: "renaming the temporary file over the target",
        source: e.error,
    })?;
    #[cfg(unix)]
    {
        // Durability of the rename; failure here does not lose the image.
        if let Ok(d) = File::open(&dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// Writes the tone-mapped film as an 8-bit sRGB PNG (tone curve and exposure
/// from `settings`), atomically.
///
/// ```
/// use caustic::film::{write_exr, write_png, Film, OutputSettings};
/// use caustic::math::Vec3;
///
/// let mut film = Film::new(4, 2);
/// film.set(1, 0, Vec3::new(4.0, 1.0, 0.25)); // linear radiance, HDR
/// let dir = tempfile::tempdir()?;
/// write_png(&dir.path().join("a.png"), &film, &OutputSettings::default())?;
/// write_exr(&dir.path().join("a.exr"), &film)?; // linear, unclamped
/// // An unwritable path is an error naming it, and leaves nothing behind.
/// let bad = dir.path().join("no-such-dir/a.png");
/// assert!(write_png(&bad, &film, &OutputSettings::default()).is_err());
/// assert!(!bad.exists());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_png(path: &Path, film: &Film, settings: &OutputSettings) -> Result<(), OutputError> {
    use image::ImageEncoder;
    let bytes = tonemap_to_srgb8(film, settings);
    write_atomically(path, |w| {
        image::codecs::png::PngEncoder::new(w)
            .write_image(&bytes, film.width, film.height, image::ExtendedColorType::Rgb8)
            .map_err(|source| OutputError::Png {
                path: path.to_path_buf(),
                source,
            })
    })
}

/// Writes the film's linear radiance as an RGB f32 OpenEXR file, atomically.
pub fn write_exr(path: &Path, film: &Film) -> Result<(), OutputError> {
    use exr::prelude::*;
    let width = film.width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = film.pixels[y * width + x];
        (p.x, p.y, p.z)
    });
    let image = Image::from_channels((width, film.height as usize), channels);
    write_atomically(path, |w| {
        image.write().to_buffered(w).map_err(|source| OutputError::Exr {
            path: path.to_path_buf(),
            source,
        })
    })
}

/// Writes the film's `R`, `G`, `B` and the `extra` channels (one f32 per
/// pixel each, row-major, e.g. `error` and `spp`) as a linear EXR, atomically
/// (lossless ZIP compression).
pub fn write_exr_with(path: &Path, film: &Film, extra: &[(&str, &[f32])]) -> Result<(), OutputError> {
    use exr::prelude::*;
    let n = film.width as usize * film.height as usize;
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        channels.push(AnyChannel::new(
            name,
            FlatSamples::F32(film.pixels.iter().map(|p| p[c]).collect()),
        ));
    }
    for (name, values) in extra {
        assert_eq!(values.len(), n, "channel {name}: one value per pixel");
        channels.push(AnyChannel::new(*name, FlatSamples::F32(values.to_vec())));
    }
    let size = (film.width as usize, film.height as usize);
    let layer = Layer::new(
        size,
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    let image = Image::from_layer(layer);
    write_atomically(path, |w| {
        image.write().to_buffered(w).map_err(|source| OutputError::Exr {
            path: path.to_path_buf(),
            source,
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    fn leftovers(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(".caustic"))
            .collect()
    }

    fn test_film() -> Film {
        let mut f = Film::new(5, 3);
        for y in 0..3 {
            for x in 0..5 {
                f.set(
                    x,
                    y,
                    Vec3::new(x as f32 * 0.5, y as f32 * 3.25, 1.0e-3 + x as f32 * 100.0),
                );
            }
        }
        f
    }

    #[test]
    fn png_is_written_atomically_and_decodes() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.png");
        std::fs::write(&path, b"old contents").unwrap();
        let settings = OutputSettings {
            tone_map: super::super::ToneMap::Clamp,
            ..Default::default()
        };
        write_png(&path, &test_film(), &settings).unwrap();
        assert!(leftovers(dir.path()).is_empty());
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (5, 3));
        // Pixel (2, 0) = (1.0, 0, 100) clamped → (255, 0, 255).
        assert_eq!(img.get_pixel(2, 0).0, [255, 0, 255]);
        assert_eq!(img.get_pixel(0, 0).0[0], 0);
    }

    /// Outputs get the mode any new file gets (0666 minus the umask), like
    /// a file made by `File::create`, not the temporary file's private 0600.
    #[cfg(unix)]
    #[test]
    fn outputs_have_the_usual_mode() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let plain = dir.path().join("plain");
        std::fs::File::create(&plain).unwrap();
        let usual = std::fs::metadata(&plain).unwrap().permissions().mode() & 0o777;
        let png = dir.path().join("out.png");
        let exr = dir.path().join("out.exr");
        write_png(&png, &test_film(), &OutputSettings::default()).unwrap();
        write_exr(&exr, &test_film()).unwrap();
        for p in [&png, &exr] {
            let mode = std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, usual, "{}: {mode:o}, a new file gets {usual:o}", p.display());
        }
        assert_ne!(usual, 0o600, "the umask hides the difference; the test proves nothing");
    }

    #[test]
    fn exr_round_trips_linear_values() {
        use exr::prelude::*;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.exr");
        let film = test_film();
        write_exr(&path, &film).unwrap();
        assert!(leftovers(dir.path()).is_empty());
        let image = read_first_rgba_layer_from_file(
            &path,
            |res: Vec2<usize>, _| (res.width(), vec![[0f32; 3]; res.area()]),
            |(w, px): &mut (usize, Vec<[f32; 3]>), pos: Vec2<usize>, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = [r, g, b];
            },
        )
        .unwrap();
        let (w, px) = &image.layer_data.channel_data.pixels;
        assert_eq!(*w, 5);
        for (i, p) in film.pixels.iter().enumerate() {
            assert_eq!(px[i], p.to_array(), "pixel {i}");
        }
    }

    #[test]
    fn errors_name_the_path_and_nothing_is_left_behind() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no/such/dir/out.png");
        let e = check_writable(&missing).unwrap_err().to_string();
        assert!(e.contains("no/such/dir/out.png"), "{e}");
        let e = write_png(&missing, &test_film(), &OutputSettings::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("out.png"), "{e}");
        // A directory as the target.
        let e = check_writable(dir.path()).unwrap_err().to_string();
        assert!(e.contains("directory"), "{e}");
        let ok = dir.path().join("fine.exr");
        check_writable(&ok).unwrap();
        assert!(leftovers(dir.path()).is_empty());
        assert!(!ok.exists());
        // Writing over a directory fails at the rename and removes the temp file.
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        std::fs::write(sub.join("x"), b"x").unwrap();
        assert!(write_exr(&sub, &test_film()).is_err());
        assert!(leftovers(dir.path()).is_empty());
    }
}
