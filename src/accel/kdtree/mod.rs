//! The in-house two-level SAH KD-tree. (Scaffold: delegates to brute force until the real tree lands.)

use super::{brute::BruteForce, Accel, AccelOptions, AccelStats, Hit};
use crate::math::Ray;
use crate::scene::Scene;

/// Two-level KD-tree accelerator.
pub struct KdTreeAccel(BruteForce);

impl KdTreeAccel {
    /// Builds the tree.
    pub fn build(scene: &Scene, options: &AccelOptions) -> Self {
        Self(BruteForce::new(scene, options.triangle_test))
    }
}

impl Accel for KdTreeAccel {
    fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        self.0.intersect(ray, t_max)
    }
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.0.occluded(ray, t_max)
    }
    fn stats(&self) -> AccelStats {
        self.0.stats()
    }
}
