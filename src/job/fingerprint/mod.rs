//! The fingerprint of a render: everything that changes its samples, so
//! that a checkpoint is only ever resumed by the same render.
//!
//! What a resume relies on: the film is a pure function of (scene, settings,
//! accelerator, seed) per pixel and sample index (see `integrator::render`),
//! and the photon pass is deterministic for any thread count, so it is
//! simply re-run on resume rather than stored (a 10M-photon map would weigh
//! hundreds of MiB; re-tracing it costs seconds).
//!
//! The encoding is explicit and versioned: every type writes its own bytes
//! ([`Fingerprint`], one module per kind of thing), little-endian, after
//! tags of the fingerprint's own, so renaming a Rust field or changing a
//! `Debug` form changes no fingerprint; meshes and images are hashed by
//! content. A change to the bytes a scene already encodes to (a new value
//! in an existing kind, another order, another tag) must bump
//! [`FINGERPRINT_FORMAT`]: checkpoints and partials record the format their
//! fingerprint was computed in, and one of another format is refused with a
//! message that says so (the old fingerprint can no longer be computed). A
//! new kind (a new enum variant, a texture slot encoded only when set)
//! leaves the scenes without it unchanged and needs no bump.

mod camera;
mod encoder;
mod geometry;
mod light;
mod material;
mod media;
mod settings;
mod texture;

pub use encoder::{Encoder, Fingerprint};

use crate::accel::AccelKind;
use crate::film::CheckpointMeta;
use crate::scene::{RenderSettings, Scene};

/// The version of the fingerprint's encoding, recorded in checkpoints and
/// partials (`caustic.fingerprint.format`) and in photon files (their magic).
/// Format 1 (files without the attribute) hashed the `Debug` text of the
/// scene's types; format 2 is the explicit encoding of this module.
pub const FINGERPRINT_FORMAT: u32 = 2;

/// Hex SHA-256 of everything that decides the samples: the scene (camera,
/// materials, lights, objects, mesh geometry, media), the render settings
/// except the display-only tone map, exposure and denoising, the
/// accelerator and its options (`accel_options`: e.g. Embree's build
/// quality; hits can differ in the last bits between backends), the
/// fingerprint format and the crate version. Thread count and the shard a
/// process renders are not included: they never change a sample, and every
/// shard of a render shares its fingerprint.
pub fn fingerprint(scene: &Scene, settings: &RenderSettings, accel: AccelKind, accel_options: &str) -> String {
    fingerprint_of(scene, settings, None, accel, accel_options)
}

/// Hex SHA-256 of everything the traced photons depend on
/// (`caustic photons`, `--photon-map`): [`fingerprint`]'s fields with the
/// image size, samples per pixel, sampler and adaptive sampling left out
/// (the trace never reads them; the map's precompute, which depends on the
/// image size, runs when a render loads the photons), and a purpose field
/// so that it never equals a render's fingerprint.
pub fn photon_fingerprint(scene: &Scene, settings: &RenderSettings, accel: AccelKind, accel_options: &str) -> String {
    let defaults = RenderSettings::default();
    let settings = RenderSettings {
        width: defaults.width,
        height: defaults.height,
        spp: defaults.spp,
        noise_threshold: None,
        min_spp: defaults.min_spp,
        adaptive_goal: defaults.adaptive_goal,
        sampler: None,
        ..settings.clone()
    };
    fingerprint_of(scene, &settings, Some("photons"), accel, accel_options)
}

fn fingerprint_of(
    scene: &Scene,
    settings: &RenderSettings,
    purpose: Option<&str>,
    accel: AccelKind,
    accel_options: &str,
) -> String {
    let mut e = Encoder::new();
    e.tag("caustic fingerprint");
    e.u32(FINGERPRINT_FORMAT);
    // Another caustic may compute other samples from the same scene.
    e.bytes(env!("CARGO_PKG_VERSION").as_bytes());
    e.option(purpose.as_ref(), |e, p| e.tag(p));
    encode_render(&mut e, scene, settings, accel, accel_options);
    e.finish()
}

