//! Light sampling for the path integrator: one light chosen in proportion
//! to its power (so that scenes with many lights spend their shadow rays on
//! the ones that matter), then a point on it (area lights uniformly over
//! their rectangle, environments uniformly over the sphere), with densities
//! in solid angle at the shading point for multiple importance sampling.

use crate::geometry::Quad;
use crate::math::sampling::uniform_sphere;
use crate::math::{Ray, Vec2, Vec3A};
use crate::scene::light::EnvironmentMap;
use crate::scene::{AreaLight, Light, Scene};
use std::f32::consts::PI;
use std::sync::Arc;

/// A light as the sampler sees it.
#[derive(Clone, Debug)]
enum Emitter {
    Point { position: Vec3A, intensity: Vec3A },
    Area { light: AreaLight, quad: Quad },
    Environment { radiance: Vec3A },
    EnvironmentMap { scale: Vec3A, map: Arc<EnvironmentMap> },
}

/// A sampled light direction.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point toward the light.
    pub wi: Vec3A,
    /// The point sampled on the light (`None` for an environment).
    pub target: Option<Vec3A>,
    /// Radiance arriving along `wi` (for a point light: intensity / d²).
    pub li: Vec3A,
    /// Density in solid angle, light choice included (for a point light:
    /// the probability of choosing it).
    pub pdf: f32,
    /// A point light (no other strategy can find it).
    pub delta: bool,
}

/// An area light hit by a ray.
#[derive(Clone, Copy, Debug)]
pub struct EmitterHit {
    /// Index among the sampler's lights.
    pub light: usize,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Emitted radiance toward the ray's origin.
    pub radiance: Vec3A,
}

/// The lights of a scene, ready to be sampled and hit.
#[derive(Clone, Debug)]
pub struct LightSampler {
    emitters: Vec<Emitter>,
    /// Probability of choosing each light.
    probability: Vec<f32>,
    /// Running sums of `probability`.
    cdf: Vec<f32>,
}

fn weight(c: Vec3A) -> f32 {
    c.x + c.y + c.z
}

impl LightSampler {
    /// The lights of `scene`; an environment's power is taken as that of
    /// its radiance falling on a disk the size of the scene's bounding
    /// sphere (`π L · π r²`).
    pub fn new(scene: &Scene) -> Self {
        let bounds = scene.bounds();
        let radius = if bounds.min.x <= bounds.max.x {
            (0.5 * bounds.extent().length()).max(1e-3)
        } else {
            1.0
        };
        let mut emitters = Vec::new();
        let mut power = Vec::new();
        // Several constant environments are one: their radiances add up.
        let environment = scene.lights.iter().fold(Vec3A::ZERO, |sum, l| match l {
            Light::Environment { radiance, map: None } => sum + *radiance,
            _ => sum,
        });
        let environment = (environment != Vec3A::ZERO).then_some(Light::Environment {
            radiance: environment,
            map: None,
        });
        for light in scene
            .lights
            .iter()
            .filter(|l| !matches!(l, Light::Environment { map: None, .. }))
            .chain(&environment)
        {
            let (e, p) = match light {
                Light::Point { position, intensity } => (
                    Emitter::Point {
                        position: *position,
                        intensity: *intensity,
                    },
                    weight(light.power()),
                ),
                Light::Area(a) => {
                    let Some(quad) = Quad::new(a.center - (a.u + a.v) * 0.5, a.u, a.v) else {
                        continue;
                    };
                    (Emitter::Area { light: a.clone(), quad }, weight(light.power()))
                }
                Light::Environment { radiance, map: None } => (
                    Emitter::Environment { radiance: *radiance },
                    weight(*radiance) * PI * PI * radius * radius,
                ),
                Light::Environment {
                    radiance,
                    map: Some(map),
                } => (
                    Emitter::EnvironmentMap {
                        scale: *radiance,
                        map: map.clone(),
                    },
                    weight(*radiance * map.mean()) * PI * PI * radius * radius,
                ),
            };
            if p > 0.0 && p.is_finite() {
                emitters.push(e);
                power.push(p);
            }
        }
        let total: f32 = power.iter().sum();
        let probability: Vec<f32> = power.iter().map(|p| p / total).collect();
        let mut acc = 0.0;
        let cdf = probability
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        Self {
            emitters,
            probability,
            cdf,
        }
    }

