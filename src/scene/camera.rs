//! The camera: a pinhole or a thin lens (depth of field) with a field of
//! view along a chosen image axis, or an orthographic projection (parallel
//! rays from a rectangle), and a near clipping distance.

use crate::film::filter::PixelFilter;
use crate::math::sampling::concentric_disk;
use crate::math::{Ray, Vec2, Vec3A};

/// Which image extent a field of view spans (Mitsuba's `fov_axis`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FovAxis {
    /// The width.
    X,
    /// The height.
    #[default]
    Y,
    /// The diagonal.
    Diagonal,
    /// The smaller of width and height.
    Smaller,
    /// The larger of width and height.
    Larger,
}

impl FovAxis {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            FovAxis::X => "x",
            FovAxis::Y => "y",
            FovAxis::Diagonal => "diagonal",
            FovAxis::Smaller => "smaller",
            FovAxis::Larger => "larger",
        }
    }

    /// The axis named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        [
            FovAxis::X,
            FovAxis::Y,
            FovAxis::Diagonal,
            FovAxis::Smaller,
            FovAxis::Larger,
        ]
        .into_iter()
        .find(|a| a.name() == name)
    }
}

/// How film positions become rays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Projection {
    /// Rays fan out from the eye (or the lens) across the field of view.
    #[default]
    Perspective,
    /// Parallel rays along the view axis from a rectangle centred on the
    /// eye position. The image shows at least `half_width` either side
    /// horizontally and `half_height` vertically (world units; 0 leaves
    /// that extent to the image's aspect ratio): the image's aspect ratio
    /// wins and extends the other extent, never stretching nor cropping
    /// (glTF 2.0 §3.10.3's advice for `xmag`/`ymag`).
    Orthographic {
        /// Smallest half width shown (≥ 0).
        half_width: f32,
        /// Smallest half height shown (≥ 0; not both 0).
        half_height: f32,
    },
}

impl Projection {
    /// Name as in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Projection::Perspective => "perspective",
            Projection::Orthographic { .. } => "orthographic",
        }
    }
}

/// The vertical half extent of an image of aspect ratio `width / height`
/// whose half extent across `axis` is `half`.
#[inline]
fn vertical_half(axis: FovAxis, half: f32, aspect: f32) -> f32 {
    let horizontal = match axis {
        FovAxis::Y => return half,
        FovAxis::X => true,
        FovAxis::Diagonal => return half / (aspect * aspect + 1.0).sqrt(),
        FovAxis::Smaller => aspect < 1.0,
        FovAxis::Larger => aspect >= 1.0,
    };
    if horizontal {
        half / aspect
    } else {
        half
    }
}

/// A camera looking from `position` towards `look_at`.
///
/// Two cameras are equal when they make the same rays: an orthographic
/// camera's field of view (and its axis) and lens are not compared.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Eye position (the lens centre).
    pub position: Vec3A,
    /// Unit viewing direction.
    pub forward: Vec3A,
    /// Unit right vector (image +x).
    pub right: Vec3A,
    /// Unit up vector (image −y).
    pub up: Vec3A,
    /// Perspective or orthographic.
    pub projection: Projection,
    /// Field of view in degrees, across [`fov_axis`](Self::fov_axis)
    /// (perspective only).
    pub fov_deg: f32,
    /// The image extent the field of view spans (perspective only).
    pub fov_axis: FovAxis,
    /// Lens radius (0: a pinhole, everything sharp).
    pub aperture_radius: f32,
    /// Distance along the view axis of the plane in focus (thin lens).
    pub focus_distance: f32,
    /// Rays start this far along the view axis (nothing nearer is seen).
    pub near_clip: f32,
    /// Pixel reconstruction filter: where in and around its pixel each
    /// camera sample lands.
    pub filter: PixelFilter,
}

impl PartialEq for Camera {
    fn eq(&self, o: &Self) -> bool {
        let perspective = !self.is_orthographic();
        self.position == o.position
            && self.forward == o.forward
            && self.right == o.right
            && self.up == o.up
            && self.projection == o.projection
            && (!perspective
                || (self.fov_deg == o.fov_deg
                    && self.fov_axis == o.fov_axis
                    && self.aperture_radius == o.aperture_radius
                    && self.focus_distance == o.focus_distance))
            && self.near_clip == o.near_clip
            && self.filter == o.filter
    }
}