/// The render's encoding after the header (format, crate version,
/// purpose): what the golden test pins.
fn encode_render(e: &mut Encoder, scene: &Scene, settings: &RenderSettings, accel: AccelKind, accel_options: &str) {
    // Exhaustive, so that a new part of the scene does not compile until it
    // is encoded here.
    let Scene {
        camera,
        materials,
        lights,
        meshes,
        objects,
        media,
        ambient,
        water_medium,
    } = scene;
    settings::encode_settings(e, settings, *ambient, water_medium.as_ref());
    e.put(camera);
    e.tag("materials");
    e.u64(materials.len() as u64);
    for m in materials {
        e.put(m);
    }
    e.tag("lights");
    e.u64(lights.len() as u64);
    for l in lights {
        e.put(l);
    }
    e.tag("meshes");
    e.u64(meshes.len() as u64);
    for m in meshes {
        e.put(m.as_ref());
    }
    e.tag("objects");
    e.u64(objects.len() as u64);
    for o in objects {
        e.put(o);
    }
    e.put(media);
    e.tag("accelerator");
    e.tag(accel.name());
    e.bytes(accel_options.as_bytes());
}

/// Why a checkpoint or partial of fingerprint format `found` cannot be
/// compared with this caustic's fingerprints, or `None` when it can.
pub fn format_refusal(found: u32) -> Option<String> {
    if found == FINGERPRINT_FORMAT {
        return None;
    }
    let who = if found < FINGERPRINT_FORMAT {
        "an older"
    } else {
        "a newer"
    };
    Some(format!(
        "written by {who} caustic (fingerprint format {found}; this one writes format {FINGERPRINT_FORMAT} and cannot \
         compute the other), so it cannot be checked against this scene; finish it with the caustic that started \
         it, or render again without it"
    ))
}

/// What differs between a checkpoint's recorded settings and this run's, in
/// words (the fingerprint alone cannot say).
pub fn differences(then: &CheckpointMeta, now: &CheckpointMeta) -> String {
    differences_between(then, "in the checkpoint", now, "now")
}

