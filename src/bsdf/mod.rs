//! Light scattering at surfaces, written once for every integrator and the
//! photon tracer.
//!
//! A [`Bsdf`] is built per shading point from a material
//! ([`Bsdf::for_material`]) and works in the local shading frame (+z is the
//! outward shading normal), with pbrt's conventions: `wo` leaves toward the
//! viewer (or the previous path vertex), `wi` toward the light;
//! [`Bsdf::eval`] and [`Bsdf::pdf`] cover the non-delta lobes; a sample's
//! throughput factor is `f |cos θi| / pdf`, delta lobes included (their
//! `pdf` is the probability of choosing them).
//!
//! Lobes: [`phong`] (the original report's Lambert, Phong / Blinn-Phong and
//! mirror), [`dielectric`] (smooth and rough glass), [`conductor`] (smooth
//! and rough metals; named presets in `scene::metals`), [`plastic`] (coated diffuse),
//! [`principled`] (glTF's metallic-roughness), [`disney`] (Mitsuba's `principled`),
//! [`disney_thin`] (Mitsuba's `principledthin`);
//! [`fresnel`] and [`microfacet`] are their building blocks; [`specular`]
//! holds the world-space reflection and refraction shared with the Whitted
//! integrator and the photon tracer.

pub mod conductor;
pub mod dielectric;
pub mod disney;
pub mod disney_thin;
pub mod energy;
pub mod flags;
pub mod fresnel;
pub mod microfacet;
pub mod null;
pub mod phong;
pub mod plastic;
pub mod principled;
pub mod rough_plastic;
pub mod specular;
pub mod whitted;

pub use crate::scene::FresnelModel;
pub use flags::{flags_over_range, material_flags, LobeFlags};
pub use specular::{fresnel_schlick, reflect, refract, DielectricInterface};
pub use whitted::{whitted_flags, WhittedKind, WhittedSurface};

use crate::math::{Vec2, Vec3A};
use crate::scene::Material;
use conductor::{RoughConductor, SmoothConductor};
use dielectric::{RoughDielectric, SmoothDielectric, ThinDielectric};
use disney::Disney;
use disney_thin::DisneyThin;
use microfacet::{Microfacet, SMOOTH_ALPHA};
use null::Null;
use phong::{Highlight, Lambert, Mirror};
use plastic::Plastic;
use principled::Principled;
use rough_plastic::RoughPlastic;

/// What a path carries: radiance from the camera, or power (importance)
/// from a light (photons). Only refraction tells them apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Camera paths.
    Radiance,
    /// Light paths (photons).
    Importance,
}

/// A sampled direction.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Direction toward the next vertex (local frame).
    pub wi: Vec3A,
    /// BSDF value (for a delta lobe: its weight divided by `|cos θi|`).
    pub f: Vec3A,
    /// Solid-angle density, or for a delta lobe the probability of choosing it.
    pub pdf: f32,
    /// From a delta lobe (mirror, smooth glass).
    pub delta: bool,
    /// Through the surface.
    pub transmission: bool,
    /// Ratio ηt/ηi of the indices across a refraction (1 otherwise).
    pub eta: f32,
}

impl BsdfSample {
    fn glossy(wi: Vec3A, f: Vec3A, pdf: f32) -> Self {
        Self {
            wi,
            f,
            pdf,
            delta: false,
            transmission: false,
            eta: 1.0,
        }
    }

    fn specular(wi: Vec3A, f: Vec3A, pdf: f32) -> Self {
        Self {
            delta: true,
            ..Self::glossy(wi, f, pdf)
        }
    }

    /// A sampled direction `wi` of a non-delta lobe with density `pdf` and
    /// value `f()` (evaluated only when the density is positive), through
    /// the surface with index ratio `eta` when `wi` is on the other side of
    /// it from `wo`.
    fn scattered(wo: Vec3A, wi: Vec3A, pdf: f32, f: impl FnOnce() -> Vec3A, eta: f32) -> Option<Self> {
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let mut s = Self::glossy(wi, f(), pdf);
        if wi.z * wo.z < 0.0 {
            s.transmission = true;
            s.eta = eta;
        }
        Some(s)
    }

    /// The throughput factor `f |cos θi| / pdf`.
    pub fn weight(&self) -> Vec3A {
        if self.pdf > 0.0 {
            self.f * (self.wi.z.abs() / self.pdf)
        } else {
            Vec3A::ZERO
        }
    }
}

