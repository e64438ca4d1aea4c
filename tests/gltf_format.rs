//! glTF 2.0 models read into the scene model: transforms composed against
//! matrices built by hand, instancing, interleaved and normalized
//! accessors, cameras, punctual lights and their units, materials and
//! their extensions, MikkTSpace tangents; and renders of an emissive quad
//! and a textured quad through the command line. The models are
//! `tests/data/gltf/` (written by `scripts/make-gltf-test-data.py`).

mod common;

use caustic::math::{Vec2, Vec3A};
use caustic::scene::gltf::{load_gltf_scene, CameraChoice, GltfOptions, GltfScene};
use caustic::scene::light::SpotFalloff;
use caustic::scene::{Light, Projection, Shape};
use caustic::texture::{Channel, FilterMode, Texture, WrapMode};
use common::cli::{caustic, describe};
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/gltf")
        .join(name)
}

fn load(name: &str) -> GltfScene {
    load_gltf_scene(&data(name), &GltfOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Vec3A, b: Vec3A) -> bool {
    (a - b).abs().max_element() < 1e-4
}

#[test]
fn node_transforms_compose_parent_first_and_meshes_are_instanced() {
    let s = load("nodes.gltf").scene;
    assert_eq!(s.objects.len(), 2, "one object per node placing the mesh");
    assert_eq!(s.meshes.len(), 1, "both nodes share one mesh");
    // parent = T(1, 2, 3) · R_y(90°) · S(2), where R_y(90°)(x, y, z) = (z, y, −x);
    // childA = parent · T(0, 0, −1), childB = parent · T(5, 0, 0) (a `matrix`).
    let parent = |p: Vec3A| Vec3A::new(1.0, 2.0, 3.0) + Vec3A::new(p.z, p.y, -p.x) * 2.0;
    let expected = [
        parent(Vec3A::new(1.0, 0.0, 0.0) + Vec3A::new(0.0, 0.0, -1.0)),
        parent(Vec3A::new(1.0, 0.0, 0.0) + Vec3A::new(5.0, 0.0, 0.0)),
    ];
    assert!(close(expected[0], Vec3A::new(-1.0, 2.0, 1.0)));
    for (o, e) in s.objects.iter().zip(expected) {
        let Shape::Mesh { transform, smooth, .. } = &o.shape else {
            panic!("a mesh")
        };
        assert!(smooth, "the file gives normals");
        let got = transform.point(Vec3A::X);
        assert!(close(got, e), "{}: {got} ≠ {e}", o.name);
    }
    let mesh = &s.meshes[0];
    // Positions and normals interleaved with a stride of 24 bytes.
    assert_eq!(mesh.positions[1].to_array(), [1.0, 0.0, 0.0]);
    assert_eq!(mesh.positions[2].to_array(), [0.0, 1.0, 0.0]);
    assert!(mesh.normals.iter().all(|n| n.to_array() == [0.0, 0.0, 1.0]));
    // Normalized unsigned shorts: 65535 → 1, 32768 → 32768 / 65535.
    assert_eq!(mesh.uvs[1], Vec2::new(1.0, 0.0));
    assert!((mesh.uvs[2].y - 32768.0 / 65535.0).abs() < 1e-7);
    assert!(mesh.tangents.is_empty(), "no normal map, no tangents");
}

#[test]
fn the_first_camera_is_used_with_its_field_of_view_and_aspect() {
    let g = load("nodes.gltf");
    assert!(!g.framed_camera);
    let c = &g.scene.camera;
    assert!(close(c.position, Vec3A::new(0.0, 0.0, 10.0)));
    assert!(close(c.forward, -Vec3A::Z) && close(c.up, Vec3A::Y));
    assert!((c.fov_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    assert!((c.near_clip - 0.05).abs() < 1e-7);
    assert_eq!((g.settings.width, g.settings.height), (900, 600));
    assert_eq!(g.settings.integrator, caustic::scene::IntegratorKind::Path);
}

#[test]
fn cameras_are_chosen_by_name_node_name_or_index() {
    let with = |c: &str| {
        let options = GltfOptions {
            camera: Some(c.parse::<CameraChoice>().unwrap()),
            ..Default::default()
        };
        load_gltf_scene(&data("nodes.gltf"), &options)
    };
    for ok in ["persp", "eye", "0"] {
        let s = with(ok).unwrap_or_else(|e| panic!("{ok}: {e}")).scene;
        assert!(close(s.camera.position, Vec3A::new(0.0, 0.0, 10.0)));
    }
    // The orthographic one: xmag × ymag half extents, its near plane, and an
    // image of aspect xmag / ymag.
    let g = with("ortho").unwrap_or_else(|e| panic!("{e}"));
    let s = &g.scene;
    assert_eq!(
        s.camera.projection,
        Projection::Orthographic {
            half_width: 1.0,
            half_height: 1.0
        }
    );
    assert!((s.camera.near_clip - 0.1).abs() < 1e-7);
    assert_eq!((g.settings.width, g.settings.height), (600, 600));
    let e = with("7").unwrap_err().to_string();
    assert!(e.contains("no such camera") && e.contains("0 `persp`"), "{e}");
}

#[test]
fn punctual_lights_are_placed_and_converted_at_683_lumens_per_watt() {
    let g = load("nodes.gltf");
    assert!(!g.default_environment);
    let lights = &g.scene.lights;
    assert_eq!(lights.len(), 3);
    match &lights[0] {
        // Rotated −90° about x: the −z axis points down.
        Light::Directional { direction, irradiance } => {
            assert!(close(*direction, -Vec3A::Y), "{direction}");
            assert!(close(*irradiance, Vec3A::new(1.0, 0.5, 0.25)), "683 lx → 1 W/m²");
        }
        other => panic!("{other:?}"),
    }
    match &lights[1] {
        Light::Point { position, intensity } => {
            assert!(close(*position, Vec3A::new(0.0, 4.0, 0.0)));
            assert!(close(*intensity, Vec3A::splat(4.0)), "2732 cd → 4 W/sr");
        }
        other => panic!("{other:?}"),
    }
    match &lights[2] {
        Light::Spot(s) => {
            assert!(close(s.position, Vec3A::new(0.0, 0.0, 5.0)) && close(s.axis, -Vec3A::Z));
            assert!(close(s.intensity, Vec3A::ONE));
            assert_eq!((s.cutoff, s.beam_width), (0.5, 0.2));
            assert_eq!(s.falloff, SpotFalloff::Gltf, "KHR_lights_punctual's smooth falloff");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn materials_map_onto_the_principled_fields_and_texture_slots() {
    let g = load("materials.gltf");
    let s = &g.scene;
    assert_eq!(s.objects.len(), 6, "one object per primitive");
    assert_eq!(s.meshes.len(), 6, "one mesh per primitive");
    let material = |i: usize| &s.materials[s.objects[i].material as usize];

    // Base colour, metallic-roughness, sampler and texture transform.
    let m = material(0);
    let p = m.principled.expect("principled");
    assert_eq!((p.metallic, p.roughness), (0.3, 0.6));
    assert!(close(m.diffuse, Vec3A::splat(0.5)));
    let t = m.textures.as_deref().expect("textures");
    let Some(Texture::Image(base)) = &t.diffuse else {
        panic!("base colour texture")
    };
    assert!(close(base.factor, Vec3A::splat(0.5)));
    assert_eq!(base.wrap, [WrapMode::Clamp, WrapMode::Mirror]);
    assert_eq!(base.filter, FilterMode::Nearest);
    // KHR_texture_transform: offset (0.5, 0), rotation 0.5, scale (2, 3):
    // (1, 0) → (2, 0) → (2 cos 0.5, −2 sin 0.5) → + offset.
    let p1 = base.transform.apply(Vec2::new(1.0, 0.0));
    let expected = Vec2::new(0.5 + 2.0 * 0.5f32.cos(), -2.0 * 0.5f32.sin());
    assert!((p1 - expected).length() < 1e-5, "{p1} ≠ {expected}");
    // Metalness in blue (255 × 0.3), roughness in green (128/255 × 0.6).
    let metal = t.principled_metallic.as_ref().expect("metallic texture");
    let rough = t.principled_roughness.as_ref().expect("roughness texture");
    assert!((metal.eval_scalar(Vec2::splat(0.5)) - 0.3).abs() < 1e-6);
    assert!((rough.eval_scalar(Vec2::splat(0.5)) - 128.0 / 255.0 * 0.6).abs() < 1e-6);
    assert!(
        g.warnings.iter().any(|w| w.contains("/materials/0/occlusionTexture")),
        "{:?}",
        g.warnings
    );

    // A normal map: its mesh gets MikkTSpace tangents (+x: u runs along +x).
    let m = material(1);
    let n = m
        .textures
        .as_deref()
        .and_then(|t| t.normal_map.as_ref())
        .expect("normal map");
    assert_eq!(n.scale, 0.5);
    let Shape::Mesh { mesh, .. } = s.objects[1].shape else {
        panic!("a mesh")
    };
    let tangents = &s.meshes[mesh as usize].tangents;
    assert_eq!(tangents.len(), 4);
    for t in tangents {
        assert!((t.truncate().to_array()[0] - 1.0).abs() < 1e-5 && t.w == 1.0, "{t}");
    }

    // Emission × emissive strength, times the texture.
    let m = material(2);
    assert!(close(m.emission, Vec3A::new(4.0, 2.0, 1.0)));
    assert!(m.textures.as_deref().is_some_and(|t| t.emission.is_some()));
    assert!(m.emits());

    // MASK: the base colour's alpha against the cutoff.
    let mask = material(3)
        .textures
        .as_deref()
        .and_then(|t| t.alpha.as_ref())
        .expect("mask");
    assert_eq!(mask.cutoff, 0.3);
    assert!(mask.opaque_at(Vec2::ZERO), "alpha 0.8 ≥ 0.3");

    // BLEND: a stochastic mix of the material (weight α) and a hole.
    let m = material(4);
    let b = m.blend.as_deref().expect("blend");
    assert!(b.first.is_none() && b.second.as_ref().is_some_and(|s| s.principled.is_some()));
    let Some(Texture::Image(alpha)) = &b.weight_texture else {
        panic!("the base colour's alpha")
    };
    assert_eq!(alpha.channel, Channel::A);
    assert!(m.has_holes());
    // Texel (0, 0) has alpha 1 (× 0.25); texel (1, 1) alpha 0.
    assert!((b.weight_at(Vec2::new(0.25, 0.25)) - 0.25).abs() < 1e-6);
    assert_eq!(b.weight_at(Vec2::new(0.75, 0.75)), 0.0);

    // Transmission, IOR, volume (a medium inside), clear coat.
    let m = material(5);
    let p = m.principled.expect("principled");
    assert_eq!((p.transmission, p.ior, p.thin), (0.9, 1.4, false));
    assert_eq!((p.clearcoat, p.clearcoat_roughness), (0.7, 0.2));
    let t = m.textures.as_deref().expect("textures");
    let Some(Texture::Image(cc)) = &t.principled_clearcoat else {
        panic!("clear coat texture")
    };
    assert_eq!(cc.channel, Channel::R);
    assert_eq!(s.media.list.len(), 1);
    // σa = −ln(c) / d with d = 2 and c = (0.5, 0.25, 1).
    let sigma = s.media.list[0].sigma_t;
    assert!(
        close(sigma, Vec3A::new(0.5f32.ln() / -2.0, 0.25f32.ln() / -2.0, 0.0)),
        "{sigma}"
    );
    assert_eq!(s.media.interface(5).interior, Some(0));
    assert_eq!(s.media.interface(0).interior, None);
}

#[test]
fn a_model_without_lights_or_camera_is_lit_and_framed() {
    let g = load("materials.gltf");
    assert!(g.framed_camera && g.default_environment);
    match g.scene.lights.as_slice() {
        [Light::Environment { radiance, map: None }] => assert!(close(*radiance, Vec3A::ONE)),
        other => panic!("{other:?}"),
    }
    // The quad [−1, 1]² is in front of the camera, which looks at its centre.
    let c = &g.scene.camera;
    assert!(c.position.z > 1.0 && close(c.forward, (Vec3A::ZERO - c.position).normalize()));
}

fn render_exr(model: &str, size: u32, extra: &[&str]) -> Vec<[f32; 3]> {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("out.exr");
    let size_arg = size.to_string();
    let mut args = vec![
        "render",
        model,
        "--exr",
        exr.to_str().unwrap(),
        "--width",
        &size_arg,
        "--height",
        &size_arg,
        "--spp",
        "16",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let o = caustic(&args);
    assert!(o.status.success(), "{}", describe(&o));
    let img = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
        move |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * size as usize + pos.x()] = [r, g, b]
        },
    )
    .expect("the EXR reads back");
    img.layer_data.channel_data.pixels
}

/// Renders `model` at `width × height` (16 spp) and returns its pixels.
fn render_size(model: &str, width: u32, height: u32) -> Vec<[f32; 3]> {
    let dir = tempfile::tempdir().unwrap();
    let exr = dir.path().join("out.exr");
    let (w, h) = (width.to_string(), height.to_string());
    let args = [
        "render",
        model,
        "--exr",
        exr.to_str().unwrap(),
        "--width",
        &w,
        "--height",
        &h,
        "--spp",
        "4",
        "--quiet",
    ];
    let o = caustic(&args);
    assert!(o.status.success(), "{}", describe(&o));
    let img = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
        move |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * width as usize + pos.x()] = [r, g, b]
        },
    )
    .expect("the EXR reads back");
    img.layer_data.channel_data.pixels
}

#[test]
fn an_orthographic_camera_shows_its_rectangle_whatever_the_image_aspect() {
    // The quad [−1, 1]² seen by xmag 2, ymag 1 from 7 units away: at the
    // model's aspect (2:1) it spans the middle half of the width and the
    // whole height; in a square image the aspect ratio wins and the
    // rectangle fits: 4 × 4 units shown, the quad in the middle half both ways.
    let model = "tests/data/gltf/ortho_quad.gltf";
    let g = load("ortho_quad.gltf");
    assert_eq!((g.settings.width, g.settings.height), (1200, 600));
    for (w, h, x0, x1, y0, y1) in [(40, 20, 10, 30, 0, 20), (20, 20, 5, 15, 5, 15)] {
        let px = render_size(model, w, h);
        for y in 0..h {
            for x in 0..w {
                let p = px[(y * w + x) as usize];
                let inside = (x0..x1).contains(&x) && (y0..y1).contains(&y);
                let expected = if inside { [1.0, 0.5, 0.25] } else { [0.0; 3] };
                for (c, e) in p.iter().zip(expected) {
                    assert!(
                        (c - e).abs() < 1e-3,
                        "{w}×{h} pixel ({x}, {y}): {p:?}, expected {expected:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn an_emissive_quad_shows_its_radiance() {
    // Emission (1, 0.5, 0.25) × strength 2 on a black base, lit by nothing.
    let px = render_exr("tests/data/gltf/emissive_quad.glb", 16, &[]);
    for p in &px {
        for (c, e) in p.iter().zip([2.0, 1.0, 0.5]) {
            assert!((c - e).abs() < 1e-3, "{p:?}");
        }
    }
}

#[test]
fn a_base_colour_texture_appears_in_its_corners() {
    // Texels: red, green (top row) / blue, white; the default environment
    // of radiance 1 lights the rough dielectric quad.
    let size = 32;
    let px = render_exr("tests/data/gltf/textured_quad.gltf", size, &[]);
    let mean = |x0: u32, y0: u32| {
        let mut m = [0.0f32; 3];
        for y in y0..y0 + size / 2 {
            for x in x0..x0 + size / 2 {
                let p = px[(y * size + x) as usize];
                for c in 0..3 {
                    m[c] += p[c] / (size * size / 4) as f32;
                }
            }
        }
        m
    };
    let (tl, tr, bl, br) = (
        mean(0, 0),
        mean(size / 2, 0),
        mean(0, size / 2),
        mean(size / 2, size / 2),
    );
    assert!(
        tl[0] > 4.0 * tl[1] && tl[0] > 4.0 * tl[2] && tl[0] > 0.5,
        "top left red: {tl:?}"
    );
    assert!(
        tr[1] > 4.0 * tr[0] && tr[1] > 4.0 * tr[2] && tr[1] > 0.5,
        "top right green: {tr:?}"
    );
    assert!(
        bl[2] > 4.0 * bl[0] && bl[2] > 4.0 * bl[1] && bl[2] > 0.5,
        "bottom left blue: {bl:?}"
    );
    assert!(
        br.iter().all(|&c| c > 0.5) && (br[0] - br[2]).abs() < 0.1,
        "bottom right white: {br:?}"
    );
    // --environment-intensity scales the default environment.
    let dim = render_exr(
        "tests/data/gltf/textured_quad.gltf",
        size,
        &["--environment-intensity", "0.5"],
    );
    let ratio =
        dim.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>() / px.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
    assert!((ratio - 0.5).abs() < 0.02, "{ratio}");
}

#[test]
fn an_environment_image_replaces_the_default_environment() {
    // A uniform grey image (sRGB 128: linear 0.2158) lights the quad 0.2158
    // times as brightly as the default environment of radiance 1, whatever
    // its rotation.
    let dir = tempfile::tempdir().unwrap();
    let env = dir.path().join("grey.png");
    image::RgbImage::from_pixel(8, 4, image::Rgb([128, 128, 128]))
        .save(&env)
        .unwrap();
    let size = 16;
    let sum = |px: &[[f32; 3]]| px.iter().map(|p| p[0] + p[1] + p[2]).sum::<f32>();
    let default = sum(&render_exr("tests/data/gltf/textured_quad.gltf", size, &[]));
    let env_arg = env.to_str().unwrap();
    let grey = sum(&render_exr(
        "tests/data/gltf/textured_quad.gltf",
        size,
        &["--environment", env_arg, "--environment-rotation", "-90"],
    ));
    let expected = caustic::texture::image::srgb_to_linear(128.0 / 255.0);
    assert!(
        (grey / default - expected).abs() < 0.01,
        "{} ≠ {expected}",
        grey / default
    );
}

#[test]
fn convert_writes_a_model_as_toml_that_loads_back_to_the_same_scene() {
    // `caustic convert` compares the scene it wrote, read back, with the
    // model's; it exits 0 only when they agree.
    let dir = tempfile::tempdir().unwrap();
    for model in ["nodes.gltf", "emissive_quad.glb", "ortho_quad.gltf"] {
        let out = dir.path().join(format!("{model}.toml"));
        let path = data(model);
        let o = caustic(&["convert", path.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        assert!(o.status.success(), "{model}: {}", describe(&o));
        let s = caustic::scene::load_scene(&out).unwrap();
        assert_eq!(s.scene.objects.len(), load(model).scene.objects.len());
    }
}

#[test]
fn the_viewer_opens_a_model() {
    let e = caustic::view::EditableScene::open(&data("nodes.gltf")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(e.scene.objects.len(), 2);
    // Its edits are saved as caustic TOML, not written into the model.
    assert!(e.save_camera().is_err());
}

#[test]
fn the_viewer_keeps_an_orthographic_camera_and_zooms_it() {
    let mut e = caustic::view::EditableScene::open(&data("ortho_quad.gltf")).unwrap_or_else(|e| panic!("{e}"));
    e.apply();
    let ortho = |e: &caustic::view::EditableScene| match e.scene.camera.projection {
        Projection::Orthographic {
            half_width,
            half_height,
        } => (half_width, half_height),
        Projection::Perspective => panic!("the orbit made the camera perspective"),
    };
    // The file's rectangle, so that it fits the viewer's image of any aspect.
    let (w, h) = ortho(&e);
    assert!((w - 2.0).abs() < 1e-5 && (h - 1.0).abs() < 1e-5, "{w} {h}");
    assert!(close(e.scene.camera.forward, -Vec3A::Z));
    // Zooming in one step (10 % closer) shows 10 % less, both ways.
    e.orbit.zoom(1.0);
    e.apply();
    let (w, h) = ortho(&e);
    assert!((w - 1.8).abs() < 1e-4 && (h - 0.9).abs() < 1e-4, "{w} {h}");
}
