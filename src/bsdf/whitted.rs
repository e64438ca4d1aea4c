//! How the Whitted integrator and its photons scatter at a material: the
//! original report's model, one decision per kind, read here once.
//!
//! - A Phong surface (Lambert and a Phong or Blinn-Phong highlight), part
//!   mirror by its `reflectivity`.
//! - A dielectric: one smooth interface (Snell and Fresnel), whatever its
//!   roughness, as the report refracts.
//! - Everything with a BSDF of its own (metals, coated diffuse, glTF's
//!   principled): its non-delta lobes are lit directly and its delta
//!   reflection, if any, is followed, weighted by the BSDF's reflectance.
//!
//! Each kind declares its [`LobeFlags`] as Whitted sees it, and
//! [`whitted_flags`] is their union over everything a material can be:
//! what the plan, the photon emitter's choice of casters and the viewer ask.
//! Kinds Whitted has no rule for (Mitsuba's principled) are shaded as Phong
//! surfaces of their colours.

use super::{flags_over_range, Bsdf, FresnelModel, LobeFlags, Transport};
use crate::scene::{Conductor, Dielectric, Material, Mirror};

/// How Whitted scatters at one (resolved, untextured) material. Small on
/// purpose (no BSDF inside): the photon tracer builds one per hit.
#[derive(Clone, Copy, Debug)]
pub enum WhittedKind {
    /// The report's Phong surface; a mirror part reflects `reflectivity` of
    /// the light.
    Phong {
        /// The mirror part, when the material has one.
        mirror: Option<Mirror>,
    },
    /// A smooth dielectric interface.
    Dielectric(Dielectric),
    /// A surface scattered by its BSDF (Fresnel exact, radiance transport;
    /// [`WhittedSurface::with_bsdf`] returns it).
    Layered {
        /// A smooth metal: its photons reflect with the conductor's Fresnel
        /// colour.
        smooth_metal: Option<Conductor>,
    },
    /// A `null` surface: light passes unchanged.
    PassThrough,
}

/// A material as Whitted scatters it, with the lobes it has in that model.
#[derive(Clone, Copy, Debug)]
pub struct WhittedSurface {
    /// What Whitted does at the surface.
    pub kind: WhittedKind,
    /// The lobes of [`Self::kind`]: a dielectric is specular and casts
    /// caustics; a layered surface has its BSDF's reflection lobes.
    pub flags: LobeFlags,
}

impl WhittedSurface {
    /// The Whitted model of `m`, a material resolved at a shading point
    /// (not a blend; its textures looked up).
    pub fn of(m: &Material) -> Self {
        Self::with_bsdf(m).0
    }

    /// [`of`](Self::of), and for a [`WhittedKind::Layered`] surface the
    /// BSDF its flags were read from, which the integrator then scatters
    /// by (built once per shading point).
    pub fn with_bsdf(m: &Material) -> (Self, Option<Bsdf<'_>>) {
        use LobeFlags as F;
        if m.null {
            let surface = Self {
                kind: WhittedKind::PassThrough,
                flags: F::PASS_THROUGH,
            };
            return (surface, None);
        }
        if let Some(d) = m.dielectric {
            let surface = Self {
                kind: WhittedKind::Dielectric(d),
                flags: F::SPECULAR | F::CASTS_CAUSTICS | F::REFLECTION | F::TRANSMISSION,
            };
            return (surface, None);
        }
        if m.conductor.is_some() || m.coating.is_some() || m.principled.is_some() {
            let bsdf = Bsdf::for_material(m, FresnelModel::Exact, Transport::Radiance);
            // Whitted follows a layered surface's reflection only.
            let flags = bsdf.flags().without(F::TRANSMISSION);
            let smooth_metal = m.conductor.filter(|_| flags.is_specular());
            let surface = Self {
                kind: WhittedKind::Layered { smooth_metal },
                flags,
            };
            return (surface, Some(bsdf));
        }
        let r = m.mirror.map_or(0.0, |mi| mi.reflectivity);
        let mut flags = F::NONE;
        if m.diffuse.max_element() > 0.0 && r < 1.0 {
            flags |= F::DIFFUSE | F::REFLECTION;
        }
        if m.specular.max_element() > 0.0 && r < 1.0 {
            flags |= F::GLOSSY | F::REFLECTION;
        }
        if r > 0.0 {
            flags |= F::SPECULAR | F::CASTS_CAUSTICS | F::REFLECTION;
        }
        let surface = Self {
            kind: WhittedKind::Phong { mirror: m.mirror },
            flags,
        };
        (surface, None)
    }
}

