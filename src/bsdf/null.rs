//! Mitsuba's `null` BSDF: a surface that scatters nothing. Every ray passes
//! straight through it, unchanged: a delta transmission of weight 1 with
//! index ratio 1, the boundary of a medium whose index matches its
//! surroundings.

use super::BsdfSample;
use crate::math::Vec3A;

/// The pass-through lobe.
#[derive(Clone, Copy, Debug)]
pub struct Null;

impl Null {
    /// The only direction: straight on, `wi = −wo`, with throughput 1
    /// (`f |cos θi| / pdf = 1` for `pdf = 1`).
    pub fn sample(&self, wo: Vec3A) -> Option<BsdfSample> {
        let cos = wo.z.abs();
        if cos == 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi: -wo,
            f: Vec3A::splat(1.0 / cos),
            pdf: 1.0,
            delta: true,
            transmission: true,
            eta: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_straight_through_with_unit_weight() {
        let wo = Vec3A::new(0.3, -0.2, 0.6).normalize();
        let s = Null.sample(wo).expect("a direction");
        assert_eq!(s.wi, -wo);
        assert!((s.weight() - Vec3A::ONE).abs().max_element() < 1e-6);
        assert!(s.delta && s.transmission && s.eta == 1.0);
        assert!(Null.sample(Vec3A::X).is_none());
    }
}
