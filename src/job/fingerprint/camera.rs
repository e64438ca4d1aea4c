//! The camera's encoding: its rays and the pixel filter that spreads them.

use super::encoder::{Encoder, Fingerprint};
use crate::film::filter::PixelFilter;
use crate::scene::{Camera, FovAxis, Projection};

impl Fingerprint for Camera {
    fn encode(&self, e: &mut Encoder) {
        let Camera {
            position,
            forward,
            right,
            up,
            fov_deg,
            fov_axis,
            aperture_radius,
            focus_distance,
            near_clip,
            filter,
            projection,
        } = self;
        e.tag("camera");
        e.put(position);
        e.put(forward);
        e.put(right);
        e.put(up);
        e.f32(*fov_deg);
        e.u8(match fov_axis {
            FovAxis::X => 0,
            FovAxis::Y => 1,
            FovAxis::Diagonal => 2,
            FovAxis::Smaller => 3,
            FovAxis::Larger => 4,
        });
        // A pinhole's focus distance changes no ray.
        let lens = self.has_lens().then_some([*aperture_radius, *focus_distance]);
        e.option(lens.as_ref(), |e, l| e.floats(l));
        e.f32(*near_clip);
        e.put(filter);
        // Appended only when not the perspective every earlier camera had.
        if let Projection::Orthographic {
            half_width,
            half_height,
        } = projection
        {
            e.tag("orthographic");
            e.floats(&[*half_width, *half_height]);
        }
    }
}

impl Fingerprint for PixelFilter {
    fn encode(&self, e: &mut Encoder) {
        e.tag("pixel filter");
        match self {
            PixelFilter::Box { radius } => {
                e.u8(0);
                e.f32(*radius);
            }
            PixelFilter::Tent { radius } => {
                e.u8(1);
                e.f32(*radius);
            }
            // The table follows from σ.
            PixelFilter::Gaussian { stddev, cdf: _ } => {
                e.u8(2);
                e.f32(*stddev);
            }
        }
    }
}