impl Camera {
    /// A pinhole camera with a vertical field of view; `None` when `look_at
    /// == position`, `up` is parallel to the viewing direction or the field
    /// of view is not in (0°, 180°).
    pub fn new(position: Vec3A, look_at: Vec3A, up: Vec3A, vfov_deg: f32) -> Option<Self> {
        let forward = (look_at - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
            return None;
        }
        Some(Self {
            position,
            forward,
            right,
            up,
            projection: Projection::Perspective,
            fov_deg: vfov_deg,
            fov_axis: FovAxis::Y,
            aperture_radius: 0.0,
            focus_distance: (look_at - position).length(),
            near_clip: 0.0,
            filter: PixelFilter::default(),
        })
    }

    /// `tan(vertical fov / 2)` for an image of aspect ratio `width / height`
    /// (the perspective field of view, whatever the projection).
    #[inline]
    pub fn tan_half_vertical(&self, aspect: f32) -> f32 {
        vertical_half(self.fov_axis, (self.fov_deg.to_radians() * 0.5).tan(), aspect)
    }

    /// True for parallel rays (an orthographic projection).
    #[inline]
    pub fn is_orthographic(&self) -> bool {
        matches!(self.projection, Projection::Orthographic { .. })
    }

    /// Half width and half height of the image on the plane one unit in
    /// front of the eye (perspective: the tangents of the half angles) or
    /// of the orthographic rectangle (world units), for an image of aspect
    /// ratio `width / height`.
    #[inline]
    pub fn half_extents(&self, aspect: f32) -> (f32, f32) {
        let v = match self.projection {
            Projection::Perspective => self.tan_half_vertical(aspect),
            // The rectangle fits: the larger of the two heights it implies.
            Projection::Orthographic {
                half_width,
                half_height,
            } => half_height.max(half_width / aspect),
        };
        (v * aspect, v)
    }

    /// The vertical field of view in degrees for an image of aspect ratio
    /// `width / height`.
    pub fn vertical_fov_deg(&self, aspect: f32) -> f32 {
        2.0 * self.tan_half_vertical(aspect).atan().to_degrees()
    }

    /// True when [`ray_through_lens`](Self::ray_through_lens) needs a lens
    /// sample (an orthographic camera has no lens).
    #[inline]
    pub fn has_lens(&self) -> bool {
        self.aperture_radius > 0.0 && !self.is_orthographic()
    }

    /// Pinhole (or orthographic) ray through film position `(x, y)` in
    /// pixels (origin top-left, y down) of a `width × height` image.
    #[inline]
    pub fn ray(&self, x: f32, y: f32, width: u32, height: u32) -> Ray {
        self.image(width, height).ray(x, y)
    }

    /// Thin-lens ray (pbrt-v4 §5.2.3, Mitsuba's `thinlens`): from the lens
    /// point of `u_lens` (a concentric-disk sample) toward the point of the
    /// focus plane that the pinhole ray through `(x, y)` reaches. A pinhole
    /// camera ignores `u_lens`.
    #[inline]
    pub fn ray_through_lens(&self, x: f32, y: f32, width: u32, height: u32, u_lens: Vec2) -> Ray {
        self.image(width, height).ray_through_lens(x, y, u_lens)
    }

    /// The rays of a `width × height` image: [`ray`](Self::ray) and
    /// [`ray_through_lens`](Self::ray_through_lens) with the image plane's
    /// extents (a tangent of the field of view) computed once.
    #[inline]
    pub fn image(&self, width: u32, height: u32) -> ImageRays<'_> {
        ImageRays {
            camera: self,
            width: width as f32,
            height: height as f32,
            half: self.half_extents(width as f32 / height as f32),
        }
    }

    /// `ray` started at the near plane.
    #[inline]
    fn clipped(&self, ray: Ray) -> Ray {
        if self.near_clip > 0.0 {
            let t = self.near_clip / ray.dir.dot(self.forward);
            Ray::new(ray.at(t), ray.dir)
        } else {
            ray
        }
    }
}

