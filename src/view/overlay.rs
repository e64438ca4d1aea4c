//! What the window shows: the linear film tone-mapped to 8-bit RGBA at the
//! view's size (a smaller preview is enlarged), and the debug layers of the
//! original report drawn over it (`p`: the photon cloud, `k`: the
//! KD-tree's boxes), both made by the batch renderer's own overlay code.

use crate::film::tonemap::{encode_srgb8, tone_map};
use crate::film::{Film, OutputSettings};
use crate::integrator::debug;
use crate::integrator::photon::PhotonMap;
use crate::math::{Aabb, Vec3};
use crate::scene::Camera;

/// `film` tone-mapped into a `width × height` RGBA8 image (nearest-pixel
/// enlargement when the film is smaller, as for the preview pass).
pub fn display_rgba(film: &Film, output: &OutputSettings, width: u32, height: u32) -> Vec<u8> {
    // Each film pixel is tone-mapped once, then repeated when enlarged.
    let mapped: Vec<[u8; 3]> = film
        .pixels
        .iter()
        .map(|p| encode_srgb8(tone_map(*p, output.tone_map, output.exposure)))
        .collect();
    let (fw, fh) = (film.width.max(1), film.height.max(1));
    let mut out = Vec::with_capacity(width as usize * height as usize * 4);
    for y in 0..height {
        let sy = (y as u64 * fh as u64 / height.max(1) as u64) as u32;
        for x in 0..width {
            let sx = (x as u64 * fw as u64 / width.max(1) as u64) as u32;
            let [r, g, b] = mapped[(sy * fw + sx) as usize];
            out.extend_from_slice(&[r, g, b, 255]);
        }
    }
    out
}

/// The debug layers as a film (black where nothing is drawn).
pub fn debug_layer(
    camera: &Camera,
    width: u32,
    height: u32,
    photons: Option<&PhotonMap>,
    boxes: Option<(&[(Aabb, u32)], u32)>,
) -> Film {
    let mut layer = Film::new(width, height);
    if let Some((boxes, depth)) = boxes {
        let shown: Vec<(Aabb, u32)> = boxes.iter().filter(|(_, d)| *d <= depth).copied().collect();
        debug::overlay_boxes(&mut layer, camera, &shown);
    }
    if let Some(map) = photons {
        // One photon drawn per 8 pixels at most keeps the image readable.
        let most = (width as usize * height as usize / 8).max(1);
        debug::overlay_photons_seen_by(&mut layer, camera, map, most);
    }
    layer
}

/// Paints the non-black pixels of `layer` over `rgba` (same size).
pub fn composite(rgba: &mut [u8], layer: &Film) {
    for (px, c) in rgba.chunks_exact_mut(4).zip(&layer.pixels) {
        if *c != Vec3::ZERO {
            let [r, g, b] = encode_srgb8(c.clamp(Vec3::ZERO, Vec3::ONE));
            px.copy_from_slice(&[r, g, b, 255]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3A;

    #[test]
    fn preview_is_enlarged_to_the_view() {
        let mut film = Film::new(2, 1);
        film.set(1, 0, Vec3::ONE);
        let rgba = display_rgba(&film, &OutputSettings::default(), 4, 2);
        assert_eq!(rgba.len(), 4 * 2 * 4);
        // Left half black, right half bright, on both rows.
        for y in 0..2 {
            assert_eq!(rgba[(y * 4) * 4], 0);
            assert!(rgba[(y * 4 + 3) * 4] > 200);
        }
    }

    #[test]
    fn box_layer_is_composited_over_the_image() {
        let cam = Camera::new(Vec3A::new(0.0, 0.0, 5.0), Vec3A::ZERO, Vec3A::Y, 60.0).unwrap();
        let boxes = vec![(Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0)), 0u32)];
        let layer = debug_layer(&cam, 64, 64, None, Some((&boxes, 0)));
        let mut rgba = vec![0u8; 64 * 64 * 4];
        composite(&mut rgba, &layer);
        assert!(rgba.chunks(4).filter(|p| p[0] > 0 || p[1] > 0).count() > 100);
        // Deeper boxes than the slider are not drawn.
        let deep = vec![(boxes[0].0, 5u32)];
        let none = debug_layer(&cam, 64, 64, None, Some((&deep, 2)));
        assert!(none.pixels.iter().all(|p| *p == Vec3::ZERO));
    }
}
