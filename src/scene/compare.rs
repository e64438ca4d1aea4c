//! Whether two scenes are the same scene: what `caustic convert` checks
//! of the scene it wrote, read back, against the scene it read.
//!
//! Two front ends may list the same things in another order (a TOML file
//! keeps its materials and media in name order, Mitsuba in the order of
//! the file), and a mesh or an image read from another path has another
//! name, so the comparison follows what each object uses: its shape (a
//! mesh by its content), its material (images by their texels), the
//! media on its sides; then the settings, the camera and the lights.

use super::{HomogeneousMedium, LoadedScene, Material, Scene, Shape};
use crate::texture::Texture;
use std::sync::Arc;

/// The first part where `a` and `b` differ, described; `None` when they
/// are the same scene.
pub fn first_difference(a: &LoadedScene, b: &LoadedScene) -> Option<String> {
    if a.settings != b.settings {
        return Some(format!("render settings: {:?} against {:?}", a.settings, b.settings));
    }
    scene_difference(&a.scene, &b.scene)
}

/// The first part where the scenes `a` and `b` differ (settings aside).
fn scene_difference(a: &Scene, b: &Scene) -> Option<String> {
    fn differ<T: PartialEq + std::fmt::Debug>(what: &str, x: &T, y: &T) -> Option<String> {
        (x != y).then(|| format!("{what}: {x:?} against {y:?}"))
    }
    let mut checks = vec![
        differ("ambient light", &a.ambient, &b.ambient),
        differ("water medium", &a.water_medium, &b.water_medium),
        differ("camera", &a.camera, &b.camera),
        differ("lights", &a.lights, &b.lights),
        differ("object count", &a.objects.len(), &b.objects.len()),
        differ("media count", &a.media.list.len(), &b.media.list.len()),
        differ(
            "how null surfaces are crossed",
            &a.media.pass_through,
            &b.media.pass_through,
        ),
        differ(
            "the camera's medium",
            &medium(a, a.media.camera),
            &medium(b, b.media.camera),
        ),
    ];
    for (i, (oa, ob)) in a.objects.iter().zip(&b.objects).enumerate() {
        let what = |part: &str| format!("object {i} (`{}`): {part}", oa.name);
        checks.push(differ(&what("name"), &oa.name, &ob.name));
        checks.push(differ(
            &what("material"),
            &comparable(&a.materials[oa.material as usize]),
            &comparable(&b.materials[ob.material as usize]),
        ));
        checks.push(match (&oa.shape, &ob.shape) {
            (
                Shape::Mesh {
                    mesh: ma,
                    transform: ta,
                    smooth: sa,
                },
                Shape::Mesh {
                    mesh: mb,
                    transform: tb,
                    smooth: sb,
                },
            ) => differ(&what("transform and smoothing"), &(ta, sa), &(tb, sb)).or_else(|| {
                let (x, y) = (&a.meshes[*ma as usize], &b.meshes[*mb as usize]);
                (!same_mesh(x, y)).then(|| what(&format!("mesh `{}` and mesh `{}` differ", x.name, y.name)))
            }),
            (x, y) => differ(&what("shape"), x, y),
        });
        let (fa, fb) = (a.media.interface(i as u32), b.media.interface(i as u32));
        checks.push(differ(
            &what("media inside and outside"),
            &(medium(a, fa.interior), medium(a, fa.exterior)),
            &(medium(b, fb.interior), medium(b, fb.exterior)),
        ));
    }
    checks.into_iter().flatten().next()
}

/// True when two meshes hold the same vertices, triangles and attributes
/// (their names, which say where they were read, aside).
pub fn same_mesh(a: &crate::scene::Mesh, b: &crate::scene::Mesh) -> bool {
    a.positions == b.positions
        && a.normals == b.normals
        && a.triangles == b.triangles
        && a.uvs == b.uvs
        && a.tangents == b.tangents
}

fn medium(scene: &Scene, i: Option<u32>) -> Option<&HomogeneousMedium> {
    i.map(|i| &scene.media.list[i as usize])
}

/// `m` with its images' names cleared: an image is the same image read
/// from any path (its texels and their hash decide).
fn comparable(m: &Material) -> Material {
    let mut m = m.clone();
    if let Some(t) = &mut m.textures {
        t.all_mut().for_each(unnamed);
    }
    if let Some(b) = &mut m.blend {
        if let Some(w) = &mut b.weight_texture {
            unnamed(w);
        }
        b.first = b.first.as_ref().map(comparable);
        b.second = b.second.as_ref().map(comparable);
    }
    m
}

fn unnamed(t: &mut Texture) {
    if let Texture::Image(i) = t {
        if !i.image.name.is_empty() {
            let mut image = (*i.image).clone();
            image.name.clear();
            i.image = Arc::new(image);
        }
    }
}
