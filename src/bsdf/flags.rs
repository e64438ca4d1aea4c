//! What kinds of scattering a BSDF has: pbrt-v4's `BxDFFlags` (Pharr,
//! Jakob & Humphreys, *Physically Based Rendering*, 4th ed., §9.1.2) plus
//! a pass-through bit for `null` surfaces and holes, which scatter nothing.
//!
//! Every lobe kind declares its flags ([`super::Bsdf::flags`] is their union
//! at a shading point); [`material_flags`] is the union over everything a
//! material can be anywhere on a surface (textured parameters over their
//! range, both sides of a blend), which is what the plan and photon
//! emission ask without a shading point.

use crate::math::Vec3A;
use crate::scene::Material;
use crate::texture::Texture;

/// A set of lobe kinds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct LobeFlags(u8);

impl LobeFlags {
    /// No lobe (a black surface).
    pub const NONE: Self = Self(0);
    /// Scatters to the side `wo` is on.
    pub const REFLECTION: Self = Self(1);
    /// Scatters through the surface.
    pub const TRANSMISSION: Self = Self(2);
    /// A lobe spread over the hemisphere (Lambert, a coat's base).
    pub const DIFFUSE: Self = Self(4);
    /// A lobe of finite width about a direction (microfacets, Phong).
    pub const GLOSSY: Self = Self(8);
    /// A delta lobe: one direction (mirror, smooth glass or metal, a
    /// smooth coat).
    pub const SPECULAR: Self = Self(16);
    /// Light continues unchanged (a `null` surface, a blend's hole): no
    /// scattering at all, so neither specular nor a transmission lobe.
    pub const PASS_THROUGH: Self = Self(32);
    /// A delta lobe that carries the surface's own reflection or
    /// transmission (a mirror, smooth glass, a smooth metal), as opposed to
    /// a smooth coat's Fresnel reflection over a base: it focuses light into
    /// caustics, so Whitted's photons are aimed at it (the original
    /// report's casters). Always set with [`Self::SPECULAR`].
    pub const CASTS_CAUSTICS: Self = Self(64);

    /// Every flag of `other` is set.
    #[inline]
    pub fn contains(self, other: Self) -> bool {
        self.0 & other.0 == other.0
    }

    /// Some flag of `other` is set.
    #[inline]
    pub fn intersects(self, other: Self) -> bool {
        self.0 & other.0 != 0
    }

    /// No flag is set.
    #[inline]
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Has a delta lobe.
    #[inline]
    pub fn is_specular(self) -> bool {
        self.contains(Self::SPECULAR)
    }

    /// Has a lobe that is not a delta (diffuse or glossy): light sampling
    /// can find it.
    #[inline]
    pub fn is_non_specular(self) -> bool {
        self.intersects(Self::DIFFUSE.union(Self::GLOSSY))
    }

    /// Scatters through the surface.
    #[inline]
    pub fn is_transmissive(self) -> bool {
        self.contains(Self::TRANSMISSION)
    }

    /// These flags without those of `other`.
    #[inline]
    pub const fn without(self, other: Self) -> Self {
        Self(self.0 & !other.0)
    }

    /// Both sets.
    #[inline]
    pub const fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// The flags, named, for messages and tests (`reflection|specular`).
    pub fn names(self) -> String {
        let names = [
            (Self::REFLECTION, "reflection"),
            (Self::TRANSMISSION, "transmission"),
            (Self::DIFFUSE, "diffuse"),
            (Self::GLOSSY, "glossy"),
            (Self::SPECULAR, "specular"),
            (Self::PASS_THROUGH, "pass-through"),
            (Self::CASTS_CAUSTICS, "casts-caustics"),
        ];
        let set: Vec<&str> = names
            .iter()
            .filter(|(f, _)| self.contains(*f))
            .map(|(_, n)| *n)
            .collect();
        if set.is_empty() {
            "none".to_string()
        } else {
            set.join("|")
        }
    }
}

impl std::ops::BitOr for LobeFlags {
    type Output = Self;
    fn bitor(self, other: Self) -> Self {
        self.union(other)
    }
}

impl std::ops::BitOrAssign for LobeFlags {
    fn bitor_assign(&mut self, other: Self) {
        *self = self.union(other);
    }
}

