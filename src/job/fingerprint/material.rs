//! Materials' encoding: every kind's parameters, their textures by
//! content, emission and blends (each side whole). The name is left out:
//! it only labels messages.

use super::encoder::{Encoder, Fingerprint};
use crate::scene::{
    AlphaMask, Blend, BumpMap, Coating, Conductor, Dielectric, Disney, FresnelModel, Material, MaterialTextures,
    MicrofacetDistribution, Mirror, NormalMap, Principled, ShadingModel,
};
use crate::texture::Texture;

impl Fingerprint for Material {
    fn encode(&self, e: &mut Encoder) {
        let Material {
            name: _,
            model,
            ambient,
            diffuse,
            specular,
            shininess,
            mirror,
            dielectric,
            conductor,
            coating,
            principled,
            disney,
            emission,
            emits_both_sides,
            one_sided,
            microfacet,
            roughness_v,
            null,
            textures,
            blend,
        } = self;
        e.tag("material");
        e.u8(match model {
            ShadingModel::Phong => 0,
            ShadingModel::BlinnPhong => 1,
        });
        e.put(ambient);
        e.put(diffuse);
        e.put(specular);
        e.f32(*shininess);
        e.option(mirror.as_ref(), |e, m| e.put(m));
        e.option(dielectric.as_ref(), |e, d| e.put(d));
        e.option(conductor.as_ref(), |e, c| e.put(c));
        e.option(coating.as_ref(), |e, c| e.put(c));
        e.option(principled.as_ref(), |e, p| e.put(p));
        e.option(disney.as_ref(), |e, d| e.put(d));
        e.put(emission);
        e.bool(*one_sided);
        e.u8(match microfacet {
            MicrofacetDistribution::Ggx => 0,
            MicrofacetDistribution::Beckmann => 1,
        });
        e.option(roughness_v.as_ref(), |e, v| e.f32(*v));
        e.bool(*null);
        e.option(textures.as_deref(), |e, t| e.put(t));
        e.option(blend.as_deref(), |e, b| e.put(b));
        // Appended only when set: one-sided emitters keep their encoding.
        if *emits_both_sides {
            e.tag("emits both sides");
        }
    }
}

impl Fingerprint for Mirror {
    fn encode(&self, e: &mut Encoder) {
        let Mirror { reflectivity, tint } = self;
        e.tag("mirror");
        e.f32(*reflectivity);
        e.put(tint);
    }
}

impl Fingerprint for Dielectric {
    fn encode(&self, e: &mut Encoder) {
        let Dielectric {
            ior,
            tint,
            roughness,
            fresnel,
            thin,
        } = self;
        e.tag("dielectric");
        e.f32(*ior);
        e.put(tint);
        e.f32(*roughness);
        e.option(fresnel.as_ref(), |e, f| {
            e.u8(match f {
                FresnelModel::Exact => 0,
                FresnelModel::Schlick => 1,
            })
        });
        e.bool(*thin);
    }
}

impl Fingerprint for Conductor {
    fn encode(&self, e: &mut Encoder) {
        let Conductor { eta, k, roughness } = self;
        e.tag("conductor");
        e.put(eta);
        e.put(k);
        e.f32(*roughness);
    }
}

impl Fingerprint for Coating {
    fn encode(&self, e: &mut Encoder) {
        // The table is computed from the other fields.
        let Coating {
            ior,
            roughness,
            nonlinear,
            table: _,
        } = self;
        e.tag("coating");
        e.f32(*ior);
        e.f32(*roughness);
        e.bool(*nonlinear);
    }
}

impl Fingerprint for Principled {
    fn encode(&self, e: &mut Encoder) {
        let Principled {
            metallic,
            roughness,
            ior,
            transmission,
            thin,
            clearcoat,
            clearcoat_roughness,
        } = self;
        e.tag("gltf principled");
        e.f32(*metallic);
        e.f32(*roughness);
        e.f32(*ior);
        e.f32(*transmission);
        e.bool(*thin);
        e.f32(*clearcoat);
        e.f32(*clearcoat_roughness);
    }
}