    /// No light emits anything.
    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// Chooses a light with `u_select` and a point on it with `u`, as seen
    /// from `p`. `None` when the choice carries no light toward `p` (the
    /// back of an area light).
    pub fn sample(&self, p: Vec3A, u_select: f32, u: Vec2) -> Option<LightSample> {
        if self.emitters.is_empty() {
            return None;
        }
        let i = self
            .cdf
            .partition_point(|&c| c <= u_select)
            .min(self.emitters.len() - 1);
        let select = self.probability[i];
        match &self.emitters[i] {
            Emitter::Point { position, intensity } => {
                let to = *position - p;
                let d2 = to.length_squared();
                if !d2.is_normal() {
                    return None;
                }
                Some(LightSample {
                    wi: to / d2.sqrt(),
                    target: Some(*position),
                    li: *intensity / d2,
                    pdf: select,
                    delta: true,
                })
            }
            Emitter::Area { light, .. } => {
                let q = light.point(u);
                let to = q - p;
                let d2 = to.length_squared();
                if !d2.is_normal() {
                    return None;
                }
                let wi = to / d2.sqrt();
                let cos_light = -wi.dot(light.normal);
                if cos_light <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    target: Some(q),
                    li: light.radiance,
                    pdf: select * d2 / (cos_light * light.area()),
                    delta: false,
                })
            }
            Emitter::Environment { radiance } => Some(LightSample {
                wi: uniform_sphere(u),
                target: None,
                li: *radiance,
                pdf: select / (4.0 * PI),
                delta: false,
            }),
            Emitter::EnvironmentMap { scale, map } => {
                let (wi, pdf) = map.sample(u)?;
                Some(LightSample {
                    wi,
                    target: None,
                    li: *scale * map.eval(wi),
                    pdf: select * pdf,
                    delta: false,
                })
            }
        }
    }

    /// The nearest area light that `ray` meets before `t_max`, from either
    /// side (path tracing treats area lights as opaque surfaces that absorb
    /// what reaches them); the radiance is zero on the side that does not
    /// emit.
    pub fn nearest_hit(&self, ray: &Ray, t_max: f32) -> Option<EmitterHit> {
        let mut nearest: Option<EmitterHit> = None;
        for (i, e) in self.emitters.iter().enumerate() {
            if let Emitter::Area { light, quad } = e {
                let limit = nearest.map_or(t_max, |n| n.t);
                if let Some((t, _, _)) = quad.intersect(ray, limit) {
                    let front = ray.dir.dot(light.normal) < 0.0;
                    nearest = Some(EmitterHit {
                        light: i,
                        t,
                        radiance: if front { light.radiance } else { Vec3A::ZERO },
                    });
                }
            }
        }
        nearest
    }

    /// Density in solid angle with which [`sample`](Self::sample) picks the
    /// point at parameter `t` of `ray` on area light `light`.
    pub fn pdf_area(&self, light: usize, ray: &Ray, t: f32) -> f32 {
        match &self.emitters[light] {
            Emitter::Area { light: a, .. } => {
                let cos_light = -ray.dir.normalize().dot(a.normal);
                let d = t * ray.dir.length();
                if cos_light <= 0.0 {
                    0.0
                } else {
                    self.probability[light] * d * d / (cos_light * a.area())
                }
            }
            _ => 0.0,
        }
    }

    /// Radiance of the environments seen by a ray leaving the scene along
    /// `dir`, and the density with which [`sample`](Self::sample) picks
    /// that direction.
    pub fn environment(&self, dir: Vec3A) -> (Vec3A, f32) {
        self.emitters
            .iter()
            .zip(&self.probability)
            .fold((Vec3A::ZERO, 0.0), |(l, pdf), (e, p)| match e {
                Emitter::Environment { radiance } => (l + *radiance, pdf + p / (4.0 * PI)),
                Emitter::EnvironmentMap { scale, map } => (l + *scale * map.eval(dir), pdf + p * map.pdf(dir)),
                _ => (l, pdf),
            })
    }
}