/// What differs between two recorded settings, each side described by its
/// label ("in a.exr", "now").
pub fn differences_between(then: &CheckpointMeta, then_label: &str, now: &CheckpointMeta, now_label: &str) -> String {
    let mut diffs = Vec::new();
    let mut field = |name: &str, a: String, b: String| {
        if a != b {
            diffs.push(format!("{name} {a} {then_label}, {b} {now_label}"));
        }
    };
    field("width", then.width.to_string(), now.width.to_string());
    field("height", then.height.to_string(), now.height.to_string());
    field("spp", then.spp.to_string(), now.spp.to_string());
    field("seed", then.seed.to_string(), now.seed.to_string());
    field("photons", then.photons.to_string(), now.photons.to_string());
    field("accelerator", then.accel.clone(), now.accel.clone());
    if diffs.is_empty() {
        "the scene file, a mesh or another setting changed".to_string()
    } else {
        diffs.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Vec3, Vec3A};
    use crate::scene::light::{SpotFalloff, SpotLight};
    use crate::scene::{Light, LoadedScene, Material, Object, Shape};
    use std::sync::Arc;

    /// A small scene built in code (no loader defaults): a textured diffuse
    /// quad, a glass sphere, a rough metal mesh, a point and an area light.
    fn small() -> LoadedScene {
        let settings = RenderSettings {
            width: 32,
            height: 24,
            spp: 4,
            seed: 7,
            max_depth: Some(5),
            ..RenderSettings::default()
        };
        let camera = crate::scene::Camera::new(Vec3A::new(0.0, 1.0, 4.0), Vec3A::ZERO, Vec3A::Y, 40.0).unwrap();
        let texels = crate::texture::image::Texels::Rgba8 {
            data: vec![[10, 20, 30, 255], [40, 50, 60, 255], [70, 80, 90, 255], [1, 2, 3, 255]],
            space: crate::texture::ColourSpace::Srgb,
        };
        let image = Arc::new(crate::texture::Image::new("t.png", 2, 2, texels));
        let mut floor = Material::diffuse("floor", Vec3A::splat(0.5));
        floor.textures = Some(Box::new(crate::scene::MaterialTextures {
            diffuse: Some(crate::texture::Texture::Image(crate::texture::ImageTexture::new(image))),
            ..Default::default()
        }));
        let glass = Material {
            dielectric: Some(crate::scene::Dielectric::smooth(1.5, Vec3A::ONE)),
            ..Material::diffuse("glass", Vec3A::ZERO)
        };
        let metal = Material {
            conductor: Some(crate::scene::Conductor {
                eta: Vec3A::new(0.2, 0.9, 1.1),
                k: Vec3A::new(3.9, 2.4, 2.2),
                roughness: 0.2,
            }),
            ..Material::diffuse("metal", Vec3A::ZERO)
        };
        let mesh =
            crate::geometry::Mesh::new("tri", vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]], None).unwrap();
        let scene = Scene {
            camera,
            materials: vec![floor, glass, metal],
            lights: vec![
                Light::Point {
                    position: Vec3A::new(1.0, 3.0, 1.0),
                    intensity: Vec3A::splat(20.0),
                },
                Light::Area(crate::scene::AreaLight {
                    center: Vec3A::new(0.0, 2.9, 0.0),
                    u: Vec3A::X,
                    v: Vec3A::Z,
                    normal: -Vec3A::Y,
                    radiance: Vec3A::splat(5.0),
                    samples: 4,
                }),
            ],
            meshes: vec![Arc::new(mesh)],
            objects: vec![
                Object {
                    name: "floor".into(),
                    shape: Shape::Quad(
                        crate::scene::Quad::new(Vec3A::splat(-1.0), Vec3A::X * 2.0, Vec3A::Z * 2.0).unwrap(),
                    ),
                    material: 0,
                },
                Object {
                    name: "ball".into(),
                    shape: Shape::Sphere(crate::scene::Sphere {
                        center: Vec3A::Y * 0.5,
                        radius: 0.5,
                    }),
                    material: 1,
                },
                Object {
                    name: "tri".into(),
                    shape: Shape::Mesh {
                        mesh: 0,
                        transform: crate::math::Transform::IDENTITY,
                        smooth: true,
                    },
                    material: 2,
                },
            ],
            media: Default::default(),
            ambient: Vec3A::ZERO,
            water_medium: None,
        };
        LoadedScene { scene, settings }
    }

    fn spot(falloff: SpotFalloff) -> SpotLight {
        SpotLight {
            position: Vec3A::new(0.0, 2.0, 0.0),
            axis: Vec3A::NEG_Y,
            intensity: Vec3A::ONE,
            cutoff: 0.5,
            beam_width: 0.3,
            falloff,
        }
    }

    fn body(s: &LoadedScene) -> String {
        let mut e = Encoder::new();
        encode_render(&mut e, &s.scene, &s.settings, AccelKind::KdTree, "");
        e.finish()
    }

    fn fp(s: &LoadedScene) -> String {
        fingerprint(&s.scene, &s.settings, AccelKind::KdTree, "")
    }

    /// The encoding is pinned: renaming a field of the scene's types, or
    /// changing their `Debug` form, changes no fingerprint. A change to the
    /// bytes this scene encodes to fails here, and must bump
    /// [`FINGERPRINT_FORMAT`] (checkpoints of the old format are then
    /// refused with a message, never silently mismatched).
    #[test]
    fn the_encoding_of_a_fixed_scene_is_pinned() {
        assert_eq!(FINGERPRINT_FORMAT, 2);
        assert_eq!(
            body(&small()),
            "976e389975b7571f10e2050ce92276c4db32ba522ab6e07ba4675d4cf1b14a78"
        );
        // The header: the format, the crate version, the purpose.
        let s = small();
        assert_ne!(fp(&s), photon_fingerprint(&s.scene, &s.settings, AccelKind::KdTree, ""));
        assert_eq!(fp(&s), fp(&small()));
        assert_eq!(fp(&s).len(), 64);
    }

    /// Names label messages only; mesh files and images count by content.
    #[test]
    fn names_and_paths_do_not_count_content_does() {
        let base = fp(&small());
        let mut s = small();
        s.scene.materials[0].name = "renamed".into();
        s.scene.objects[1].name = "renamed".into();
        s.scene.meshes[0] = Arc::new(crate::geometry::Mesh {
            name: "elsewhere/other.ply".into(),
            ..(*s.scene.meshes[0]).clone()
        });
        assert_eq!(base, fp(&s));
        // One vertex moved by one ulp.
        let mut mesh = (*s.scene.meshes[0]).clone();
        mesh.positions[1].x = f32::from_bits(mesh.positions[1].x.to_bits() + 1);
        s.scene.meshes[0] = Arc::new(mesh);
        assert_ne!(base, fp(&s));
        // The same texels from another file: the same; one texel changed: not.
        let retexture = |data: Vec<[u8; 4]>, name: &str| {
            let mut s = small();
            let texels = crate::texture::image::Texels::Rgba8 {
                data,
                space: crate::texture::ColourSpace::Srgb,
            };
            let image = Arc::new(crate::texture::Image::new(name, 2, 2, texels));
            s.scene.materials[0].textures.as_mut().unwrap().diffuse =
                Some(crate::texture::Texture::Image(crate::texture::ImageTexture::new(image)));
            fp(&s)
        };
        let texels = vec![[10, 20, 30, 255], [40, 50, 60, 255], [70, 80, 90, 255], [1, 2, 3, 255]];
        assert_eq!(base, retexture(texels.clone(), "another/dir/copy.png"));
        let mut changed = texels;
        changed[3][1] = 3;
        assert_ne!(base, retexture(changed, "t.png"));
    }

    /// Every field that changes samples changes the fingerprint, each to a
    /// fingerprint of its own.
    #[test]
    fn every_field_that_changes_samples_changes_the_fingerprint() {
        type Edit = fn(&mut LoadedScene);
        let edits: &[(&str, Edit)] = &[
            ("width", |s| s.settings.width += 1),
            ("height", |s| s.settings.height += 1),
            ("spp", |s| s.settings.spp += 1),
            ("seed", |s| s.settings.seed += 1),
            ("max depth", |s| s.settings.max_depth = Some(6)),
            ("no max depth", |s| s.settings.max_depth = None),
            ("integrator", |s| {
                s.settings.integrator = crate::scene::IntegratorKind::Path
            }),
            ("noise threshold", |s| s.settings.noise_threshold = Some(0.01)),
            ("min spp", |s| s.settings.min_spp += 1),
            ("adaptive goal", |s| {
                s.settings.adaptive_goal = crate::scene::AdaptiveGoal::Image
            }),
            ("sampler", |s| {
                s.settings.sampler = Some(crate::math::SamplerKind::Sobol)
            }),
            ("ambient", |s| s.scene.ambient.y = 0.1),
            ("triangle test", |s| {
                s.settings.triangle_test = crate::geometry::TriangleTest::MollerTrumbore
            }),
            ("sharing", |s| s.settings.sharing = crate::scene::SampleSharing::Split),
            ("photon count", |s| s.settings.photons.count += 1),
            ("photon k", |s| s.settings.photons.k += 1),
            ("photon radius", |s| s.settings.photons.max_radius = Some(0.1)),
            ("cone k", |s| s.settings.photons.cone_k = 1.2),
            ("gather", |s| {
                s.settings.photons.gather = crate::scene::GatherMode::Direct
            }),
            ("caustics", |s| {
                s.settings.photons.caustics = crate::scene::CausticsMode::Map
            }),
            ("progressive", |s| s.settings.photons.progressive = true),
            ("progressive alpha", |s| {
                s.settings.photons.progressive = true;
                s.settings.photons.alpha = 0.5;
            }),
            ("hide emitters", |s| s.settings.hide_emitters = true),
            ("camera position", |s| s.scene.camera.position.z += 1.0e-3),
            ("camera fov", |s| s.scene.camera.fov_deg += 1.0),
            ("fov axis", |s| s.scene.camera.fov_axis = crate::scene::FovAxis::X),
            ("aperture", |s| s.scene.camera.aperture_radius = 0.1),
            ("focus with a lens", |s| {
                s.scene.camera.aperture_radius = 0.1;
                s.scene.camera.focus_distance += 1.0;
            }),
            ("near clip", |s| s.scene.camera.near_clip = 0.5),
            ("orthographic", |s| {
                s.scene.camera.projection = crate::scene::Projection::Orthographic {
                    half_width: 2.0,
                    half_height: 0.0,
                }
            }),
            ("tent filter", |s| {
                s.scene.camera.filter = crate::film::filter::PixelFilter::Tent { radius: 1.0 }
            }),
            ("wide box", |s| {
                s.scene.camera.filter = crate::film::filter::PixelFilter::Box { radius: 1.0 }
            }),
            ("gaussian", |s| {
                s.scene.camera.filter = crate::film::filter::PixelFilter::gaussian(0.5)
            }),
            ("diffuse", |s| s.scene.materials[0].diffuse.x += 1.0e-6),
            ("shading model", |s| {
                s.scene.materials[0].model = crate::scene::ShadingModel::Phong
            }),
            ("shininess", |s| s.scene.materials[0].shininess = 2.0),
            ("emission", |s| s.scene.materials[0].emission = Vec3A::ONE),
            ("one-sided", |s| s.scene.materials[0].one_sided = true),
            ("null", |s| s.scene.materials[0].null = true),
            ("texture factor", |s| {
                if let Some(crate::texture::Texture::Image(i)) =
                    s.scene.materials[0].textures.as_mut().unwrap().diffuse.as_mut()
                {
                    i.factor.y = 0.5;
                }
            }),
            ("texture wrap", |s| {
                if let Some(crate::texture::Texture::Image(i)) =
                    s.scene.materials[0].textures.as_mut().unwrap().diffuse.as_mut()
                {
                    i.wrap[1] = crate::texture::WrapMode::Clamp;
                }
            }),
            ("texture slot", |s| {
                let t = s.scene.materials[0].textures.as_mut().unwrap();
                t.specular = t.diffuse.take();
            }),
            ("normal map", |s| {
                s.scene.materials[0].textures.as_mut().unwrap().normal_map = Some(crate::scene::NormalMap {
                    texture: crate::texture::Texture::Constant(Vec3A::Z),
                    scale: 1.0,
                })
            }),
            ("ior", |s| s.scene.materials[1].dielectric.as_mut().unwrap().ior = 1.33),
            ("glass roughness", |s| {
                s.scene.materials[1].dielectric.as_mut().unwrap().roughness = 0.1
            }),
            ("thin", |s| {
                s.scene.materials[1].dielectric.as_mut().unwrap().thin = true
            }),
            ("fresnel", |s| {
                s.scene.materials[1].dielectric.as_mut().unwrap().fresnel = Some(crate::scene::FresnelModel::Schlick)
            }),
            ("mirror", |s| {
                s.scene.materials[1].mirror = Some(crate::scene::Mirror {
                    reflectivity: 0.5,
                    tint: Vec3A::ONE,
                })
            }),
            ("metal roughness", |s| {
                s.scene.materials[2].conductor.as_mut().unwrap().roughness = 0.3
            }),
            ("metal k", |s| {
                s.scene.materials[2].conductor.as_mut().unwrap().k.z = 2.0
            }),
            ("anisotropy", |s| s.scene.materials[2].roughness_v = Some(0.05)),
            ("beckmann", |s| {
                s.scene.materials[2].microfacet = crate::scene::MicrofacetDistribution::Beckmann
            }),
            ("coating", |s| {
                s.scene.materials[0].coating = Some(crate::scene::Coating::smooth(1.5))
            }),
            ("rough coating", |s| {
                let mut c = crate::scene::Coating::smooth(1.5);
                c.roughness = 0.2;
                s.scene.materials[0].coating = Some(c);
            }),
            ("principled", |s| {
                s.scene.materials[2].principled = Some(Default::default())
            }),
            ("principled clearcoat", |s| {
                s.scene.materials[2].principled = Some(crate::scene::Principled {
                    clearcoat: 0.5,
                    ..Default::default()
                })
            }),
            ("disney", |s| s.scene.materials[2].disney = Some(Default::default())),
            ("disney sheen", |s| {
                s.scene.materials[2].disney = Some(crate::scene::Disney {
                    sheen: 0.5,
                    ..Default::default()
                })
            }),
            ("disney sampling rate", |s| {
                s.scene.materials[2].disney = Some(crate::scene::Disney {
                    clearcoat_sampling_rate: 0.5,
                    ..Default::default()
                })
            }),
            ("blend", |s| {
                s.scene.materials[2].blend = Some(Box::new(crate::scene::Blend {
                    weight: 0.5,
                    weight_texture: None,
                    first: Some(Material::diffuse("a", Vec3A::ONE)),
                    second: None,
                }))
            }),
            ("blend weight", |s| {
                s.scene.materials[2].blend = Some(Box::new(crate::scene::Blend {
                    weight: 0.25,
                    weight_texture: None,
                    first: Some(Material::diffuse("a", Vec3A::ONE)),
                    second: None,
                }))
            }),
            ("blend holes swapped", |s| {
                s.scene.materials[2].blend = Some(Box::new(crate::scene::Blend {
                    weight: 0.5,
                    weight_texture: None,
                    first: None,
                    second: Some(Material::diffuse("a", Vec3A::ONE)),
                }))
            }),
            ("cutout", |s| {
                s.scene.materials[0].textures.as_mut().unwrap().alpha = Some(crate::scene::AlphaMask {
                    texture: crate::texture::Texture::Constant(Vec3A::splat(0.5)),
                    cutoff: 0.5,
                })
            }),
            ("point power", |s| {
                if let Light::Point { intensity, .. } = &mut s.scene.lights[0] {
                    intensity.x *= 2.0;
                }
            }),
            ("area samples", |s| {
                if let Light::Area(a) = &mut s.scene.lights[1] {
                    a.samples += 1;
                }
            }),
            ("environment", |s| {
                s.scene.lights.push(Light::Environment {
                    radiance: Vec3A::splat(0.5),
                    map: None,
                })
            }),
            ("light order", |s| s.scene.lights.swap(0, 1)),
            ("spot", |s| s.scene.lights.push(Light::Spot(spot(SpotFalloff::Mitsuba)))),
            ("gltf spot", |s| {
                s.scene.lights.push(Light::Spot(spot(SpotFalloff::Gltf)))
            }),
            ("sphere radius", |s| {
                if let Shape::Sphere(b) = &mut s.scene.objects[1].shape {
                    b.radius = 0.6;
                }
            }),
            ("object material", |s| s.scene.objects[1].material = 0),
            ("flat mesh", |s| {
                if let Shape::Mesh { smooth, .. } = &mut s.scene.objects[2].shape {
                    *smooth = false;
                }
            }),
            ("mesh transform", |s| {
                if let Shape::Mesh { transform, .. } = &mut s.scene.objects[2].shape {
                    *transform = crate::math::Transform::from_srt(Vec3::ONE, Vec3::ZERO, Vec3::X).unwrap();
                }
            }),
            ("mesh uvs", |s| {
                let mut m = (*s.scene.meshes[0]).clone();
                m.uvs = vec![crate::math::Vec2::ZERO; 3];
                s.scene.meshes[0] = Arc::new(m);
            }),
            ("mesh normals", |s| {
                let mut m = (*s.scene.meshes[0]).clone();
                m.normals[0] = Vec3::Y;
                s.scene.meshes[0] = Arc::new(m);
            }),
            ("mesh winding", |s| {
                let mut m = (*s.scene.meshes[0]).clone();
                m.triangles[0] = [0, 2, 1];
                s.scene.meshes[0] = Arc::new(m);
            }),
            ("medium", |s| {
                s.scene.media.list.push(crate::scene::HomogeneousMedium {
                    name: "fog".into(),
                    sigma_t: Vec3A::splat(0.1),
                    albedo: Vec3A::splat(0.9),
                    phase: crate::scene::PhaseFunction::Isotropic,
                    sample_emitters: true,
                });
                s.scene.media.camera = Some(0);
            }),
            ("pass through", |s| {
                s.scene.media.pass_through = crate::scene::PassThrough::Volumetric
            }),
        ];
        let base = fp(&small());
        let mut seen = std::collections::HashMap::new();
        seen.insert(base.clone(), "the scene itself");
        for (name, edit) in edits {
            let mut s = small();
            edit(&mut s);
            let f = fp(&s);
            if let Some(other) = seen.insert(f, name) {
                panic!("{name}: the same fingerprint as {other}");
            }
        }
        assert_ne!(base, {
            let s = small();
            fingerprint(&s.scene, &s.settings, AccelKind::Brute, "")
        });
        assert_ne!(base, {
            let s = small();
            fingerprint(&s.scene, &s.settings, AccelKind::KdTree, "robust")
        });
    }

    /// Display-only settings, and values the render does not read, change
    /// nothing.
    #[test]
    fn display_settings_do_not_change_the_fingerprint() {
        let base = fp(&small());
        let mut s = small();
        s.settings.output.exposure = 2.0;
        s.settings.output.tone_map = crate::film::ToneMap::Clamp;
        s.settings.denoise = true;
        s.settings.denoise_quality = crate::film::denoise::DenoiseQuality::Fast;
        assert_eq!(base, fp(&s));
        // α without progressive photon mapping, a pinhole's focus distance,
        // the sampler the integrator uses anyway.
        let mut s = small();
        s.settings.photons.alpha = 0.5;
        s.scene.camera.focus_distance += 1.0;
        s.settings.sampler = Some(crate::math::SamplerKind::Independent);
        assert_eq!(base, fp(&s));
        // The photons do not depend on the image size or samples per pixel.
        let photons = {
            let s = small();
            photon_fingerprint(&s.scene, &s.settings, AccelKind::KdTree, "")
        };
        let mut s = small();
        s.settings.width += 1;
        s.settings.spp += 1;
        assert_eq!(
            photons,
            photon_fingerprint(&s.scene, &s.settings, AccelKind::KdTree, "")
        );
        s.settings.seed += 1;
        assert_ne!(
            photons,
            photon_fingerprint(&s.scene, &s.settings, AccelKind::KdTree, "")
        );
    }

    #[test]
    fn another_format_is_refused_with_its_reason() {
        assert_eq!(format_refusal(FINGERPRINT_FORMAT), None);
        let old = format_refusal(1).unwrap();
        assert!(
            old.contains("an older caustic") && old.contains("fingerprint format 1"),
            "{old}"
        );
        assert!(old.contains(&format!("format {FINGERPRINT_FORMAT}")), "{old}");
        assert!(format_refusal(FINGERPRINT_FORMAT + 1)
            .unwrap()
            .contains("a newer caustic"));
    }
}