/// The union of the flags of `m`'s BSDF wherever it is seen: each side of
/// a blend (a hole is pass-through), and every textured parameter over its
/// range. The range of an image or checkerboard texture is taken as
/// `[0, its largest value]`, so a textured roughness may be smooth
/// somewhere (specular) and rough elsewhere (glossy): conservative, never
/// missing a lobe a shading point can have.
pub fn material_flags(m: &Material) -> LobeFlags {
    flags_over_range(m, &|m: &Material| {
        super::Bsdf::for_material(m, super::FresnelModel::Exact, super::Transport::Radiance).flags()
    })
}

/// The union of `flags` (the lobe flags of one untextured material) over
/// everything `m` can be: each side of a blend (a hole is pass-through),
/// each textured parameter at the ends of its range.
pub fn flags_over_range(m: &Material, flags: &dyn Fn(&Material) -> LobeFlags) -> LobeFlags {
    if let Some(b) = m.blend.as_deref() {
        let side = |s: &Option<Material>| {
            s.as_ref()
                .map_or(LobeFlags::PASS_THROUGH, |m| flags_over_range(m, flags))
        };
        return side(&b.first) | side(&b.second);
    }
    let Some(t) = m.textures.as_deref().filter(|t| t.has_values()) else {
        return flags(m);
    };
    // The lobes a BSDF builds change with its roughness (smooth or rough)
    // and with its weights (a lobe of weight 0 is left out): every
    // combination of each group at the low and the high end of its range.
    let mut out = LobeFlags::NONE;
    for rough_high in [false, true] {
        for weight_high in [false, true] {
            out |= flags(&at_extremes(m, t, rough_high, weight_high));
        }
    }
    out
}

