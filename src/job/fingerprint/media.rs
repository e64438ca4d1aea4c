//! Media's encoding: the homogeneous media, which side of which object
//! they fill, the camera's medium and how null surfaces are crossed.

use super::encoder::{Encoder, Fingerprint};
use crate::scene::{HomogeneousMedium, Media, MediumInterface, PassThrough, PhaseFunction};

impl Fingerprint for Media {
    fn encode(&self, e: &mut Encoder) {
        let Media {
            list,
            interfaces,
            camera,
            pass_through,
        } = self;
        e.tag("media");
        e.u64(list.len() as u64);
        for m in list {
            e.put(m);
        }
        e.u64(interfaces.len() as u64);
        for i in interfaces {
            let MediumInterface { interior, exterior } = i;
            e.option(interior.as_ref(), |e, m| e.u32(*m));
            e.option(exterior.as_ref(), |e, m| e.u32(*m));
        }
        e.option(camera.as_ref(), |e, m| e.u32(*m));
        e.u8(match pass_through {
            PassThrough::Volumetric => 0,
            PassThrough::SurfaceBounce => 1,
        });
    }
}

impl Fingerprint for HomogeneousMedium {
    fn encode(&self, e: &mut Encoder) {
        // The name only labels messages.
        let HomogeneousMedium {
            name: _,
            sigma_t,
            albedo,
            phase,
            sample_emitters,
        } = self;
        e.tag("homogeneous medium");
        e.put(sigma_t);
        e.put(albedo);
        match phase {
            PhaseFunction::Isotropic => e.u8(0),
            PhaseFunction::HenyeyGreenstein { g } => {
                e.u8(1);
                e.f32(*g);
            }
        }
        e.bool(*sample_emitters);
    }
}
