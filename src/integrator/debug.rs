//! Debug overlays drawn over a rendered film (the original report's 'p' and
//! 'k' keys): the photon map as points, and boxes (the KD-tree's nodes) as
//! projected wireframes colour-coded by depth.

use super::photon::PhotonMap;
use crate::film::Film;
use crate::math::{Aabb, Vec3, Vec3A};
use crate::scene::{Camera, Scene};

/// Pinhole or orthographic projection of world points onto a `width ×
/// height` film, the inverse of `Camera::ray`.
#[derive(Clone, Copy, Debug)]
pub struct Projector<'c> {
    camera: &'c Camera,
    width: f32,
    height: f32,
    /// The camera's half extents (`Camera::half_extents`).
    half: (f32, f32),
}

/// Points closer to the eye than this (along the view axis) are not drawn.
const NEAR: f32 = 1e-4;

impl<'c> Projector<'c> {
    /// A projector for `camera` and the film size.
    pub fn new(camera: &'c Camera, width: u32, height: u32) -> Self {
        Self {
            camera,
            width: width as f32,
            height: height as f32,
            half: camera.half_extents(width as f32 / height as f32),
        }
    }

    /// Camera-space `(right, up, forward)` coordinates of `p`.
    pub fn view(&self, p: Vec3A) -> Vec3A {
        let d = p - self.camera.position;
        Vec3A::new(
            d.dot(self.camera.right),
            d.dot(self.camera.up),
            d.dot(self.camera.forward),
        )
    }

    /// Film position (pixels, origin top-left, y down) of a camera-space
    /// point in front of the eye.
    pub fn film_of_view(&self, v: Vec3A) -> Option<(f32, f32)> {
        if v.z.is_nan() || v.z <= NEAR {
            return None;
        }
        // Perspective divides by the depth; parallel rays do not.
        let depth = if self.camera.is_orthographic() { 1.0 } else { v.z };
        let sx = v.x / depth / self.half.0;
        let sy = v.y / depth / self.half.1;
        Some(((sx + 1.0) * 0.5 * self.width, (1.0 - sy) * 0.5 * self.height))
    }

    /// Film position of world point `p`, if it is in front of the eye.
    pub fn project(&self, p: Vec3A) -> Option<(f32, f32)> {
        self.film_of_view(self.view(p))
    }
}

fn put(film: &mut Film, x: f32, y: f32, colour: Vec3) {
    if x >= 0.0 && y >= 0.0 && x < film.width as f32 && y < film.height as f32 {
        film.set(x as u32, y as u32, colour);
    }
}

/// Draws every stored photon of `map` as one pixel at its (coarse)
/// position, seen from the scene's camera, coloured by the photon's
/// chromaticity at a bright fixed level (no occlusion: a point cloud, as in
/// the original report's figure 21).
pub fn overlay_photons(film: &mut Film, scene: &Scene, map: &PhotonMap) {
    overlay_photons_seen_by(film, &scene.camera, map, usize::MAX);
}

/// [`overlay_photons`] seen from `camera` (the viewer's, which moves),
/// drawing at most `max_points` photons, evenly spread over the map (a
/// million photons on a 960×540 view would cover it).
pub fn overlay_photons_seen_by(film: &mut Film, camera: &Camera, map: &PhotonMap, max_points: usize) {
    let proj = Projector::new(camera, film.width, film.height);
    let stride = map.len().div_ceil(max_points.max(1)).max(1);
    for i in (0..map.len()).step_by(stride) {
        let Some((x, y)) = map.coarse_position(i).and_then(|p| proj.project(p)) else {
            continue;
        };
        let power = map.record(i).power();
        let m = power.max_element();
        let colour = if m > 0.0 { power / m * 4.0 } else { Vec3A::splat(4.0) };
        put(film, x, y, Vec3::from(colour));
    }
}

/// A bright colour for tree depth `depth`: the hue turns by 40° per level.
pub fn depth_colour(depth: u32) -> Vec3 {
    let h = (depth % 9) as f32 / 9.0 * 6.0;
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    Vec3::new(r, g, b) * 4.0
}