/// `m` with each textured scalar at the low or high end of its texture's
/// range (roughnesses by `rough_high`, weights by `weight_high`) and each
/// textured colour at its largest.
fn at_extremes(m: &Material, t: &crate::scene::MaterialTextures, rough_high: bool, weight_high: bool) -> Material {
    let end = |tex: &Option<Texture>, value: f32, high: bool| match tex {
        None => value,
        Some(Texture::Constant(c)) => c.x,
        Some(t) if high => t.max_value().max_element(),
        Some(_) => 0.0,
    };
    // Colours only scale lobes that other values choose; at their largest
    // they leave out no lobe (a lobe of colour 0 is left out).
    let colour = |tex: &Option<Texture>, value: Vec3A| tex.as_ref().map_or(value, Texture::max_value);
    let (r, w) = (rough_high, weight_high);
    let mut v = m.clone();
    v.textures = None;
    v.diffuse = colour(&t.diffuse, m.diffuse);
    v.specular = colour(&t.specular, m.specular);
    if let Some(mi) = v.mirror.as_mut() {
        mi.reflectivity = end(&t.mirror_reflectivity, mi.reflectivity, w).clamp(0.0, 1.0);
        mi.tint = colour(&t.mirror_tint, mi.tint);
    }
    if let Some(d) = v.dielectric.as_mut() {
        d.roughness = end(&t.dielectric_roughness, d.roughness, r).max(0.0);
        d.tint = colour(&t.dielectric_tint, d.tint);
    }
    if let Some(c) = v.conductor.as_mut() {
        c.roughness = end(&t.conductor_roughness, c.roughness, r).max(0.0);
    }
    v.roughness_v = m.roughness_v.map(|x| end(&t.roughness_v, x, r).max(0.0));
    if let Some(p) = v.principled.as_mut() {
        p.roughness = end(&t.principled_roughness, p.roughness, r).clamp(0.0, 1.0);
        p.clearcoat_roughness = end(&t.principled_clearcoat_roughness, p.clearcoat_roughness, r).clamp(0.0, 1.0);
        p.metallic = end(&t.principled_metallic, p.metallic, w).clamp(0.0, 1.0);
        p.transmission = end(&t.principled_transmission, p.transmission, w).clamp(0.0, 1.0);
        p.clearcoat = end(&t.principled_clearcoat, p.clearcoat, w).clamp(0.0, 1.0);
    }
    if let Some(d) = v.disney.as_mut() {
        d.roughness = end(&t.disney_roughness, d.roughness, r);
        d.metallic = end(&t.disney_metallic, d.metallic, w);
        d.spec_trans = end(&t.disney_spec_trans, d.spec_trans, w);
        d.diff_trans = end(&t.disney_diff_trans, d.diff_trans, w);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Bsdf, FresnelModel, Transport};
    use crate::math::{Rng, Vec2};
    use crate::scene::{Blend, Coating, Conductor, Dielectric, Disney, Mirror, Principled};

    fn plain(name: &str) -> Material {
        Material::diffuse(name, Vec3A::splat(0.6))
    }

    /// One material of every BSDF kind.
    fn kinds() -> Vec<Material> {
        let glass = |roughness: f32, thin: bool| Material {
            dielectric: Some(Dielectric {
                roughness,
                thin,
                ..Dielectric::smooth(1.5, Vec3A::ONE)
            }),
            ..Material::diffuse("glass", Vec3A::ZERO)
        };
        let metal = |roughness: f32, roughness_v: Option<f32>| Material {
            conductor: Some(Conductor {
                eta: Vec3A::new(0.2, 0.9, 1.1),
                k: Vec3A::new(3.9, 2.4, 2.2),
                roughness,
            }),
            roughness_v,
            ..Material::diffuse("metal", Vec3A::ZERO)
        };
        let coated = |roughness: f32| Material {
            coating: Some(Coating {
                roughness,
                ..Coating::smooth(1.5)
            }),
            ..plain("coated")
        };
        let principled = |roughness: f32, metallic: f32, transmission: f32, clearcoat: f32| Material {
            principled: Some(Principled {
                roughness,
                metallic,
                transmission,
                thin: false,
                clearcoat,
                clearcoat_roughness: 0.0,
                ..Principled::default()
            }),
            ..plain("principled")
        };
        vec![
            plain("lambert"),
            Material {
                specular: Vec3A::splat(0.3),
                shininess: 20.0,
                ..plain("phong")
            },
            Material {
                mirror: Some(Mirror {
                    reflectivity: 0.5,
                    tint: Vec3A::ONE,
                }),
                ..plain("half mirror")
            },
            glass(0.0, false),
            glass(0.0, true),
            glass(0.3, false),
            metal(0.0, None),
            metal(0.3, None),
            metal(0.3, Some(0.05)),
            coated(0.0),
            coated(0.3),
            principled(0.0, 0.0, 1.0, 0.0),
            principled(0.5, 1.0, 0.0, 0.0),
            principled(0.5, 0.0, 0.0, 1.0),
            principled(0.4, 0.0, 0.6, 0.0),
            Material {
                disney: Some(Disney {
                    spec_trans: 0.5,
                    metallic: 0.2,
                    ..Disney::default()
                }),
                ..plain("disney")
            },
            Material {
                disney: Some(Disney::default()),
                ..plain("opaque disney")
            },
            Material {
                null: true,
                ..plain("null")
            },
        ]
    }

    /// What one sample is.
    fn kind_of(s: &crate::bsdf::BsdfSample, null: bool) -> LobeFlags {
        if null {
            return LobeFlags::PASS_THROUGH;
        }
        let lobe = if s.delta {
            LobeFlags::SPECULAR
        } else {
            LobeFlags::DIFFUSE | LobeFlags::GLOSSY
        };
        let side = if s.transmission {
            LobeFlags::TRANSMISSION
        } else {
            LobeFlags::REFLECTION
        };
        lobe | side
    }

    /// Each kind's declared flags agree with what its `sample` returns:
    /// no sample of an undeclared kind, and every declared kind sampled.
    #[test]
    fn every_kind_samples_what_it_declares() {
        for m in kinds() {
            let bsdf = Bsdf::for_material(&m, FresnelModel::Exact, Transport::Radiance);
            let declared = bsdf.flags();
            assert_eq!(declared, material_flags(&m), "{}", m.name);
            let mut seen = LobeFlags::NONE;
            let mut rng = Rng::for_pixel(1, 2, 3);
            for i in 0..4000 {
                // From above, and from below for the kinds that transmit.
                let z = 0.05 + 0.9 * rng.f32();
                let phi = std::f32::consts::TAU * rng.f32();
                let r = (1.0 - z * z).sqrt();
                let z = if i % 2 == 1 { -z } else { z };
                let wo = Vec3A::new(r * phi.cos(), r * phi.sin(), z);
                let Some(s) = bsdf.sample(wo, rng.f32(), Vec2::new(rng.f32(), rng.f32())) else {
                    continue;
                };
                let kind = kind_of(&s, m.null);
                // The sample's lobe kind and side must both be declared.
                let lobe_ok = if s.delta {
                    declared.intersects(LobeFlags::SPECULAR | LobeFlags::PASS_THROUGH)
                } else {
                    declared.is_non_specular()
                };
                let side_ok = m.null
                    || declared.contains(if s.transmission {
                        LobeFlags::TRANSMISSION
                    } else {
                        LobeFlags::REFLECTION
                    });
                assert!(
                    lobe_ok && side_ok,
                    "{}: declared {}, sampled {}",
                    m.name,
                    declared.names(),
                    kind.names()
                );
                seen |= if s.delta && !m.null {
                    LobeFlags::SPECULAR
                } else {
                    LobeFlags::NONE
                };
                seen |= if !s.delta { LobeFlags::GLOSSY } else { LobeFlags::NONE };
                seen |= if s.transmission && !m.null {
                    LobeFlags::TRANSMISSION
                } else {
                    LobeFlags::NONE
                };
                seen |= if m.null {
                    LobeFlags::PASS_THROUGH
                } else {
                    LobeFlags::NONE
                };
            }
            for (flag, what) in [
                (LobeFlags::SPECULAR, "a delta"),
                (LobeFlags::TRANSMISSION, "a transmission"),
                (LobeFlags::PASS_THROUGH, "a pass-through"),
            ] {
                assert_eq!(
                    declared.contains(flag),
                    seen.contains(flag),
                    "{}: declares {}, {what} sample {}",
                    m.name,
                    declared.names(),
                    if seen.contains(flag) { "seen" } else { "never seen" }
                );
            }
            assert_eq!(
                declared.is_non_specular(),
                seen.contains(LobeFlags::GLOSSY),
                "{}: declares {}",
                m.name,
                declared.names()
            );
        }
    }

    #[test]
    fn the_predicates_read_the_flags() {
        let k = kinds();
        let get = |name: &str| {
            let m = k.iter().find(|m| m.name == name).unwrap();
            Bsdf::for_material(m, FresnelModel::Exact, Transport::Radiance)
        };
        assert!(get("glass").is_delta() && get("glass").has_delta_lobe());
        assert!(!get("glass").has_smooth_lobe());
        assert!(get("coated").has_delta_lobe() && get("coated").has_smooth_lobe());
        assert!(!get("null").has_delta_lobe() && !get("null").has_smooth_lobe());
        assert!(!get("lambert").has_delta_lobe() && get("lambert").has_smooth_lobe());
        assert_eq!(
            get("lambert").flags().names(),
            "reflection|diffuse",
            "flags name themselves"
        );
    }

    /// A material's flags, without a shading point: a blend is the union of
    /// its sides (a hole passes through), a textured roughness is both
    /// smooth and rough unless it is constant.
    #[test]
    fn material_flags_cover_blends_and_textured_parameters() {
        let glass = Material {
            dielectric: Some(Dielectric::smooth(1.5, Vec3A::ONE)),
            ..plain("glass")
        };
        let blend = Material {
            blend: Some(Box::new(Blend {
                weight: 0.5,
                weight_texture: None,
                first: Some(plain("white")),
                second: Some(glass),
            })),
            ..plain("blend")
        };
        let f = material_flags(&blend);
        assert!(
            f.is_specular() && f.is_transmissive() && f.contains(LobeFlags::DIFFUSE),
            "{}",
            f.names()
        );
        let holey = Material {
            blend: Some(Box::new(Blend {
                weight: 0.5,
                weight_texture: None,
                first: Some(plain("white")),
                second: None,
            })),
            ..plain("holey")
        };
        assert_eq!(
            material_flags(&holey),
            LobeFlags::DIFFUSE | LobeFlags::REFLECTION | LobeFlags::PASS_THROUGH
        );
        let rough_metal = |texture: Texture| Material {
            conductor: Some(Conductor {
                eta: Vec3A::ONE,
                k: Vec3A::ONE,
                roughness: 0.3,
            }),
            textures: Some(Box::new(crate::scene::MaterialTextures {
                conductor_roughness: Some(texture),
                ..Default::default()
            })),
            ..plain("metal")
        };
        let constant = rough_metal(Texture::Constant(Vec3A::splat(0.4)));
        assert_eq!(material_flags(&constant), LobeFlags::GLOSSY | LobeFlags::REFLECTION);
        let checker = Texture::Checkerboard(crate::texture::Checkerboard {
            colour0: Vec3A::splat(0.2),
            colour1: Vec3A::splat(0.6),
            transform: Default::default(),
        });
        let textured = material_flags(&rough_metal(checker));
        assert_eq!(
            textured,
            LobeFlags::GLOSSY | LobeFlags::SPECULAR | LobeFlags::CASTS_CAUSTICS | LobeFlags::REFLECTION,
            "{}",
            textured.names()
        );
    }
}