impl Fingerprint for Disney {
    fn encode(&self, e: &mut Encoder) {
        let Disney {
            roughness,
            anisotropic,
            metallic,
            spec_trans,
            eta,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            diffuse_sampling_rate,
            specular_sampling_rate,
            clearcoat_sampling_rate,
            thin,
            diff_trans,
            specular_transmission_sampling_rate,
            diffuse_transmission_sampling_rate,
        } = self;
        e.tag("disney");
        e.floats(&[
            *roughness,
            *anisotropic,
            *metallic,
            *spec_trans,
            *eta,
            *spec_tint,
            *sheen,
            *sheen_tint,
            *flatness,
            *clearcoat,
            *clearcoat_gloss,
            *diffuse_sampling_rate,
            *specular_sampling_rate,
            *clearcoat_sampling_rate,
        ]);
        // Mitsuba's `principledthin`: its own values after the flag.
        e.bool(*thin);
        if *thin {
            e.floats(&[
                *diff_trans,
                *specular_transmission_sampling_rate,
                *diffuse_transmission_sampling_rate,
            ]);
        }
    }
}

impl Fingerprint for Blend {
    fn encode(&self, e: &mut Encoder) {
        let Blend {
            weight,
            weight_texture,
            first,
            second,
        } = self;
        e.tag("blend");
        e.f32(*weight);
        e.option(weight_texture.as_ref(), |e, t| e.put(t));
        // `None`: a hole.
        e.option(first.as_ref(), |e, m| e.put(m));
        e.option(second.as_ref(), |e, m| e.put(m));
    }
}

impl Fingerprint for MaterialTextures {
    fn encode(&self, e: &mut Encoder) {
        let MaterialTextures {
            ambient,
            diffuse,
            specular,
            shininess,
            mirror_reflectivity,
            mirror_tint,
            dielectric_tint,
            dielectric_roughness,
            conductor_roughness,
            roughness_v,
            principled_metallic,
            principled_roughness,
            principled_transmission,
            principled_clearcoat,
            principled_clearcoat_roughness,
            disney_roughness,
            disney_anisotropic,
            disney_metallic,
            disney_spec_trans,
            disney_spec_tint,
            disney_sheen,
            disney_sheen_tint,
            disney_flatness,
            disney_clearcoat,
            disney_clearcoat_gloss,
            disney_diff_trans,
            disney_eta,
            emission,
            normal_map,
            bump_map,
            alpha,
        } = self;
        e.tag("material textures");
        // Only the slots that are set, each after its own tag: a slot
        // added later leaves the encoding of materials without it as it was.
        let slots: [(&str, &Option<Texture>); 28] = [
            ("ambient", ambient),
            ("diffuse", diffuse),
            ("specular", specular),
            ("shininess", shininess),
            ("mirror reflectivity", mirror_reflectivity),
            ("mirror tint", mirror_tint),
            ("dielectric tint", dielectric_tint),
            ("dielectric roughness", dielectric_roughness),
            ("conductor roughness", conductor_roughness),
            ("roughness v", roughness_v),
            ("principled metallic", principled_metallic),
            ("principled roughness", principled_roughness),
            ("principled transmission", principled_transmission),
            ("principled clearcoat", principled_clearcoat),
            ("principled clearcoat roughness", principled_clearcoat_roughness),
            ("disney roughness", disney_roughness),
            ("disney anisotropic", disney_anisotropic),
            ("disney metallic", disney_metallic),
            ("disney spec trans", disney_spec_trans),
            ("disney spec tint", disney_spec_tint),
            ("disney sheen", disney_sheen),
            ("disney sheen tint", disney_sheen_tint),
            ("disney flatness", disney_flatness),
            ("disney clearcoat", disney_clearcoat),
            ("disney clearcoat gloss", disney_clearcoat_gloss),
            ("disney diff trans", disney_diff_trans),
            ("disney eta", disney_eta),
            ("emission", emission),
        ];
        for (tag, texture) in slots {
            if let Some(t) = texture {
                e.tag(tag);
                e.put(t);
            }
        }
        if let Some(NormalMap { texture, scale }) = normal_map {
            e.tag("normal map");
            e.put(texture);
            e.f32(*scale);
        }
        if let Some(BumpMap { texture, scale }) = bump_map {
            e.tag("bump map");
            e.put(texture);
            e.f32(*scale);
        }
        if let Some(AlphaMask { texture, cutoff }) = alpha {
            e.tag("alpha mask");
            e.put(texture);
            e.f32(*cutoff);
        }
        e.tag("end");
    }
}
