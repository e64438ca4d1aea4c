//! The fingerprint of a render: everything that changes its samples, so
//! that a checkpoint is only ever resumed by the same render.
//!
//! What a resume relies on: the film is a pure function of (scene, settings,
//! accelerator, seed) per pixel and sample index (see `integrator::render`),
//! and the photon pass is deterministic for any thread count, so it is
//! simply re-run on resume rather than stored (a 10M-photon map would weigh
//! hundreds of MiB; re-tracing it costs seconds).

use crate::accel::AccelKind;
use crate::film::CheckpointMeta;
use crate::scene::{RenderSettings, Scene};
use sha2::{Digest, Sha256};

/// Hex SHA-256 of everything that decides the samples: the scene (camera,
/// materials, lights, objects, mesh geometry), the render settings except
/// the display-only tone map and exposure, the accelerator and its options
/// (`accel_options`: e.g. Embree's build quality; hits can differ in the
/// last bits between backends), the checkpoint layout and the crate
/// version. Thread count and the shard a process renders are not included:
/// they never change a sample, and every shard of a render shares its
/// fingerprint.
pub fn fingerprint(scene: &Scene, accel: AccelKind, accel_options: &str) -> String {
    fingerprint_of(scene, &scene.settings, None, accel, accel_options)
}

/// Hex SHA-256 of everything the traced photons depend on
/// (`caustic photons`, `--photon-map`): [`fingerprint`]'s fields with the
/// image size, samples per pixel, sampler and adaptive sampling left out
/// (the trace never reads them; the map's precompute, which depends on the
/// image size, runs when a render loads the photons), and a purpose field
/// so that it never equals a render's fingerprint.
pub fn photon_fingerprint(scene: &Scene, accel: AccelKind, accel_options: &str) -> String {
    let defaults = RenderSettings::default();
    let settings = RenderSettings {
        width: defaults.width,
        height: defaults.height,
        spp: defaults.spp,
        noise_threshold: None,
        min_spp: defaults.min_spp,
        adaptive_goal: defaults.adaptive_goal,
        sampler: None,
        ..scene.settings.clone()
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
    let mut h = Sha256::new();
    let mut field = |name: &str, bytes: &[u8]| {
        // Length-prefixed so that no two field sequences hash alike.
        h.update((name.len() as u64).to_le_bytes());
        h.update(name.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(bytes);
    };
    // The per-pixel layout the samples are kept in; format 3 only added
    // header attributes and format 4 the AOV sums (the image's samples are
    // unchanged), so their fingerprints equal format 2's (whose checkpoints
    // still resume).
    field("format", crate::film::checkpoint::CHECKPOINT_FORMAT_2.as_bytes());
    field("version", env!("CARGO_PKG_VERSION").as_bytes());
    if let Some(purpose) = purpose {
        field("purpose", purpose.as_bytes());
    }
    // Debug output of f32 is the shortest text that round-trips, so it
    // identifies values exactly.
    let settings = RenderSettings {
        output: crate::film::OutputSettings::default(),
        denoise: false,
        denoise_quality: Default::default(),
        ..settings.clone()
    };
    // Denoising changes no sample: its fields (the last two) are left out
    // of the text, which stays that of the settings before they existed
    // (older checkpoints still resume).
    let text = format!("{settings:?}");
    let text = match text.strip_suffix(", denoise: false, denoise_quality: High }") {
        Some(head) => format!("{head} }}"),
        None => text,
    };
    // Progressive photon mapping's keys are left out of the text too (the
    // text of a render without them stays the one before they existed) and
    // hashed as a field of their own, only when it is on: a checkpoint of a
    // non-progressive render never resumes a progressive one, nor one of
    // another α. `alpha` changes nothing without `progressive`.
    let p = &settings.photons;
    let ppm_keys = format!(", progressive: {:?}, alpha: {:?}", p.progressive, p.alpha);
    let text = text.replacen(&ppm_keys, "", 1);
    // Hiding emitters likewise, hashed on its own only when on.
    let text = text.replacen(&format!(", hide_emitters: {:?}", settings.hide_emitters), "", 1);
    field("settings", text.as_bytes());
    if settings.hide_emitters {
        field("hide emitters", b"on");
    }
    if p.progressive {
        field("progressive photons", format!("alpha {:?}", p.alpha).as_bytes());
    }
    field(
        "camera",
        format!("{:?}", encoding::Camera::of(&scene.camera)).as_bytes(),
    );
    let c = &scene.camera;
    // The camera's later keys, only when they change the rays (a pinhole
    // with a vertical field of view keeps its fingerprint).
    if c.fov_axis != crate::scene::FovAxis::Y || c.has_lens() || c.near_clip > 0.0 {
        let lens = if c.has_lens() {
            format!(" aperture {:?} focus {:?}", c.aperture_radius, c.focus_distance)
        } else {
            String::new()
        };
        let text = format!("fov axis {}{lens} near {:?}", c.fov_axis.name(), c.near_clip);
        field("camera lens", text.as_bytes());
    }
    if let crate::scene::Projection::Orthographic {
        half_width,
        half_height,
    } = c.projection
    {
        let text = format!("orthographic half extents {half_width:?} {half_height:?}");
        field("camera projection", text.as_bytes());
    }
    // The pixel filter, only when it moves samples (the one-pixel box keeps
    // the fingerprint of renders before filters existed).
    if !c.filter.is_pixel_box() {
        let text = match &c.filter {
            crate::film::filter::PixelFilter::Gaussian { stddev, .. } => format!("gaussian stddev {stddev:?}"),
            f => format!("{} radius {:?}", f.name(), f.radius()),
        };
        field("pixel filter", text.as_bytes());
    }
    let materials: Vec<encoding::Material> = scene.materials.iter().map(encoding::Material::of).collect();
    field("materials", format!("{materials:?}").as_bytes());
    // What a material's kind adds to the fields above, only where it differs
    // from the defaults (the fingerprint of a scene that uses none of it is
    // the one before these existed).
    for (i, m) in scene.materials.iter().enumerate() {
        let text = kind_text(m);
        if !text.is_empty() {
            field("material kind", format!("material {i}:{text}").as_bytes());
        }
    }
    // Emission, only for the materials that emit (the fingerprint of a
    // scene without emitting materials is the one before they existed).
    for (i, m) in scene.materials.iter().enumerate() {
        if m.emission != crate::math::Vec3A::ZERO {
            field(
                "material emission",
                format!("material {i}: {:?}", m.emission.to_array()).as_bytes(),
            );
        }
    }
    // Textures by content, only for the materials that have them (the
    // fingerprint of an untextured scene is the one before textures existed).
    for (i, m) in scene.materials.iter().enumerate() {
        if let Some(t) = m.textures.as_deref().filter(|t| t.all().next().is_some()) {
            let mut text = format!("material {i}:");
            for (name, texture) in t.all() {
                text += &format!(" {name} {}", encoding::texture(texture));
            }
            if let Some(n) = &t.normal_map {
                text += &format!(" normal scale {:?}", n.scale);
            }
            if let Some(b) = &t.bump_map {
                text += &format!(" bump scale {:?}", b.scale);
            }
            if let Some(a) = &t.alpha {
                text += &format!(" alpha cutoff {:?}", a.cutoff);
            }
            field("material textures", text.as_bytes());
        }
    }
    let lights: Vec<encoding::Light> = scene.lights.iter().map(encoding::Light::of).collect();
    field("lights", format!("{lights:?}").as_bytes());
    // Environment images by content, only where there are some.
    for (i, light) in scene.lights.iter().enumerate() {
        if let crate::scene::Light::Environment { map: Some(m), .. } = light {
            let hash: String = m.image.hash.iter().map(|b| format!("{b:02x}")).collect();
            let text = format!("light {i}: image {hash} to world {:?}", m.to_world.to_cols_array());
            field("environment map", text.as_bytes());
        }
    }
    field("objects", encoding::objects(&scene.objects).as_bytes());
    // Null surfaces and media, only where there are some (the fingerprint
    // of a scene in vacuum is the one before media existed).
    for (i, m) in scene.materials.iter().enumerate() {
        if m.null {
            field("material null", format!("material {i}").as_bytes());
        }
    }
    if scene.media != crate::scene::Media::default() {
        field("media", format!("{:?}", scene.media).as_bytes());
    }
    for mesh in &scene.meshes {
        // Geometry only: moving or renaming the mesh file does not matter.
        let floats = mesh.positions.iter().chain(&mesh.normals).flat_map(|v| v.to_array());
        let bytes: Vec<u8> = floats.flat_map(f32::to_le_bytes).collect();
        field("mesh vertices", &bytes);
        let bytes: Vec<u8> = mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        field("mesh triangles", &bytes);
        if !mesh.uvs.is_empty() {
            let bytes: Vec<u8> = mesh
                .uvs
                .iter()
                .flat_map(|v| v.to_array())
                .flat_map(f32::to_le_bytes)
                .collect();
            field("mesh uvs", &bytes);
        }
        if !mesh.tangents.is_empty() {
            let bytes: Vec<u8> = mesh
                .tangents
                .iter()
                .flat_map(|v| v.to_array())
                .flat_map(f32::to_le_bytes)
                .collect();
            field("mesh tangents", &bytes);
        }
    }
    field("accel", format!("{accel:?} {accel_options}").as_bytes());
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

/// A material's fields beyond [`encoding::Material`]'s, as text: empty
/// for a material that uses none of them; a blend spells its sides whole.
fn kind_text(m: &crate::scene::Material) -> String {
    let mut text = String::new();
    if m.one_sided {
        text += " one-sided";
    }
    if m.microfacet != crate::scene::MicrofacetDistribution::Ggx {
        text += &format!(" microfacet {}", m.microfacet.name());
    }
    if m.dielectric.is_some_and(|d| d.thin) {
        text += " thin";
    }
    if let Some(v) = m.roughness_v {
        text += &format!(" roughness_v {v:?}");
    }
    if let Some(c) = m.coating.as_ref().filter(|c| c.roughness > 0.0 || c.nonlinear) {
        text += &format!(" coating roughness {:?} nonlinear {}", c.roughness, c.nonlinear);
    }
    if let Some(p) = m.principled {
        text += &format!(
            " principled metallic {:?} roughness {:?} ior {:?} transmission {:?} thin {} clearcoat {:?} \
             clearcoat_roughness {:?}",
            p.metallic, p.roughness, p.ior, p.transmission, p.thin, p.clearcoat, p.clearcoat_roughness
        );
    }
    if let Some(d) = m.disney {
        // Every field: the Debug form names them all.
        text += &format!(" disney {d:?}");
    }
    if let Some(b) = m.blend.as_deref() {
        let side = |s: &Option<crate::scene::Material>| match s {
            None => "hole".to_string(),
            Some(s) => {
                let textures: String = s
                    .textures
                    .iter()
                    .flat_map(|t| t.all())
                    .map(|(name, t)| format!(" {name} {}", encoding::texture(t)))
                    .collect();
                format!("{{{:?}{}{textures}}}", encoding::Material::of(s), kind_text(s))
            }
        };
        text += &format!(
            " blend weight {:?} texture {} first {} second {}",
            b.weight,
            b.weight_texture.as_ref().map_or("none".into(), encoding::texture),
            side(&b.first),
            side(&b.second)
        );
    }
    text
}

/// The fingerprint's own spelling of the materials: structs whose derived
/// `Debug` text is the encoding, declared here so that renaming a field of
/// the scene's types changes no fingerprint (a test pins the text).
// The fields are read through the derived `Debug` only.
#[allow(dead_code)]
mod encoding {
    use crate::math::Vec3A;
    use crate::scene;
    use crate::texture::Texture;

    #[derive(Debug)]
    pub(super) struct Material {
        name: String,
        model: Model,
        ambient: Vec3A,
        diffuse: Vec3A,
        specular: Vec3A,
        shininess: f32,
        mirror: Option<Mirror>,
        dielectric: Option<Dielectric>,
        conductor: Option<Conductor>,
        coating: Option<Coating>,
    }

    /// The objects' text: the derived `Debug` of the scene's objects as it
    /// was before disks and cylinders existed (the fingerprints of scenes
    /// without them are unchanged), a disk or a cylinder in the
    /// fingerprint's own spelling below.
    pub(super) fn objects(objects: &[scene::Object]) -> String {
        let texts: Vec<String> = objects
            .iter()
            .map(|o| {
                let shape = match &o.shape {
                    scene::Shape::Disk(d) => format!("{:?}", Disk::of(d)),
                    scene::Shape::Cylinder(c) => format!("{:?}", Cylinder::of(c)),
                    _ => return format!("{o:?}"),
                };
                format!(
                    "Object {{ name: {:?}, shape: {shape}, material: {} }}",
                    o.name, o.material
                )
            })
            .collect();
        format!("[{}]", texts.join(", "))
    }

    #[derive(Debug)]
    pub(super) struct Disk {
        center: Vec3A,
        a: Vec3A,
        b: Vec3A,
        normal: Vec3A,
    }

    impl Disk {
        pub(super) fn of(d: &scene::Disk) -> Self {
            Self {
                center: d.center,
                a: d.a,
                b: d.b,
                normal: d.normal,
            }
        }
    }

    #[derive(Debug)]
    pub(super) struct Cylinder {
        base: Vec3A,
        s: Vec3A,
        t: Vec3A,
        axis: Vec3A,
        radius: f32,
        length: f32,
        inward: bool,
    }

    impl Cylinder {
        pub(super) fn of(c: &scene::Cylinder) -> Self {
            Self {
                base: c.base,
                s: c.s,
                t: c.t,
                axis: c.axis,
                radius: c.radius,
                length: c.length,
                inward: c.inward,
            }
        }
    }

    #[derive(Debug)]
    pub(super) struct Camera {
        position: Vec3A,
        forward: Vec3A,
        right: Vec3A,
        up: Vec3A,
        vfov_deg: f32,
    }

    impl Camera {
        pub(super) fn of(c: &scene::Camera) -> Self {
            Self {
                position: c.position,
                forward: c.forward,
                right: c.right,
                up: c.up,
                vfov_deg: c.fov_deg,
            }
        }
    }

    #[derive(Debug)]
    pub(super) enum Light {
        Point {
            position: Vec3A,
            intensity: Vec3A,
        },
        Area(AreaLight),
        Environment {
            radiance: Vec3A,
        },
        Spot {
            position: Vec3A,
            axis: Vec3A,
            intensity: Vec3A,
            cutoff: f32,
            beam_width: f32,
        },
        /// A spot with glTF's falloff (a variant of its own, so that
        /// Mitsuba's spots keep their fingerprints).
        GltfSpot {
            position: Vec3A,
            axis: Vec3A,
            intensity: Vec3A,
            cutoff: f32,
            beam_width: f32,
        },
        Directional {
            direction: Vec3A,
            irradiance: Vec3A,
        },
    }

    #[derive(Debug)]
    pub(super) struct AreaLight {
        center: Vec3A,
        u: Vec3A,
        v: Vec3A,
        normal: Vec3A,
        radiance: Vec3A,
        samples: u32,
    }

    impl Light {
        pub(super) fn of(l: &scene::Light) -> Self {
            match l {
                scene::Light::Point { position, intensity } => Light::Point {
                    position: *position,
                    intensity: *intensity,
                },
                scene::Light::Area(a) => Light::Area(AreaLight {
                    center: a.center,
                    u: a.u,
                    v: a.v,
                    normal: a.normal,
                    radiance: a.radiance,
                    samples: a.samples,
                }),
                scene::Light::Environment { radiance, .. } => Light::Environment { radiance: *radiance },
                scene::Light::Spot(s) if s.falloff == crate::scene::light::SpotFalloff::Gltf => Light::GltfSpot {
                    position: s.position,
                    axis: s.axis,
                    intensity: s.intensity,
                    cutoff: s.cutoff,
                    beam_width: s.beam_width,
                },
                scene::Light::Spot(s) => Light::Spot {
                    position: s.position,
                    axis: s.axis,
                    intensity: s.intensity,
                    cutoff: s.cutoff,
                    beam_width: s.beam_width,
                },
                scene::Light::Directional { direction, irradiance } => Light::Directional {
                    direction: *direction,
                    irradiance: *irradiance,
                },
            }
        }
    }

    #[derive(Debug)]
    enum Model {
        Phong,
        BlinnPhong,
    }

    #[derive(Debug)]
    struct Mirror {
        reflectivity: f32,
        tint: Vec3A,
    }

    #[derive(Debug)]
    struct Dielectric {
        ior: f32,
        tint: Vec3A,
        roughness: f32,
        fresnel: Option<Fresnel>,
    }

    #[derive(Debug)]
    enum Fresnel {
        Exact,
        Schlick,
    }

    #[derive(Debug)]
    struct Conductor {
        eta: Vec3A,
        k: Vec3A,
        roughness: f32,
    }

    #[derive(Debug)]
    struct Coating {
        ior: f32,
    }

    impl Material {
        pub(super) fn of(m: &scene::Material) -> Self {
            Self {
                name: m.name.clone(),
                model: match m.model {
                    scene::ShadingModel::Phong => Model::Phong,
                    scene::ShadingModel::BlinnPhong => Model::BlinnPhong,
                },
                ambient: m.ambient,
                diffuse: m.diffuse,
                specular: m.specular,
                shininess: m.shininess,
                mirror: m.mirror.map(|x| Mirror {
                    reflectivity: x.reflectivity,
                    tint: x.tint,
                }),
                dielectric: m.dielectric.map(|d| Dielectric {
                    ior: d.ior,
                    tint: d.tint,
                    roughness: d.roughness,
                    fresnel: d.fresnel.map(|f| match f {
                        scene::FresnelModel::Exact => Fresnel::Exact,
                        scene::FresnelModel::Schlick => Fresnel::Schlick,
                    }),
                }),
                conductor: m.conductor.map(|c| Conductor {
                    eta: c.eta,
                    k: c.k,
                    roughness: c.roughness,
                }),
                coating: m.coating.as_ref().map(|c| Coating { ior: c.ior }),
            }
        }
    }

    /// A texture by what it computes: an image by its texels' hash, never
    /// by its path.
    pub(super) fn texture(t: &Texture) -> String {
        match t {
            Texture::Constant(c) => format!("constant {:?}", c.to_array()),
            Texture::Checkerboard(c) => format!(
                "checkerboard {:?} {:?} uv {:?}",
                c.colour0.to_array(),
                c.colour1.to_array(),
                c.transform.0.to_cols_array()
            ),
            Texture::Image(i) => format!(
                "image {} uv {:?} wrap {} {} filter {} factor {:?} alpha {:?} channel {}",
                i.image.hash.iter().map(|b| format!("{b:02x}")).collect::<String>(),
                i.transform.0.to_cols_array(),
                i.wrap[0].name(),
                i.wrap[1].name(),
                i.filter.name(),
                i.factor.to_array(),
                i.alpha_factor,
                i.channel.name()
            ),
        }
    }
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

    /// The materials' encoding is pinned: a renamed field of the scene's
    /// types must not change any fingerprint (checkpoints would stop resuming).
    #[test]
    fn material_encoding_is_stable() {
        let m = crate::scene::Material {
            mirror: Some(crate::scene::Mirror {
                reflectivity: 0.5,
                tint: crate::math::Vec3A::ONE,
            }),
            ..crate::scene::Material::diffuse("m", crate::math::Vec3A::splat(0.25))
        };
        assert_eq!(
            format!("{:?}", encoding::Material::of(&m)),
            "Material { name: \"m\", model: BlinnPhong, ambient: Vec3A(0.25, 0.25, 0.25), \
             diffuse: Vec3A(0.25, 0.25, 0.25), specular: Vec3A(0.0, 0.0, 0.0), shininess: 1.0, \
             mirror: Some(Mirror { reflectivity: 0.5, tint: Vec3A(1.0, 1.0, 1.0) }), dielectric: None, \
             conductor: None, coating: None }"
        );
        let g = crate::scene::Material {
            dielectric: Some(crate::scene::Dielectric::smooth(1.5, crate::math::Vec3A::ONE)),
            conductor: Some(crate::scene::Conductor {
                eta: crate::math::Vec3A::ONE,
                k: crate::math::Vec3A::ZERO,
                roughness: 0.1,
            }),
            coating: Some(crate::scene::Coating::smooth(1.4)),
            ..crate::scene::Material::diffuse("g", crate::math::Vec3A::ZERO)
        };
        let text = format!("{:?}", encoding::Material::of(&g));
        let lights = [
            crate::scene::Light::Point {
                position: crate::math::Vec3A::ONE,
                intensity: crate::math::Vec3A::splat(2.0),
            },
            crate::scene::Light::Environment {
                radiance: crate::math::Vec3A::splat(0.5),
                map: None,
            },
        ];
        let lights: Vec<encoding::Light> = lights.iter().map(encoding::Light::of).collect();
        assert_eq!(
            format!("{lights:?}"),
            "[Point { position: Vec3A(1.0, 1.0, 1.0), intensity: Vec3A(2.0, 2.0, 2.0) }, \
             Environment { radiance: Vec3A(0.5, 0.5, 0.5) }]"
        );
        assert!(
            text.ends_with(
                "dielectric: Some(Dielectric { ior: 1.5, tint: Vec3A(1.0, 1.0, 1.0), roughness: 0.0, fresnel: None }), \
                 conductor: Some(Conductor { eta: Vec3A(1.0, 1.0, 1.0), k: Vec3A(0.0, 0.0, 0.0), roughness: 0.1 }), \
                 coating: Some(Coating { ior: 1.4 }) }"
            ),
            "{text}"
        );
    }

    /// The objects' text is the derived `Debug` of the objects for the
    /// shapes that existed before disks and cylinders (the fingerprints of
    /// those scenes are unchanged), and pinned for disks and cylinders.
    #[test]
    fn object_encoding_is_stable() {
        use crate::math::Vec3A;
        use crate::scene::{Cylinder, Disk, Object, Shape};
        let s = scene();
        assert_eq!(encoding::objects(&s.objects), format!("{:?}", s.objects));
        let objects = [
            Object {
                name: "d".into(),
                shape: Shape::Disk(Disk::new(Vec3A::Z, Vec3A::X, Vec3A::Y * 2.0, true).unwrap()),
                material: 1,
            },
            Object {
                name: "c".into(),
                shape: Shape::Cylinder(
                    Cylinder::new(Vec3A::ZERO, [Vec3A::X, Vec3A::Y, Vec3A::Z], 0.5, 2.0, false).unwrap(),
                ),
                material: 0,
            },
        ];
        assert_eq!(
            encoding::objects(&objects),
            "[Object { name: \"d\", shape: Disk { center: Vec3A(0.0, 0.0, 1.0), a: Vec3A(1.0, 0.0, 0.0), \
             b: Vec3A(0.0, 2.0, 0.0), normal: Vec3A(-0.0, -0.0, -1.0) }, material: 1 }, \
             Object { name: \"c\", shape: Cylinder { base: Vec3A(0.0, 0.0, 0.0), s: Vec3A(1.0, 0.0, 0.0), \
             t: Vec3A(0.0, 1.0, 0.0), axis: Vec3A(0.0, 0.0, 1.0), radius: 0.5, length: 2.0, inward: false }, \
             material: 0 }]"
        );
    }

    fn scene() -> Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/test/shadow.toml");
        crate::scene::load_scene(&path).unwrap()
    }

    #[test]
    fn fingerprint_sees_media_and_pass_through_surfaces() {
        let base = fingerprint(&scene(), AccelKind::KdTree, "");
        let mut s = scene();
        s.materials[0].null = true;
        let null = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, null);
        s.materials[0].null = false;
        s.materials[0].dielectric = Some(crate::scene::Dielectric {
            thin: true,
            ..crate::scene::Dielectric::smooth(1.5, crate::math::Vec3A::ONE)
        });
        let thin = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, thin);
        assert_ne!(null, thin);
        s.materials[0].dielectric = None;
        s.materials[0].principled = Some(crate::scene::Principled::default());
        let principled = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, principled);
        s.materials[0].principled.as_mut().unwrap().clearcoat = 0.5;
        assert_ne!(principled, fingerprint(&s, AccelKind::KdTree, ""));
        s.materials[0].disney = Some(crate::scene::Disney::default());
        let disney = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(principled, disney);
        s.materials[0].disney.as_mut().unwrap().sheen = 0.5;
        assert_ne!(disney, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.media.list.push(crate::scene::HomogeneousMedium {
            name: "fog".into(),
            sigma_t: crate::math::Vec3A::splat(0.1),
            albedo: crate::math::Vec3A::splat(0.9),
            phase: crate::scene::PhaseFunction::Isotropic,
            sample_emitters: true,
        });
        // How null surfaces are crossed (a `volpath` scene may have no medium).
        let mut p = scene();
        p.media.pass_through = crate::scene::PassThrough::Volumetric;
        assert_ne!(base, fingerprint(&p, AccelKind::KdTree, ""));
        s.media.camera = Some(0);
        let fog = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, fog);
        s.media.list[0].albedo.y = 0.8;
        assert_ne!(fog, fingerprint(&s, AccelKind::KdTree, ""));
    }

    #[test]
    fn fingerprint_sees_what_changes_samples_only() {
        let base = fingerprint(&scene(), AccelKind::KdTree, "");
        assert_eq!(base.len(), 64);
        assert_eq!(base, fingerprint(&scene(), AccelKind::KdTree, ""));
        // Display-only settings do not matter.
        let mut s = scene();
        s.settings.output.exposure = 2.0;
        s.settings.output.tone_map = crate::film::ToneMap::Clamp;
        s.settings.denoise = true;
        s.settings.denoise_quality = crate::film::denoise::DenoiseQuality::Fast;
        assert_eq!(base, fingerprint(&s, AccelKind::KdTree, ""));
        // The denoise fields are the settings' last, which the hashed text
        // leaves out (the text of the settings before they existed).
        let text = format!("{:?}", RenderSettings::default());
        assert!(text.ends_with(", denoise: false, denoise_quality: High }"), "{text}");
        // Everything else does.
        let mut s = scene();
        s.settings.seed += 1;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.settings.spp += 1;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.materials[0].diffuse.x += 1.0e-6;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        assert_ne!(base, fingerprint(&scene(), AccelKind::Brute, ""));
        assert_ne!(base, fingerprint(&scene(), AccelKind::KdTree, "robust"));
        // Progressive photon mapping: on changes it, α only when on.
        let mut s = scene();
        s.settings.photons.alpha = 0.5;
        assert_eq!(base, fingerprint(&s, AccelKind::KdTree, ""));
        s.settings.photons.progressive = true;
        let progressive = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, progressive);
        s.settings.photons.alpha = 0.6;
        assert_ne!(progressive, fingerprint(&s, AccelKind::KdTree, ""));
        // The camera's axis, lens and near plane.
        let mut s = scene();
        s.camera.fov_axis = crate::scene::FovAxis::X;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.camera.aperture_radius = 0.1;
        let lens = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, lens);
        s.camera.focus_distance += 1.0;
        assert_ne!(lens, fingerprint(&s, AccelKind::KdTree, ""));
        let mut s = scene();
        s.camera.near_clip = 0.5;
        assert_ne!(base, fingerprint(&s, AccelKind::KdTree, ""));
        // The projection and its scale.
        let mut s = scene();
        s.camera.projection = crate::scene::Projection::Orthographic {
            half_width: 2.0,
            half_height: 0.0,
        };
        let ortho = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, ortho);
        s.camera.projection = crate::scene::Projection::Orthographic {
            half_width: 2.0,
            half_height: 3.0,
        };
        assert_ne!(ortho, fingerprint(&s, AccelKind::KdTree, ""));
        // The pixel filter: kind and width.
        use crate::film::filter::PixelFilter;
        let with_filter = |f: PixelFilter| {
            let mut s = scene();
            s.camera.filter = f;
            fingerprint(&s, AccelKind::KdTree, "")
        };
        assert_eq!(base, with_filter(PixelFilter::Box { radius: 0.5 }));
        let wide_box = with_filter(PixelFilter::Box { radius: 1.0 });
        let tent = with_filter(PixelFilter::Tent { radius: 1.0 });
        let gaussian = with_filter(PixelFilter::gaussian(0.5));
        for f in [&wide_box, &tent, &gaussian] {
            assert_ne!(&base, f);
        }
        assert_ne!(wide_box, tent);
        assert_ne!(gaussian, with_filter(PixelFilter::gaussian(0.6)));
        // A pinhole's focus distance changes no ray.
        let mut s = scene();
        s.camera.focus_distance += 1.0;
        assert_eq!(base, fingerprint(&s, AccelKind::KdTree, ""));
        // Textures change it by content, not by path.
        let mut s = scene();
        let image = |v: u8, name: &str| {
            let texels = crate::texture::image::Texels::Rgba8 {
                data: vec![[v, v, v, 255]; 4],
                space: crate::texture::ColourSpace::Srgb,
            };
            std::sync::Arc::new(crate::texture::Image::new(name, 2, 2, texels))
        };
        let textured = |img| crate::texture::Texture::Image(crate::texture::ImageTexture::new(img));
        s.materials[0].textures = Some(Box::new(crate::scene::MaterialTextures {
            diffuse: Some(textured(image(9, "a.png"))),
            ..Default::default()
        }));
        let with_texture = fingerprint(&s, AccelKind::KdTree, "");
        assert_ne!(base, with_texture);
        s.materials[0].textures = Some(Box::new(crate::scene::MaterialTextures {
            diffuse: Some(textured(image(9, "elsewhere/b.png"))),
            ..Default::default()
        }));
        assert_eq!(with_texture, fingerprint(&s, AccelKind::KdTree, ""));
        s.materials[0].textures = Some(Box::new(crate::scene::MaterialTextures {
            diffuse: Some(textured(image(10, "a.png"))),
            ..Default::default()
        }));
        assert_ne!(with_texture, fingerprint(&s, AccelKind::KdTree, ""));
        // The keys the text leaves out are found in it.
        let text = format!("{:?}", RenderSettings::default());
        assert!(text.contains(", progressive: false, alpha: 0.6666667 }"), "{text}");
    }
}