/// Draws the twelve edges of every box, projected through `camera` (edges
/// are clipped at the eye's near plane), colour-coded by the `u32` (the
/// node's depth in the tree, via [`depth_colour`]).
pub fn overlay_boxes(film: &mut Film, camera: &Camera, boxes: &[(Aabb, u32)]) {
    let proj = Projector::new(camera, film.width, film.height);
    for (b, depth) in boxes {
        if b.is_empty() {
            continue;
        }
        let colour = depth_colour(*depth);
        let corner = |i: usize| {
            Vec3A::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            )
        };
        for i in 0..8usize {
            for bit in [1usize, 2, 4] {
                if i & bit == 0 {
                    draw_line(film, &proj, corner(i), corner(i | bit), colour);
                }
            }
        }
    }
}

/// Draws the world segment `a–b`, clipped to the near plane, by stepping
/// one pixel at a time along its projection.
fn draw_line(film: &mut Film, proj: &Projector, a: Vec3A, b: Vec3A, colour: Vec3) {
    let (mut va, mut vb) = (proj.view(a), proj.view(b));
    if va.z <= NEAR && vb.z <= NEAR {
        return;
    }
    // Clip the part behind the near plane (projection is not linear
    // across it).
    if va.z <= NEAR {
        va = vb + (va - vb) * ((vb.z - 2.0 * NEAR) / (vb.z - va.z));
    } else if vb.z <= NEAR {
        vb = va + (vb - va) * ((va.z - 2.0 * NEAR) / (va.z - vb.z));
    }
    let (Some((x0, y0)), Some((x1, y1))) = (proj.film_of_view(va), proj.film_of_view(vb)) else {
        return;
    };
    // Clip to a generous window around the film so that nearly-grazing
    // edges do not loop over millions of off-screen pixels.
    let limit = 4.0 * (film.width.max(film.height) as f32);
    let steps = (x1 - x0).abs().max((y1 - y0).abs()).ceil().min(limit * 2.0);
    if !steps.is_finite() {
        return;
    }
    let n = steps.max(1.0) as u32;
    for s in 0..=n {
        let t = s as f32 / n as f32;
        put(film, x0 + (x1 - x0) * t, y0 + (y1 - y0) * t, colour);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_inverts_camera_rays() {
        let cam = Camera::new(Vec3A::new(1.0, 2.0, 5.0), Vec3A::ZERO, Vec3A::Y, 50.0).unwrap();
        let proj = Projector::new(&cam, 320, 200);
        for (x, y) in [(10.5f32, 20.25f32), (160.0, 100.0), (300.0, 190.0)] {
            let r = cam.ray(x, y, 320, 200);
            let (px, py) = proj.project(r.at(3.7)).unwrap();
            assert!((px - x).abs() < 1e-2 && (py - y).abs() < 1e-2, "{x},{y} → {px},{py}");
        }
        // Behind the camera: not drawn.
        assert!(proj.project(cam.position - cam.forward).is_none());
        let mut ortho = cam.clone();
        ortho.projection = crate::scene::Projection::Orthographic {
            half_width: 1.5,
            half_height: 1.5,
        };
        let proj = Projector::new(&ortho, 320, 200);
        for (x, y) in [(10.5f32, 20.25f32), (160.0, 100.0), (300.0, 190.0)] {
            let r = ortho.ray(x, y, 320, 200);
            let (px, py) = proj.project(r.at(3.7)).unwrap();
            assert!((px - x).abs() < 1e-2 && (py - y).abs() < 1e-2, "{x},{y} → {px},{py}");
        }
    }

    #[test]
    fn boxes_draw_edges_in_their_depth_colour() {
        let cam = Camera::new(Vec3A::new(0.0, 0.0, 5.0), Vec3A::ZERO, Vec3A::Y, 60.0).unwrap();
        let mut film = Film::new(64, 64);
        let b = Aabb::new(Vec3A::splat(-1.0), Vec3A::splat(1.0));
        overlay_boxes(&mut film, &cam, &[(b, 3)]);
        let c = depth_colour(3);
        let drawn = film.pixels.iter().filter(|p| **p == c).count();
        assert!(drawn > 100, "{drawn}");
        // The centre of the front face is not an edge.
        assert_eq!(film.get(32, 32), Vec3::ZERO);
        assert_ne!(depth_colour(0), depth_colour(1));
        // A box around the camera (edges crossing the near plane) is safe.
        overlay_boxes(
            &mut film,
            &cam,
            &[(Aabb::new(Vec3A::splat(-10.0), Vec3A::splat(10.0)), 0)],
        );
    }
}