/// The union of [`WhittedSurface::flags`] over everything `m` can be at a
/// shading point: both sides of a blend (a hole passes light through) and
/// every textured parameter over its range, as
/// [`super::material_flags`] takes it.
pub fn whitted_flags(m: &Material) -> LobeFlags {
    flags_over_range(m, &|m: &Material| WhittedSurface::of(m).flags)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3A;
    use crate::scene::{Blend, Coating, MaterialTextures, Principled};
    use crate::texture::{Checkerboard, Texture};
    use LobeFlags as F;

    fn plain(name: &str) -> Material {
        Material::diffuse(name, Vec3A::splat(0.6))
    }

    fn mirror(reflectivity: f32) -> Material {
        Material {
            mirror: Some(Mirror {
                reflectivity,
                tint: Vec3A::ONE,
            }),
            ..plain("mirror")
        }
    }

    fn metal(roughness: f32) -> Material {
        Material {
            conductor: Some(Conductor {
                eta: Vec3A::new(0.2, 0.9, 1.1),
                k: Vec3A::new(3.9, 2.4, 2.2),
                roughness,
            }),
            ..Material::diffuse("metal", Vec3A::ZERO)
        }
    }

    fn coated(diffuse: f32) -> Material {
        Material {
            coating: Some(Coating::smooth(1.5)),
            ..Material::diffuse("coated", Vec3A::splat(diffuse))
        }
    }

    fn principled(roughness: f32, metallic: f32, transmission: f32) -> Material {
        Material {
            principled: Some(Principled {
                roughness,
                metallic,
                transmission,
                ..Principled::default()
            }),
            ..plain("principled")
        }
    }

    fn casts(m: &Material) -> bool {
        whitted_flags(m).contains(F::CASTS_CAUSTICS)
    }

    #[test]
    fn mirrors_glass_and_smooth_metals_cast_caustics_and_coats_do_not() {
        assert!(casts(&mirror(0.5)) && casts(&mirror(1.0)));
        assert!(!casts(&mirror(0.0)));
        assert!(casts(&metal(0.0)));
        assert!(!casts(&metal(0.3)));
        assert!(casts(&principled(0.0, 1.0, 0.0)) && casts(&principled(0.0, 0.0, 1.0)));
        for m in [
            coated(0.6),
            principled(0.0, 0.0, 0.0),
            principled(0.5, 1.0, 0.0),
            plain("white"),
        ] {
            assert!(!casts(&m), "{}: {}", m.name, whitted_flags(&m).names());
        }
        // A smooth coat and a smooth dielectric layer still reflect: Whitted
        // follows them.
        assert!(whitted_flags(&coated(0.6)).is_specular());
        assert!(whitted_flags(&principled(0.0, 0.0, 0.0)).is_specular());
    }

    #[test]
    fn whitted_refracts_every_dielectric_through_one_smooth_interface() {
        for roughness in [0.0, 0.4] {
            let glass = Material {
                dielectric: Some(Dielectric {
                    roughness,
                    ..Dielectric::smooth(1.5, Vec3A::ONE)
                }),
                ..Material::diffuse("glass", Vec3A::ZERO)
            };
            assert!(matches!(WhittedSurface::of(&glass).kind, WhittedKind::Dielectric(_)));
            assert_eq!(
                whitted_flags(&glass),
                F::SPECULAR | F::CASTS_CAUSTICS | F::REFLECTION | F::TRANSMISSION
            );
        }
    }

    #[test]
    fn the_diffuse_part_is_what_receives_photons() {
        let diffuse = |m: &Material| whitted_flags(m).contains(F::DIFFUSE);
        assert!(diffuse(&plain("white")) && diffuse(&mirror(0.5)) && diffuse(&coated(0.6)));
        assert!(!diffuse(&mirror(1.0)), "a perfect mirror has no diffuse part");
        assert!(!diffuse(&coated(0.0)), "a black base under a coat");
        assert!(!diffuse(&metal(0.0)) && !diffuse(&metal(0.3)));
        assert!(!diffuse(&Material::diffuse("black", Vec3A::ZERO)));
        assert!(!diffuse(&principled(0.5, 1.0, 0.0)) && diffuse(&principled(0.5, 0.5, 0.0)));
    }

    #[test]
    fn blends_and_textures_take_every_side_and_the_whole_range() {
        let holey = Material {
            blend: Some(Box::new(Blend {
                weight: 0.5,
                weight_texture: None,
                first: Some(mirror(1.0)),
                second: None,
            })),
            ..plain("holey")
        };
        let f = whitted_flags(&holey);
        assert!(f.contains(F::CASTS_CAUSTICS | F::PASS_THROUGH), "{}", f.names());
        // A mirror whose reflectivity a texture sets is a caster where the
        // texture is above 0 and diffuse where it is below 1.
        let textured = Material {
            textures: Some(Box::new(MaterialTextures {
                mirror_reflectivity: Some(Texture::Checkerboard(Checkerboard {
                    colour0: Vec3A::ZERO,
                    colour1: Vec3A::ONE,
                    transform: Default::default(),
                })),
                ..MaterialTextures::default()
            })),
            ..mirror(0.0)
        };
        let f = whitted_flags(&textured);
        assert!(f.contains(F::CASTS_CAUSTICS | F::DIFFUSE), "{}", f.names());
        let null = Material {
            null: true,
            ..plain("null")
        };
        assert_eq!(whitted_flags(&null), F::PASS_THROUGH);
    }
}