/// The camera rays of one image size ([`Camera::image`]).
#[derive(Clone, Copy, Debug)]
pub struct ImageRays<'a> {
    camera: &'a Camera,
    width: f32,
    height: f32,
    /// [`Camera::half_extents`] of the image's aspect ratio.
    half: (f32, f32),
}

impl ImageRays<'_> {
    /// [`Camera::ray`] of this image.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let c = self.camera;
        if let Projection::Orthographic { .. } = c.projection {
            // Parallel projection (pbrt-v4 §5.1.4, Mitsuba's `orthographic`):
            // the film point on the rectangle through the eye, looking down
            // the view axis.
            let (sx, sy) = self.film_offsets(x, y);
            let origin = c.position + c.right * sx + c.up * sy;
            return c.clipped(Ray::new(origin, c.forward));
        }
        c.clipped(Ray::new(c.position, self.direction(x, y)))
    }

    /// [`Camera::ray_through_lens`] of this image.
    #[inline]
    pub fn ray_through_lens(&self, x: f32, y: f32, u_lens: Vec2) -> Ray {
        let c = self.camera;
        if !c.has_lens() {
            return self.ray(x, y);
        }
        let dir = self.direction(x, y);
        let focus = c.position + dir * (c.focus_distance / dir.dot(c.forward));
        let d = concentric_disk(u_lens) * c.aperture_radius;
        let origin = c.position + c.right * d.x + c.up * d.y;
        c.clipped(Ray::new(origin, (focus - origin).normalize()))
    }

    /// Offsets of film position `(x, y)` along `right` and `up` on the
    /// image plane (see [`Camera::half_extents`]).
    #[inline]
    fn film_offsets(&self, x: f32, y: f32) -> (f32, f32) {
        let (hx, hy) = self.half;
        ((2.0 * x / self.width - 1.0) * hx, (1.0 - 2.0 * y / self.height) * hy)
    }

    #[inline]
    fn direction(&self, x: f32, y: f32) -> Vec3A {
        let (sx, sy) = self.film_offsets(x, y);
        let c = self.camera;
        (c.forward + c.right * sx + c.up * sy).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_forward_and_corners_are_symmetric() {
        let c = Camera::new(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 90.0).unwrap();
        let r = c.ray(50.0, 50.0, 100, 100);
        assert!((r.dir - -Vec3A::Z).length() < 1e-6);
        let tl = c.ray(0.0, 0.0, 100, 100).dir;
        assert!(tl.x < 0.0 && tl.y > 0.0);
        // 90° vertical fov: the top edge is at 45°.
        let top = c.ray(50.0, 0.0, 100, 100).dir;
        assert!((top.y - top.z.abs()).abs() < 1e-5);
        assert!(Camera::new(Vec3A::ZERO, Vec3A::Y, Vec3A::Y, 60.0).is_none());
    }

    #[test]
    fn fov_axes_span_their_extent() {
        let mut c = Camera::new(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 90.0).unwrap();
        let (w, h) = (200, 100);
        // The angle of the ray through film point (x, y) off the view axis, per axis.
        let slope = |c: &Camera, x: f32, y: f32| {
            let d = c.ray(x, y, w, h).dir;
            (d.x / -d.z, d.y / -d.z)
        };
        for (axis, edge) in [
            (FovAxis::X, (200.0, 50.0)),
            (FovAxis::Larger, (200.0, 50.0)),
            (FovAxis::Y, (100.0, 0.0)),
            (FovAxis::Smaller, (100.0, 0.0)),
        ] {
            c.fov_axis = axis;
            let (sx, sy) = slope(&c, edge.0, edge.1);
            // 90°: the extent's edge is at 45°, a slope of 1.
            assert!((sx.abs().max(sy.abs()) - 1.0).abs() < 1e-5, "{axis:?}: {sx} {sy}");
        }
        c.fov_axis = FovAxis::Diagonal;
        let (sx, sy) = slope(&c, 200.0, 0.0);
        assert!(((sx * sx + sy * sy).sqrt() - 1.0).abs() < 1e-5);
        // Portrait: smaller is the width.
        c.fov_axis = FovAxis::Smaller;
        let d = c.ray(100.0, 100.0, 100, 200).dir;
        assert!((d.x / -d.z - 1.0).abs() < 1e-5);
        assert!((c.vertical_fov_deg(0.5) - 2.0 * 2.0f32.atan().to_degrees()).abs() < 1e-3);
    }

    #[test]
    fn thin_lens_rays_meet_on_the_focus_plane() {
        let mut c = Camera::new(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 40.0).unwrap();
        c.aperture_radius = 0.2;
        c.focus_distance = 5.0;
        let pin = c.ray(30.0, 70.0, 100, 100);
        let focus = pin.at(5.0 / pin.dir.dot(c.forward));
        for u in [Vec2::new(0.1, 0.9), Vec2::new(0.5, 0.5), Vec2::new(0.95, 0.2)] {
            let r = c.ray_through_lens(30.0, 70.0, 100, 100, u);
            assert!(r.origin.z == 0.0 && (r.origin.x.hypot(r.origin.y)) <= 0.2 + 1e-6);
            let p = r.at((focus - r.origin).length());
            assert!((p - focus).length() < 1e-4, "{p} {focus}");
        }
        // A pinhole ignores the lens sample.
        c.aperture_radius = 0.0;
        assert_eq!(c.ray_through_lens(30.0, 70.0, 100, 100, Vec2::new(0.9, 0.1)), pin);
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_the_scale() {
        let mut c = Camera::new(Vec3A::new(1.0, 2.0, 3.0), Vec3A::new(1.0, 2.0, 0.0), Vec3A::Y, 60.0).unwrap();
        c.projection = Projection::Orthographic {
            half_width: 2.0,
            half_height: 0.0,
        };
        let (w, h) = (200, 100);
        for (x, y) in [(0.0, 0.0), (100.0, 50.0), (200.0, 100.0), (37.0, 81.0)] {
            let r = c.ray(x, y, w, h);
            assert_eq!(r.dir, -Vec3A::Z);
            // On the plane through the eye, at the film point scaled to the extents.
            assert_eq!(r.origin.z, 3.0);
            let ex = 1.0 + (x / 100.0 - 1.0) * 2.0;
            let ey = 2.0 + (1.0 - y / 50.0) * 1.0;
            assert!(
                (r.origin.x - ex).abs() < 1e-5 && (r.origin.y - ey).abs() < 1e-5,
                "{}",
                r.origin
            );
        }
        assert_eq!(c.half_extents(2.0), (2.0, 1.0));
        // Both extents: the image's aspect ratio extends the binding one's partner.
        c.projection = Projection::Orthographic {
            half_width: 2.0,
            half_height: 2.0,
        };
        assert_eq!(c.half_extents(2.0), (4.0, 2.0));
        assert_eq!(c.half_extents(0.5), (2.0, 4.0));
        c.projection = Projection::Orthographic {
            half_width: 0.0,
            half_height: 1.5,
        };
        assert_eq!(c.half_extents(0.5), (0.75, 1.5));
        // The near clip moves the start along the view axis; a lens is ignored.
        c.near_clip = 0.5;
        c.aperture_radius = 0.3;
        assert!(!c.has_lens());
        let r = c.ray_through_lens(100.0, 50.0, w, h, Vec2::new(0.9, 0.1));
        assert_eq!(r.origin, Vec3A::new(1.0, 2.0, 2.5));
    }

    #[test]
    fn near_clip_starts_rays_on_the_near_plane() {
        let mut c = Camera::new(Vec3A::ZERO, -Vec3A::Z, Vec3A::Y, 60.0).unwrap();
        c.near_clip = 2.0;
        for (x, y) in [(50.0, 50.0), (0.0, 0.0), (99.0, 20.0)] {
            let r = c.ray(x, y, 100, 100);
            assert!((r.origin.dot(c.forward) - 2.0).abs() < 1e-5, "{}", r.origin);
            assert!((r.origin.normalize() - r.dir).length() < 1e-5);
        }
    }
}