/// One lobe of a material.
#[derive(Clone, Copy, Debug)]
enum Lobe<'a> {
    Lambert(Lambert),
    Highlight(Highlight),
    Mirror(Mirror),
    SmoothDielectric(SmoothDielectric),
    ThinDielectric(ThinDielectric),
    RoughDielectric(RoughDielectric),
    SmoothConductor(SmoothConductor),
    RoughConductor(RoughConductor),
    Plastic(Plastic),
    RoughPlastic(RoughPlastic<'a>),
    Principled(Principled),
    /// Mitsuba's `principled` (Burley's Disney BSDF).
    Disney(Disney),
    /// Mitsuba's `principledthin` (the thin Disney BSDF).
    DisneyThin(DisneyThin),
    /// Mitsuba's `null`, or a blend's hole: light continues straight through, unchanged.
    Null(Null),
}

impl Lobe<'_> {
    fn eval(&self, wo: Vec3A, wi: Vec3A, transport: Transport) -> Vec3A {
        match self {
            Lobe::Lambert(l) => l.eval(wo, wi),
            Lobe::Highlight(h) => h.eval(wo, wi),
            Lobe::RoughDielectric(d) => d.eval(wo, wi, transport),
            Lobe::RoughConductor(c) => c.eval(wo, wi),
            Lobe::Plastic(p) => p.eval(wo, wi),
            Lobe::RoughPlastic(p) => p.eval(wo, wi),
            Lobe::Principled(p) => p.eval(wo, wi, transport),
            Lobe::Disney(d) => d.eval(wo, wi, transport),
            Lobe::DisneyThin(d) => d.eval(wo, wi),
            Lobe::Mirror(_)
            | Lobe::SmoothDielectric(_)
            | Lobe::ThinDielectric(_)
            | Lobe::SmoothConductor(_)
            | Lobe::Null(_) => Vec3A::ZERO,
        }
    }

    fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        match self {
            Lobe::Lambert(l) => l.pdf(wo, wi),
            Lobe::Highlight(h) => h.pdf(wo, wi),
            Lobe::RoughDielectric(d) => d.pdf(wo, wi),
            Lobe::RoughConductor(c) => c.pdf(wo, wi),
            Lobe::Plastic(p) => p.pdf(wo, wi),
            Lobe::RoughPlastic(p) => p.pdf(wo, wi),
            Lobe::Principled(p) => p.pdf(wo, wi),
            Lobe::Disney(d) => d.pdf(wo, wi),
            Lobe::DisneyThin(d) => d.pdf(wo, wi),
            Lobe::Mirror(_)
            | Lobe::SmoothDielectric(_)
            | Lobe::ThinDielectric(_)
            | Lobe::SmoothConductor(_)
            | Lobe::Null(_) => 0.0,
        }
    }

    fn sample(&self, wo: Vec3A, uc: f32, u: Vec2, transport: Transport) -> Option<BsdfSample> {
        match self {
            Lobe::Lambert(l) => l.sample(wo, u),
            Lobe::Highlight(h) => h.sample(wo, u),
            Lobe::Mirror(m) => m.sample(wo),
            Lobe::SmoothDielectric(d) => d.sample(wo, uc, transport),
            Lobe::ThinDielectric(d) => d.sample(wo, uc),
            Lobe::RoughDielectric(d) => d.sample(wo, uc, u, transport),
            Lobe::SmoothConductor(c) => c.sample(wo),
            Lobe::RoughConductor(c) => c.sample(wo, u),
            Lobe::Plastic(p) => p.sample(wo, uc, u),
            Lobe::RoughPlastic(p) => p.sample(wo, uc, u),
            Lobe::Principled(p) => p.sample(wo, uc, u, transport),
            Lobe::Disney(d) => d.sample(wo, uc, u, transport),
            Lobe::DisneyThin(d) => d.sample(wo, uc, u),
            Lobe::Null(n) => n.sample(wo),
        }
    }

    /// Probability that [`Lobe::sample`] returns a delta direction.
    fn delta_probability(&self, wo: Vec3A) -> f32 {
        match self {
            Lobe::Mirror(_)
            | Lobe::SmoothDielectric(_)
            | Lobe::ThinDielectric(_)
            | Lobe::SmoothConductor(_)
            | Lobe::Null(_) => 1.0,
            Lobe::Plastic(p) => p.delta_probability(wo),
            Lobe::Principled(p) => p.delta_probability(wo),
            _ => 0.0,
        }
    }

    /// The lobe kinds this lobe samples (each kind's declaration).
    fn flags(&self) -> LobeFlags {
        use LobeFlags as F;
        match self {
            Lobe::Lambert(_) => F::DIFFUSE | F::REFLECTION,
            Lobe::Highlight(_) => F::GLOSSY | F::REFLECTION,
            Lobe::Mirror(_) | Lobe::SmoothConductor(_) => F::SPECULAR | F::CASTS_CAUSTICS | F::REFLECTION,
            Lobe::SmoothDielectric(_) | Lobe::ThinDielectric(_) => {
                F::SPECULAR | F::CASTS_CAUSTICS | F::REFLECTION | F::TRANSMISSION
            }
            Lobe::RoughDielectric(_) => F::GLOSSY | F::REFLECTION | F::TRANSMISSION,
            Lobe::RoughConductor(_) => F::GLOSSY | F::REFLECTION,
            Lobe::Plastic(p) => F::SPECULAR | F::REFLECTION | base_flags(p.kd),
            Lobe::RoughPlastic(p) => F::GLOSSY | F::REFLECTION | base_flags(p.base),
            Lobe::Principled(p) => p.flags(),
            Lobe::Disney(d) => d.flags(),
            Lobe::DisneyThin(d) => d.flags(),
            Lobe::Null(_) => F::PASS_THROUGH,
        }
    }
}

