//! Light sampling for the path integrator: one emitter chosen in
//! proportion to its power (so that scenes with many lights spend their
//! shadow rays on the ones that matter), then a point or direction on it
//! through [`Emitter::sample_li`], with densities in solid angle at the
//! shading point for multiple importance sampling. Emitting objects are
//! found by the scene's own rays; `[[lights]]` rectangles, which are not
//! scene objects, by [`LightSampler::nearest_hit`].

use crate::geometry::Quad;
use crate::math::{Ray, Vec2, Vec3A};
use crate::scene::light::{bounding_sphere, Emitter, LightSample};
use crate::scene::{Light, Scene};

/// A `[[lights]]` rectangle hit by a ray.
#[derive(Clone, Copy, Debug)]
pub struct EmitterHit {
    /// Index among the sampler's emitters.
    pub light: usize,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Emitted radiance toward the ray's origin.
    pub radiance: Vec3A,
}

/// The emitters of a scene, ready to be chosen, sampled and hit.
#[derive(Clone, Debug)]
pub struct LightSampler {
    emitters: Vec<Emitter>,
    /// Probability of choosing each emitter.
    probability: Vec<f32>,
    /// Running sums of `probability`.
    cdf: Vec<f32>,
    /// The rectangles, by emitter index.
    rects: Vec<(usize, Quad)>,
    /// The emitter of each object (`u32::MAX`: it does not emit).
    object_emitter: Vec<u32>,
}

fn weight(c: Vec3A) -> f32 {
    c.x + c.y + c.z
}

impl LightSampler {
    /// The emitters of `scene`: its lights (constant environments merged
    /// into one, since their radiances add up), then its emitting objects.
    pub fn new(scene: &Scene) -> Self {
        let (center, radius) = bounding_sphere(scene);
        let constant = scene.lights.iter().fold(Vec3A::ZERO, |sum, l| match l {
            Light::Environment { radiance, map: None } => sum + *radiance,
            _ => sum,
        });
        let constant = (constant != Vec3A::ZERO).then_some(Light::Environment {
            radiance: constant,
            map: None,
        });
        let lights = scene
            .lights
            .iter()
            .filter(|l| !matches!(l, Light::Environment { map: None, .. }))
            .chain(&constant)
            .map(|l| (u32::MAX, Emitter::of_light(l, center, radius)));
        let objects = (0..scene.objects.len() as u32).filter_map(|i| Emitter::of_object(scene, i).map(|e| (i, e)));
        let mut sampler = Self {
            emitters: Vec::new(),
            probability: Vec::new(),
            cdf: Vec::new(),
            rects: Vec::new(),
            object_emitter: vec![u32::MAX; scene.objects.len()],
        };
        let mut power = Vec::new();
        for (object, e) in lights.chain(objects) {
            let p = weight(e.power());
            if !(p > 0.0 && p.is_finite()) {
                continue;
            }
            let index = sampler.emitters.len();
            if let Emitter::Rect(a) = &e {
                let Some(quad) = Quad::new(a.center - (a.u + a.v) * 0.5, a.u, a.v) else {
                    continue;
                };
                sampler.rects.push((index, quad));
            }
            if object != u32::MAX {
                sampler.object_emitter[object as usize] = index as u32;
            }
            sampler.emitters.push(e);
            power.push(p);
        }
        let total: f32 = power.iter().sum();
        sampler.probability = power.iter().map(|p| p / total).collect();
        let mut acc = 0.0;
        sampler.cdf = sampler
            .probability
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        sampler
    }

    /// No light emits anything.
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// The emitters, in choice order.
    pub fn emitters(&self) -> &[Emitter] {
        &self.emitters
    }

    /// Chooses an emitter with `u_select` and a point on it with `u`, as
    /// seen from `p`; the density includes the choice. `None` when the
    /// choice carries no light toward `p` (the back of an area light).
    pub fn sample(&self, p: Vec3A, u_select: f32, u: Vec2) -> Option<LightSample> {
        if self.emitters.is_empty() {
            return None;
        }
        let i = self
            .cdf
            .partition_point(|&c| c <= u_select)
            .min(self.emitters.len() - 1);
        let mut ls = self.emitters[i].sample_li(p, u)?;
        ls.pdf *= self.probability[i];
        Some(ls)
    }

    /// The nearest `[[lights]]` rectangle that `ray` meets before `t_max`,
    /// from either side (path tracing treats them as opaque surfaces that
    /// absorb what reaches them); the radiance is zero on the side that
    /// does not emit.
    pub fn nearest_hit(&self, ray: &Ray, t_max: f32) -> Option<EmitterHit> {
        let mut nearest: Option<EmitterHit> = None;
        for &(i, quad) in &self.rects {
            let limit = nearest.map_or(t_max, |n| n.t);
            if let Some((t, _, _)) = quad.intersect(ray, limit) {
                let Emitter::Rect(light) = &self.emitters[i] else {
                    continue;
                };
                let front = ray.dir.dot(light.normal) < 0.0;
                nearest = Some(EmitterHit {
                    light: i,
                    t,
                    radiance: if front { light.radiance } else { Vec3A::ZERO },
                });
            }
        }
        nearest
    }

    /// Density in solid angle with which [`sample`](Self::sample) picks the
    /// point at parameter `t` of `ray` on rectangle `light`.
    pub fn pdf_area(&self, light: usize, ray: &Ray, t: f32) -> f32 {
        let q = ray.at(t);
        self.probability[light] * self.emitters[light].pdf_li(ray.origin, q, Vec3A::ZERO)
    }

    /// The emitter index of object `object`, when it emits.
    #[inline]
    pub fn object_emitter(&self, object: u32) -> Option<usize> {
        let i = *self.object_emitter.get(object as usize)?;
        (i != u32::MAX).then_some(i as usize)
    }

    /// Density in solid angle with which [`sample`](Self::sample) at `p`
    /// picks the point `q` (normal `n`) of emitter `light`.
    pub fn pdf_point(&self, light: usize, p: Vec3A, q: Vec3A, n: Vec3A) -> f32 {
        self.probability[light] * self.emitters[light].pdf_li(p, q, n)
    }

    /// Radiance of the environments seen by a ray leaving the scene along
    /// `dir`, and the density with which [`sample`](Self::sample) picks
    /// that direction.
    pub fn environment(&self, dir: Vec3A) -> (Vec3A, f32) {
        self.emitters
            .iter()
            .zip(&self.probability)
            .fold((Vec3A::ZERO, 0.0), |(l, pdf), (e, p)| {
                let (le, d) = e.environment(dir);
                (l + le, pdf + p * d)
            })
    }
}
