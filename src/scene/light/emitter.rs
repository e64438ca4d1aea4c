//! The one interface every integrator reaches lights through (pbrt-v4's
//! `Light`: `SampleLi`, `PDF_Li`, `L`/`Le`, `SampleLe`, `Phi`): direct light
//! toward a point, the density of that choice for MIS, emitted radiance,
//! photon emission and power.

use super::{AreaLight, EnvironmentMap, Light, ShapeEmitter, SpotLight};
use crate::math::sampling::{concentric_disk, cosine_hemisphere, uniform_cone, uniform_sphere};
use crate::math::{Frame, Vec2, Vec3A};
use crate::scene::{Material, Scene};
use std::f32::consts::PI;
use std::sync::Arc;

/// A sampled light direction seen from a point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the point toward the light.
    pub wi: Vec3A,
    /// The point sampled on the light (`None` toward infinity: directional
    /// and environment lights).
    pub target: Option<Vec3A>,
    /// Radiance arriving along `wi` (delta lights: the irradiance a
    /// surface facing them receives, `I / d²` or `E`).
    pub li: Vec3A,
    /// Density in solid angle of this light's strategy (delta lights: 1).
    pub pdf: f32,
    /// A delta light (no other strategy can find it).
    pub delta: bool,
}

/// Where a photon leaves a light: what [`Emitter::sample_origin`] returns.
#[derive(Clone, Copy, Debug)]
pub struct EmissionOrigin {
    /// Position.
    pub x: Vec3A,
    /// Unit normal of an emitting surface (`None` for points).
    pub normal: Option<Vec3A>,
    /// Radiant intensity scale divided by the position's density:
    /// intensity for point and spot lights, radiance × area for surfaces,
    /// irradiance × disk area for a directional light.
    pub scale: Vec3A,
    /// The one direction of a directional light.
    pub direction: Option<Vec3A>,
}

/// A light ready to be sampled: a scene light or an emitting object.
#[derive(Clone, Debug)]
pub enum Emitter {
    /// Isotropic point light.
    Point {
        /// Position.
        position: Vec3A,
        /// Radiant intensity (W/sr).
        intensity: Vec3A,
    },
    /// Spot light.
    Spot(SpotLight),
    /// Directional light over the scene's bounding sphere.
    Directional {
        /// Unit direction of travel.
        direction: Vec3A,
        /// Irradiance perpendicular to it.
        irradiance: Vec3A,
        /// Centre of the scene's bounding sphere.
        center: Vec3A,
        /// Its radius.
        radius: f32,
    },
    /// A `[[lights]]` rectangle.
    Rect(AreaLight),
    /// Environment, constant or an image.
    Environment {
        /// Radiance, or the image's scale.
        radiance: Vec3A,
        /// The image.
        map: Option<Arc<EnvironmentMap>>,
        /// Centre of the scene's bounding sphere (where photons aim).
        center: Vec3A,
        /// Its radius (for the power and the photons' disk).
        radius: f32,
    },
    /// An object whose material emits.
    Shape {
        /// Where to sample.
        shape: ShapeEmitter,
        /// Its material (the emission, textured or not).
        material: Box<Material>,
    },
}

impl Emitter {
    /// The emitter of a scene light, in a scene of bounding sphere
    /// `(center, radius)`.
    pub fn of_light(light: &Light, center: Vec3A, radius: f32) -> Self {
        match light {
            Light::Point { position, intensity } => Emitter::Point {
                position: *position,
                intensity: *intensity,
            },
            Light::Spot(s) => Emitter::Spot(*s),
            Light::Directional { direction, irradiance } => Emitter::Directional {
                direction: *direction,
                irradiance: *irradiance,
                center,
                radius,
            },
            Light::Area(a) => Emitter::Rect(a.clone()),
            Light::Environment { radiance, map } => Emitter::Environment {
                radiance: *radiance,
                map: map.clone(),
                center,
                radius,
            },
        }
    }