/// A coat's base: diffuse unless it is black (then the coat alone reflects).
fn base_flags(albedo: Vec3A) -> LobeFlags {
    if albedo.max_element() > 0.0 {
        LobeFlags::DIFFUSE
    } else {
        LobeFlags::NONE
    }
}

/// Most lobes of one material (Lambert, highlight, mirror).
const MAX_LOBES: usize = 3;

/// The scattering of one material at one shading point: a mixture of lobes,
/// one chosen per sample with a probability proportional to its mean
/// reflectance.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf<'a> {
    lobes: [(Lobe<'a>, f32); MAX_LOBES],
    count: usize,
    /// Reflection-only materials scatter the same on both sides (the
    /// frame is flipped toward `wo`); dielectrics tell inside from outside.
    two_sided: bool,
    transport: Transport,
}

fn mean(c: Vec3A) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// The microfacets of roughness `u` (along `∂p/∂u`) and `v` (across it;
/// `None`: isotropic), or `None` for a smooth surface.
fn rough_or_smooth(u: f32, v: Option<f32>, distribution: crate::scene::MicrofacetDistribution) -> Option<Microfacet> {
    match v {
        None => (u >= SMOOTH_ALPHA).then_some(Microfacet::isotropic(distribution, u)),
        Some(v) => (u.max(v) >= SMOOTH_ALPHA).then_some(Microfacet {
            distribution,
            alpha: u.max(SMOOTH_ALPHA),
            alpha_y: v.max(SMOOTH_ALPHA),
        }),
    }
}

impl<'a> Bsdf<'a> {
    /// The BSDF of `m`, with `default_fresnel` for dielectrics that do not
    /// name a Fresnel formula.
    pub fn for_material(m: &'a Material, default_fresnel: FresnelModel, transport: Transport) -> Self {
        // Unused slots hold the payload-free `Null`: nothing to write but its tag.
        let mut b = Self {
            lobes: [(Lobe::Null(Null), 0.0); MAX_LOBES],
            count: 0,
            two_sided: !m.one_sided,
            transport,
        };
        if m.null {
            b.two_sided = false;
            b.push(Lobe::Null(Null), 1.0);
        } else if let Some(d) = m.dielectric {
            b.two_sided = false;
            let tint = d.tint;
            let lobe = match rough_or_smooth(d.roughness, m.roughness_v, m.microfacet) {
                None if d.thin => Lobe::ThinDielectric(ThinDielectric {
                    eta: d.ior,
                    tint,
                    fresnel: d.fresnel.unwrap_or(default_fresnel),
                }),
                None => Lobe::SmoothDielectric(SmoothDielectric {
                    eta: d.ior,
                    tint,
                    fresnel: d.fresnel.unwrap_or(default_fresnel),
                }),
                Some(microfacet) => Lobe::RoughDielectric(RoughDielectric {
                    eta: d.ior,
                    tint,
                    microfacet,
                }),
            };
            b.push(lobe, 1.0);
        } else if let Some(c) = m.conductor {
            let lobe = match rough_or_smooth(c.roughness, m.roughness_v, m.microfacet) {
                None => Lobe::SmoothConductor(SmoothConductor { eta: c.eta, k: c.k }),
                Some(microfacet) => Lobe::RoughConductor(RoughConductor {
                    eta: c.eta,
                    k: c.k,
                    microfacet,
                }),
            };
            b.push(lobe, 1.0);
        } else if let Some(d) = m.disney.filter(|d| d.thin) {
            // Both sides alike, with or without `twosided` (Mitsuba's
            // `principledthin` turns the directions itself).
            b.two_sided = true;
            b.push(Lobe::DisneyThin(DisneyThin::new(m.diffuse, d)), 1.0);
        } else if let Some(d) = m.disney {
            // One-sided like Mitsuba's `principled` unless wrapped in `twosided`.
            b.push(Lobe::Disney(Disney::new(m.diffuse, d)), 1.0);
        } else if let Some(p) = m.principled {
            let lobe = Principled {
                base: m.diffuse,
                metallic: p.metallic,
                transmission: p.transmission,
                eta: p.ior,
                thin: p.thin,
                microfacet: principled::microfacets(p.roughness),
                clearcoat: p.clearcoat,
                coat_microfacet: principled::microfacets(p.clearcoat_roughness),
            };
            if !p.thin && p.transmission > 0.0 {
                // A refracting solid tells inside from outside.
                b.two_sided = false;
            }
            b.push(Lobe::Principled(lobe), 1.0);
        } else if let Some(c) = &m.coating {
            let lobe = match rough_or_smooth(c.roughness, None, m.microfacet) {
                None => Lobe::Plastic(Plastic {
                    kd: m.diffuse,
                    eta: c.ior,
                    nonlinear: c.nonlinear,
                }),
                Some(microfacet) => {
                    let table = c
                        .table
                        .0
                        .get_or_init(|| rough_plastic::coating_table(c.ior, microfacet));
                    Lobe::RoughPlastic(RoughPlastic::new(m.diffuse, c.ior, microfacet, c.nonlinear, table))
                }
            };
            b.push(lobe, 1.0);
        } else {
            let r = m.mirror.map_or(0.0, |mi| mi.reflectivity);
            let kd = m.diffuse * (1.0 - r);
            let ks = m.specular * (1.0 - r);
            b.push(Lobe::Lambert(Lambert { kd }), mean(kd));
            b.push(
                Lobe::Highlight(Highlight {
                    ks,
                    n: m.shininess,
                    model: m.model,
                }),
                mean(ks),
            );
            if let Some(mi) = m.mirror {
                let tint = mi.tint * r;
                b.push(Lobe::Mirror(Mirror { tint }), mean(tint));
            }
        }
        b
    }

    /// The BSDF of a hole in a surface (a blend's empty side): light passes
    /// straight through, a delta transmission of weight 1 that does not
    /// bend the ray (Mitsuba's `null`).
    pub fn pass_through(transport: Transport) -> Self {
        let mut b = Self {
            lobes: [(Lobe::Null(Null), 0.0); MAX_LOBES],
            count: 0,
            two_sided: false,
            transport,
        };
        b.push(Lobe::Null(Null), 1.0);
        b
    }

    /// The BSDF of whatever `m` resolves to at a shading point
    /// ([`Material::resolve`]): its lobes, or a hole's.
    pub fn for_resolved(m: Option<&'a Material>, default_fresnel: FresnelModel, transport: Transport) -> Self {
        match m {
            Some(m) => Self::for_material(m, default_fresnel, transport),
            None => Self::pass_through(transport),
        }
    }

    fn push(&mut self, lobe: Lobe<'a>, weight: f32) {
        if weight > 0.0 && self.count < MAX_LOBES {
            self.lobes[self.count] = (lobe, weight);
            self.count += 1;
        }
    }

    fn lobes(&self) -> &[(Lobe<'a>, f32)] {
        &self.lobes[..self.count]
    }

    fn total_weight(&self) -> f32 {
        self.lobes().iter().map(|(_, w)| w).sum()
    }

    /// Has an anisotropic lobe: its local frame must follow the surface's
    /// tangent (`∂p/∂u`), not any frame about the normal.
    pub fn is_anisotropic(&self) -> bool {
        self.lobes().iter().any(|(l, _)| match l {
            Lobe::RoughConductor(c) => c.microfacet.is_anisotropic(),
            Lobe::RoughDielectric(d) => d.microfacet.is_anisotropic(),
            Lobe::Disney(d) => d.microfacet.is_anisotropic(),
            Lobe::DisneyThin(d) => d.is_anisotropic(),
            _ => false,
        })
    }

    /// The local frame this BSDF works in about the shading normal `ns`:
    /// anisotropic lobes follow the tangent `dpdu`, the rest any frame.
    pub fn frame(&self, ns: Vec3A, dpdu: Vec3A) -> crate::math::Frame {
        if self.is_anisotropic() {
            crate::math::Frame::from_normal_tangent(ns, dpdu)
        } else {
            crate::math::Frame::from_normal(ns)
        }
    }

    /// The weight of the mirror-direction reflection of the delta lobes
    /// from `wo` (local frame): what a ray reflected about the shading
    /// normal carries (the Whitted integrator's reflection of metals, coats
    /// and principled surfaces). Zero when no such lobe exists.
    pub fn delta_reflectance(&self, wo: Vec3A) -> Vec3A {
        let wo = if self.two_sided && wo.z < 0.0 {
            Vec3A::new(wo.x, wo.y, -wo.z)
        } else {
            wo
        };
        if wo.z <= 0.0 {
            return Vec3A::ZERO;
        }
        self.lobes().iter().fold(Vec3A::ZERO, |r, (l, _)| {
            r + match l {
                Lobe::SmoothConductor(c) => fresnel::conductor(wo.z, c.eta, c.k),
                Lobe::Plastic(p) => Vec3A::splat(fresnel::dielectric(wo.z, p.eta).0),
                Lobe::Principled(p) => p.delta_reflectance(wo),
                _ => Vec3A::ZERO,
            }
        })
    }

    /// Scatters nothing (a black material).
    pub fn is_black(&self) -> bool {
        self.count == 0
    }

    /// The union of the lobes' kinds at this shading point.
    pub fn flags(&self) -> LobeFlags {
        self.lobes().iter().fold(LobeFlags::NONE, |f, (l, _)| f | l.flags())
    }

    /// Has a non-delta lobe: light sampling can find it.
    pub fn has_smooth_lobe(&self) -> bool {
        self.flags().is_non_specular()
    }

    /// Only delta lobes (mirror, smooth glass or metal).
    pub fn is_delta(&self) -> bool {
        !self.is_black() && !self.has_smooth_lobe()
    }

    /// Has a delta lobe (mirror, smooth glass or metal, a clear coat): the
    /// path integrator's photon-mapped caustics start at such surfaces.
    pub fn has_delta_lobe(&self) -> bool {
        self.flags().is_specular()
    }

    /// Mitsuba's `null` BSDF (or a blend's hole): rays pass straight through, nothing scatters.
    pub fn is_null(&self) -> bool {
        matches!(self.lobes(), [(Lobe::Null(_), _)])
    }

    /// True when [`sample`](Self::sample) with the same `wo` and `uc` picks
    /// a delta lobe: over uniform `uc` that happens with probability
    /// [`delta_probability`](Self::delta_probability), whatever the
    /// direction sample then gives (a photon that does not pick one is
    /// stored with its power divided by the complement).
    pub fn picks_delta(&self, wo: Vec3A, uc: f32) -> bool {
        let Some((chosen, uc_rest)) = self.choose(uc) else {
            return false;
        };
        let wo = if self.two_sided && wo.z < 0.0 {
            Vec3A::new(wo.x, wo.y, -wo.z)
        } else {
            wo
        };
        uc_rest < self.lobes()[chosen].0.delta_probability(wo)
    }

    /// The lobe `uc` chooses (in proportion to the weights) and what is
    /// left of `uc` to use inside it.
    fn choose(&self, uc: f32) -> Option<(usize, f32)> {
        let total = self.total_weight();
        if total <= 0.0 {
            return None;
        }
        let mut acc = 0.0;
        for (i, (_, w)) in self.lobes().iter().enumerate() {
            let p = w / total;
            if uc < acc + p || i == self.count - 1 {
                return Some((i, ((uc - acc) / p).clamp(0.0, 1.0 - f32::EPSILON)));
            }
            acc += p;
        }
        None
    }

    /// Probability that [`sample`](Self::sample) returns a delta direction
    /// from `wo` (the photon tracer stores a photon when it does not, and
    /// divides its power by the complement).
    pub fn delta_probability(&self, wo: Vec3A) -> f32 {
        let total = self.total_weight();
        if total <= 0.0 {
            return 0.0;
        }
        let wo = if self.two_sided && wo.z < 0.0 {
            Vec3A::new(wo.x, wo.y, -wo.z)
        } else {
            wo
        };
        self.lobes()
            .iter()
            .map(|(l, w)| w / total * l.delta_probability(wo))
            .sum::<f32>()
            .min(1.0)
    }

    /// Reflection-only materials are seen the same from both sides.
    fn oriented(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, Vec3A) {
        if self.two_sided && wo.z < 0.0 {
            (Vec3A::new(wo.x, wo.y, -wo.z), Vec3A::new(wi.x, wi.y, -wi.z))
        } else {
            (wo, wi)
        }
    }

    /// The reflectance `kd` when this BSDF is a single Lambert lobe: its
    /// value is then the constant `kd/π` wherever
    /// [`lambert_reflects`](Self::lambert_reflects) holds and zero
    /// elsewhere, so a sum over many directions (the photon gather's
    /// `Σ f(ωo, ωp) Φp`) needs only that side test per direction, not an
    /// evaluation of the lobes.
    pub fn lambert(&self) -> Option<Vec3A> {
        match self.lobes() {
            [(Lobe::Lambert(l), _)] => Some(l.kd),
            _ => None,
        }
    }

    /// Whether [`eval`](Self::eval) of a single Lambert lobe is non-zero
    /// for local directions whose `z` components are `wo_z` and `wi_z`
    /// (both on the lobe's side, after turning a two-sided surface toward
    /// `wo`): the same test, in the same arithmetic, as the lobe's.
    #[inline]
    pub fn lambert_reflects(&self, wo_z: f32, wi_z: f32) -> bool {
        let (wo_z, wi_z) = if self.two_sided && wo_z < 0.0 {
            (-wo_z, -wi_z)
        } else {
            (wo_z, wi_z)
        };
        wo_z > 0.0 && wi_z > 0.0
    }

    /// The BSDF value of the non-delta lobes.
    pub fn eval(&self, wo: Vec3A, wi: Vec3A) -> Vec3A {
        let (wo, wi) = self.oriented(wo, wi);
        self.lobes()
            .iter()
            .fold(Vec3A::ZERO, |f, (l, _)| f + l.eval(wo, wi, self.transport))
    }

    /// Solid-angle density with which [`sample`](Self::sample) picks `wi`
    /// through a non-delta lobe.
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let (wo, wi) = self.oriented(wo, wi);
        let total = self.total_weight();
        if total <= 0.0 {
            return 0.0;
        }
        self.lobes().iter().map(|(l, w)| w / total * l.pdf(wo, wi)).sum()
    }

    /// Samples a direction: `uc` chooses the lobe (and, within it, reflection
    /// or refraction), `u` the direction. `None` when the sample carries no
    /// light (below the surface, total absorption).
    pub fn sample(&self, wo: Vec3A, uc: f32, u: Vec2) -> Option<BsdfSample> {
        let total = self.total_weight();
        let flip = self.two_sided && wo.z < 0.0;
        let wo_local = if flip { Vec3A::new(wo.x, wo.y, -wo.z) } else { wo };
        // Choose a lobe and reuse what is left of `uc` inside it.
        let (chosen, uc_rest) = self.choose(uc)?;
        let (lobe, w) = &self.lobes()[chosen];
        let mut s = lobe.sample(wo_local, uc_rest, u, self.transport)?;
        if s.delta {
            s.pdf *= w / total;
        } else if self.count > 1 {
            // The mixture's value and density at the sampled direction.
            s.f = self
                .lobes()
                .iter()
                .fold(Vec3A::ZERO, |f, (l, _)| f + l.eval(wo_local, s.wi, self.transport));
            s.pdf = self
                .lobes()
                .iter()
                .map(|(l, lw)| lw / total * l.pdf(wo_local, s.wi))
                .sum();
        }
        if flip {
            s.wi.z = -s.wi.z;
        }
        (s.pdf > 0.0 && s.f.max_element() > 0.0).then_some(s)
    }
}
