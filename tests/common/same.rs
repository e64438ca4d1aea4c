//! Two scenes compared part by part, so that a difference names the part:
//! settings, camera, lights, each object with the material and mesh
//! content it uses (indices into the lists may differ between formats: a
//! TOML file keeps its materials and media in name order), and the media
//! as the objects and the camera see them.

use caustic::accel::{self, AccelKind, AccelOptions};
use caustic::integrator::{render, RenderPlan, RenderSetup};
use caustic::scene::{HomogeneousMedium, LoadedScene, Material, Scene, Shape};
use caustic::texture::Texture;
use std::sync::Arc;

/// Whether the names (of materials, objects, media) must agree too: a
/// scene written out and read back keeps them; two formats' twins do not.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Names {
    /// Compared.
    Same,
    /// Ignored.
    Ignored,
}

/// `m` with its images' names (the paths they were read from) cleared,
/// and its own name and its blend sides' names too when `names` says so.
fn comparable(m: &Material, names: Names) -> Material {
    fn image(t: &mut Texture) {
        if let Texture::Image(i) = t {
            let mut copy = (*i.image).clone();
            copy.name.clear();
            i.image = Arc::new(copy);
        }
    }
    let mut m = m.clone();
    if names == Names::Ignored {
        m.name.clear();
    }
    if let Some(t) = &mut m.textures {
        t.all_mut().for_each(image);
    }
    if let Some(b) = &mut m.blend {
        if let Some(w) = &mut b.weight_texture {
            image(w);
        }
        b.first = b.first.as_ref().map(|m| comparable(m, names));
        b.second = b.second.as_ref().map(|m| comparable(m, names));
    }
    m
}

fn medium(scene: &Scene, i: Option<u32>, names: Names) -> Option<HomogeneousMedium> {
    i.map(|i| {
        let mut m = scene.media.list[i as usize].clone();
        if names == Names::Ignored {
            m.name.clear();
        }
        m
    })
}

/// Panics with the first part where `a` and `b` differ.
pub fn assert_same_scene(a: &LoadedScene, b: &LoadedScene, names: Names) {
    assert_eq!(a.settings, b.settings, "render settings");
    let (a, b) = (&a.scene, &b.scene);
    assert_eq!(a.ambient, b.ambient, "ambient light");
    assert_eq!(a.water_medium, b.water_medium, "water medium");
    assert_eq!(a.camera, b.camera, "camera");
    assert_eq!(a.lights, b.lights, "lights");
    assert_eq!(a.objects.len(), b.objects.len(), "object count");
    assert_eq!(
        a.media.pass_through, b.media.pass_through,
        "how null surfaces are crossed"
    );
    assert_eq!(a.media.list.len(), b.media.list.len(), "media count");
    assert_eq!(
        medium(a, a.media.camera, names),
        medium(b, b.media.camera, names),
        "the camera's medium"
    );
    for (i, (oa, ob)) in a.objects.iter().zip(&b.objects).enumerate() {
        let what = format!("object {i} (`{}`)", oa.name);
        if names == Names::Same {
            assert_eq!(oa.name, ob.name, "{what}: name");
        }
        let (ma, mb) = (&a.materials[oa.material as usize], &b.materials[ob.material as usize]);
        assert_eq!(comparable(ma, names), comparable(mb, names), "{what}: material");
        match (&oa.shape, &ob.shape) {
            (
                Shape::Mesh {
                    mesh: ia,
                    transform: ta,
                    smooth: sa,
                },
                Shape::Mesh {
                    mesh: ib,
                    transform: tb,
                    smooth: sb,
                },
            ) => {
                assert_eq!((ta, sa), (tb, sb), "{what}: transform and smoothing");
                let (x, y) = (&a.meshes[*ia as usize], &b.meshes[*ib as usize]);
                assert_eq!(x.positions, y.positions, "{what}: mesh positions");
                assert_eq!(x.normals, y.normals, "{what}: mesh normals");
                assert_eq!(x.triangles, y.triangles, "{what}: mesh triangles");
                assert_eq!(x.uvs, y.uvs, "{what}: mesh texture coordinates");
                assert_eq!(x.tangents, y.tangents, "{what}: mesh tangents");
            }
            (sa, sb) => assert_eq!(sa, sb, "{what}: shape"),
        }
        let (fa, fb) = (a.media.interface(i as u32), b.media.interface(i as u32));
        assert_eq!(
            (medium(a, fa.interior, names), medium(a, fa.exterior, names)),
            (medium(b, fb.interior, names), medium(b, fb.exterior, names)),
            "{what}: media inside and outside"
        );
    }
}

/// The linear pixels of a render of `scene` at `width × height` and `spp`
/// (the scene's own seed and settings otherwise).
pub fn render_small(loaded: &LoadedScene, width: u32, height: u32, spp: u32) -> Vec<[f32; 3]> {
    let scene = &loaded.scene;
    let mut settings = loaded.settings.clone();
    settings.width = width;
    settings.height = height;
    settings.spp = spp;
    settings.noise_threshold = None;
    settings.photons.count = settings.photons.count.min(20_000);
    let accel = accel::build(scene, AccelKind::KdTree, &AccelOptions::default()).unwrap();
    let plan = RenderPlan::new(scene, &settings);
    let out = render(scene, accel.as_ref(), &plan, RenderSetup::default());
    out.film.pixels.iter().map(|p| p.to_array()).collect()
}