    /// The emitter of object `object`, when its material emits and it has
    /// an area.
    pub fn of_object(scene: &Scene, object: u32) -> Option<Self> {
        let material = &scene.materials[scene.objects[object as usize].material as usize];
        if !material.emits() {
            return None;
        }
        Some(Emitter::Shape {
            shape: ShapeEmitter::new(scene, object)?,
            material: Box::new(material.clone()),
        })
    }

    /// Every emitter of `scene`: its lights, then its emitting objects.
    pub fn all(scene: &Scene) -> Vec<Emitter> {
        let (center, radius) = bounding_sphere(scene);
        let lights = scene.lights.iter().map(|l| Emitter::of_light(l, center, radius));
        let objects = (0..scene.objects.len() as u32).filter_map(|i| Emitter::of_object(scene, i));
        lights.chain(objects).collect()
    }

    /// True when photons leave from one point (point and spot lights).
    pub fn is_point(&self) -> bool {
        matches!(self, Emitter::Point { .. } | Emitter::Spot(_))
    }

    /// True for a light no ray can hit.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Emitter::Point { .. } | Emitter::Spot(_) | Emitter::Directional { .. }
        )
    }

    /// Total emitted power (W per channel); for directional and environment
    /// lights, what crosses the scene's bounding disk.
    pub fn power(&self) -> Vec3A {
        match self {
            Emitter::Point { intensity, .. } => *intensity * (4.0 * PI),
            Emitter::Spot(s) => s.power(),
            Emitter::Directional { irradiance, radius, .. } => *irradiance * (PI * radius * radius),
            Emitter::Rect(a) => a.power(),
            Emitter::Environment {
                radiance, map, radius, ..
            } => {
                let mean = map.as_ref().map_or(Vec3A::ONE, |m| m.mean());
                *radiance * mean * (PI * PI * radius * radius)
            }
            // The brightest texel stands for a textured emission: any
            // positive weight keeps the light choice unbiased.
            Emitter::Shape { shape, material } => {
                let peak = match material.textures.as_deref().and_then(|t| t.emission.as_ref()) {
                    Some(t) => t.max_value() * material.emission,
                    None => material.emission,
                };
                let sides = if material.emits_both_sides { 2.0 } else { 1.0 };
                peak * (PI * shape.area * sides)
            }
        }
    }

    /// Light arriving at `p` from this emitter for `u ∈ [0, 1)²` (pbrt's
    /// `SampleLi`); `None` when the sample carries nothing toward `p`.
    pub fn sample_li(&self, p: Vec3A, u: Vec2) -> Option<LightSample> {
        match self {
            Emitter::Point { position, intensity } => point_sample(p, *position, *intensity),
            Emitter::Spot(s) => {
                let mut ls = point_sample(p, s.position, s.intensity)?;
                ls.li *= s.falloff(-ls.wi);
                (ls.li.max_element() > 0.0).then_some(ls)
            }
            Emitter::Directional {
                direction, irradiance, ..
            } => Some(LightSample {
                wi: -*direction,
                target: None,
                li: *irradiance,
                pdf: 1.0,
                delta: true,
            }),
            Emitter::Rect(a) => {
                let q = a.point(u);
                let to = q - p;
                let d2 = to.length_squared();
                if !d2.is_normal() {
                    return None;
                }
                let wi = to / d2.sqrt();
                let cos_light = -wi.dot(a.normal);
                if cos_light <= 0.0 {
                    return None;
                }
                Some(LightSample {
                    wi,
                    target: Some(q),
                    li: a.radiance,
                    pdf: d2 / (cos_light * a.area()),
                    delta: false,
                })
            }
            Emitter::Environment {
                radiance, map: None, ..
            } => Some(LightSample {
                wi: uniform_sphere(u),
                target: None,
                li: *radiance,
                pdf: 1.0 / (4.0 * PI),
                delta: false,
            }),
            Emitter::Environment {
                radiance, map: Some(m), ..
            } => {
                let (wi, pdf) = m.sample(u)?;
                Some(LightSample {
                    wi,
                    target: None,
                    li: *radiance * m.eval(wi),
                    pdf,
                    delta: false,
                })
            }
            Emitter::Shape { shape, material } => {
                let (q, pdf) = shape.sample_from(p, u, emission_uses_uv(material))?;
                let to = q.p - p;
                let wi = to.normalize_or_zero();
                // Only the side the normal faces emits, unless both do.
                let cos = wi.dot(q.n);
                if wi == Vec3A::ZERO || cos == 0.0 || (cos > 0.0 && !material.emits_both_sides) {
                    return None;
                }
                let li = material.emission_at(q.uv);
                (li.max_element() > 0.0).then_some(LightSample {
                    wi,
                    target: Some(q.p),
                    li,
                    pdf,
                    delta: false,
                })
            }
        }
    }

    /// Density in solid angle with which [`sample_li`](Self::sample_li) at
    /// `p` picks the point `q` (of normal `n`) of a rectangle or an emitting
    /// surface; 0 for other kinds.
    pub fn pdf_li(&self, p: Vec3A, q: Vec3A, n: Vec3A) -> f32 {
        match self {
            Emitter::Rect(a) => {
                let to = q - p;
                let d2 = to.length_squared();
                let cos = -(to / d2.sqrt()).dot(a.normal);
                if cos <= 0.0 || !d2.is_normal() {
                    0.0
                } else {
                    d2 / (cos * a.area())
                }
            }
            Emitter::Shape { shape, .. } => shape.pdf_from(p, q, n),
            _ => 0.0,
        }
    }

    /// Radiance an environment sends from direction `dir`, and the density
    /// with which [`sample_li`](Self::sample_li) picks it; zero for other kinds.
    pub fn environment(&self, dir: Vec3A) -> (Vec3A, f32) {
        match self {
            Emitter::Environment {
                radiance, map: None, ..
            } => (*radiance, 1.0 / (4.0 * PI)),
            Emitter::Environment {
                radiance, map: Some(m), ..
            } => (*radiance * m.eval(dir), m.pdf(dir)),
            _ => (Vec3A::ZERO, 0.0),
        }
    }

    /// True for an environment: its photons need
    /// [`sample_environment_origin`](Self::sample_environment_origin).
    pub fn is_environment(&self) -> bool {
        matches!(self, Emitter::Environment { .. })
    }

    /// Where a photon from the environment starts and where it goes: `u`
    /// picks the direction toward the sky (the map's distribution, or
    /// uniform for a constant), `u_disk` a point of the scene's bounding
    /// disk facing it, behind the scene; the power is `Le · π r² / pdf`
    /// (pbrt-v4's `ImageInfiniteLight::SampleLe`). `None` for other lights
    /// and for a direction the map cannot send.
    pub fn sample_environment_origin(&self, u: Vec2, u_disk: Vec2) -> Option<EmissionOrigin> {
        let Emitter::Environment {
            radiance,
            map,
            center,
            radius,
        } = self
        else {
            return None;
        };
        let (toward_sky, pdf) = match map {
            Some(m) => m.sample(u)?,
            None => (uniform_sphere(u), 1.0 / (4.0 * PI)),
        };
        let le = *radiance * map.as_ref().map_or(Vec3A::ONE, |m| m.eval(toward_sky));
        let direction = -toward_sky;
        let d = concentric_disk(u_disk) * *radius;
        let f = Frame::from_normal(direction);
        Some(EmissionOrigin {
            x: *center + f.s * d.x + f.t * d.y - direction * (*radius * 1.01),
            normal: None,
            scale: le * (PI * radius * radius / pdf),
            direction: Some(direction),
        })
    }

    /// Where a photon leaves the light for `u ∈ [0, 1)²` (pbrt's
    /// `SampleLe`, position half); `None` for an environment, whose
    /// direction comes first ([`sample_environment_origin`](Self::sample_environment_origin)).
    pub fn sample_origin(&self, u: Vec2) -> Option<EmissionOrigin> {
        let point = |x: Vec3A, scale: Vec3A| EmissionOrigin {
            x,
            normal: None,
            scale,
            direction: None,
        };
        match self {
            Emitter::Point { position, intensity } => Some(point(*position, *intensity)),
            Emitter::Spot(s) => Some(point(s.position, s.intensity)),
            Emitter::Directional {
                direction,
                irradiance,
                center,
                radius,
            } => {
                // A disk of the scene's bounding sphere, facing the light,
                // behind the scene.
                let d = concentric_disk(u) * *radius;
                let f = Frame::from_normal(*direction);
                Some(EmissionOrigin {
                    x: *center + f.s * d.x + f.t * d.y - *direction * (*radius * 1.01),
                    normal: None,
                    scale: *irradiance * (PI * radius * radius),
                    direction: Some(*direction),
                })
            }
            Emitter::Rect(a) => Some(EmissionOrigin {
                x: a.point(u),
                normal: Some(a.normal),
                scale: a.radiance * a.area(),
                direction: None,
            }),
            Emitter::Environment { .. } => None,
            Emitter::Shape { shape, material } => {
                // Both sides: the first half of `u.x` picks the front, the
                // second the back, each at twice the density.
                let (u, normal_sign, sides) = match material.emits_both_sides {
                    false => (u, 1.0, 1.0),
                    true if u.x < 0.5 => (Vec2::new(2.0 * u.x, u.y), 1.0, 2.0),
                    true => (
                        Vec2::new((2.0 * u.x - 1.0).min(1.0 - f32::EPSILON / 2.0), u.y),
                        -1.0,
                        2.0,
                    ),
                };
                let q = shape.sample_point(u, emission_uses_uv(material));
                Some(EmissionOrigin {
                    x: q.p,
                    normal: Some(q.n * normal_sign),
                    scale: material.emission_at(q.uv) * (shape.area * sides),
                    direction: None,
                })
            }
        }
    }

    /// Radiant intensity from `origin` toward unit `dir`, divided by the
    /// origin's density (pbrt's `Le` on the photon's first ray).
    pub fn intensity(&self, origin: &EmissionOrigin, dir: Vec3A) -> Vec3A {
        match (self, origin.normal) {
            (Emitter::Spot(s), _) => origin.scale * s.falloff(dir),
            (_, Some(n)) => origin.scale * dir.dot(n).max(0.0),
            _ => origin.scale,
        }
    }

    /// A photon direction from `origin` drawn from the light's whole
    /// emission, with its intensity divided by the direction's density.
    pub fn sample_direction(&self, origin: &EmissionOrigin, u: Vec2) -> (Vec3A, Vec3A) {
        if let Some(d) = origin.direction {
            return (d, origin.scale);
        }
        match (self, origin.normal) {
            (Emitter::Spot(s), _) => {
                let cos_max = s.cos_cutoff();
                let dir = s.frame().to_world(uniform_cone(u, cos_max));
                (dir, origin.scale * (s.falloff(dir) * 2.0 * PI * (1.0 - cos_max)))
            }
            (_, Some(n)) => (Frame::from_normal(n).to_world(cosine_hemisphere(u)), origin.scale * PI),
            _ => (uniform_sphere(u), origin.scale * (4.0 * PI)),
        }
    }
}

/// The emission of `material` reads texture coordinates.
fn emission_uses_uv(material: &Material) -> bool {
    material
        .textures
        .as_deref()
        .and_then(|t| t.emission.as_ref())
        .is_some_and(|t| !t.is_constant())
}

/// A point light of intensity `intensity` at `position`, seen from `p`.
fn point_sample(p: Vec3A, position: Vec3A, intensity: Vec3A) -> Option<LightSample> {
    let to = position - p;
    let d2 = to.length_squared();
    if !d2.is_normal() {
        return None;
    }
    Some(LightSample {
        wi: to / d2.sqrt(),
        target: Some(position),
        li: intensity / d2,
        pdf: 1.0,
        delta: true,
    })
}

/// Centre and radius of the scene's bounding sphere (radius 1 around the
/// origin for a scene without objects).
pub fn bounding_sphere(scene: &Scene) -> (Vec3A, f32) {
    let b = scene.bounds();
    if b.min.x <= b.max.x {
        (b.center(), (0.5 * b.extent().length()).max(1e-3))
    } else {
        (Vec3A::ZERO, 1.0)
    }
}
