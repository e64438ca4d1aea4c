//! The scene graph (glTF 2.0 §3.5): the scene's node trees walked from
//! their roots, each node's world matrix the product of its ancestors'
//! local matrices (`T · R · S` or `matrix`), and every mesh a node places
//! added as objects that share one caustic mesh per primitive, however
//! many nodes place it (instancing).

use super::materials::{self, Built};
use super::meshes;
use super::Ctx;
use crate::geometry::Mesh;
use crate::scene::load::SceneError;
use crate::scene::Origin;
use crate::scene::{HomogeneousMedium, Material, MediumInterface, Object, Shape};
use glam::{Affine3A, Mat4};
use std::collections::HashMap;
use std::sync::Arc;

/// Something a node places, with the node's world matrix.
#[derive(Clone, Debug)]
pub(crate) struct Placed {
    /// Index of the mesh, camera or light.
    pub item: usize,
    /// The node that places it.
    pub node: usize,
    /// The node's object-to-world matrix.
    pub world: Mat4,
}

/// What the scene's nodes place.
#[derive(Debug, Default)]
pub(crate) struct Graph {
    pub meshes: Vec<Placed>,
    pub cameras: Vec<Placed>,
    pub lights: Vec<Placed>,
}

/// The node's local matrix (glTF 2.0 §3.5.2: `matrix`, or `T · R · S`).
pub(crate) fn local_matrix(node: &gltf::Node) -> Mat4 {
    Mat4::from_cols_array_2d(&node.transform().matrix())
}

/// Walks the default scene (or the first; with no scene, every node that
/// is no other's child) depth first.
pub(super) fn walk(ctx: &mut Ctx) -> Result<Graph, SceneError> {
    let doc = ctx.doc;
    let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => {
            let mut child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    child[c.index()] = true;
                }
            }
            if !child.is_empty() {
                ctx.warn("", "the model has no scene: every root node is rendered");
            }
            (0..child.len()).filter(|&i| !child[i]).collect()
        }
    };
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut seen = vec![false; nodes.len()];
    let mut graph = Graph::default();
    let mut stack: Vec<(usize, Mat4, String)> = roots
        .iter()
        .rev()
        .map(|&i| (i, Mat4::IDENTITY, format!("/nodes/{i}")))
        .collect();
    while let Some((i, parent, pointer)) = stack.pop() {
        if std::mem::replace(&mut seen[i], true) {
            // §3.5.3: the nodes form disjoint strict trees.
            return Err(ctx.error(
                pointer,
                format!("node {i} is reached twice: a node has one parent at most and the hierarchy has no cycle"),
            ));
        }
        let node = &nodes[i];
        let world = parent * local_matrix(node);
        if !world.is_finite() {
            return Err(ctx.error(
                format!("/nodes/{i}"),
                "the node's transform (composed with its parents') is not finite",
            ));
        }
        let place = |item: usize| Placed { item, node: i, world };
        if let Some(m) = node.mesh() {
            graph.meshes.push(place(m.index()));
        }
        if let Some(c) = node.camera() {
            graph.cameras.push(place(c.index()));
        }
        if let Some(l) = node.light() {
            graph.lights.push(place(l.index()));
        }
        if node.skin().is_some() {
            ctx.warn(
                &format!("/nodes/{i}/skin"),
                "skins are not applied: the mesh is rendered in its bind pose",
            );
        }
        for (k, c) in node.children().enumerate().collect::<Vec<_>>().into_iter().rev() {
            let _ = k;
            stack.push((c.index(), world, format!("/nodes/{i}/children/{k}")));
        }
    }
    Ok(graph)
}

/// The scene's geometry, materials and media.
pub(super) struct BuiltScene {
    /// The materials, each with its JSON pointer.
    pub materials: Vec<(Material, Origin)>,
    pub meshes: Vec<Arc<Mesh>>,
    /// The objects, each with the pointer of its primitive.
    pub objects: Vec<(Object, Origin)>,
    pub media: Vec<HomogeneousMedium>,
    /// Per object, the media on its sides.
    pub interfaces: Vec<MediumInterface>,
}

/// A material's index in the scene, its medium's, and whether it is normal-mapped.
#[derive(Clone, Copy)]
struct MaterialSlot {
    index: u32,
    medium: Option<u32>,
    normal_mapped: bool,
}

/// Objects for every primitive of every placed mesh; materials and meshes
/// built once, on first use.
pub(super) fn build(ctx: &mut Ctx, graph: &Graph) -> Result<BuiltScene, SceneError> {
    let doc = ctx.doc;
    let mut out = BuiltScene {
        materials: Vec::new(),
        meshes: Vec::new(),
        objects: Vec::new(),
        media: Vec::new(),
        interfaces: Vec::new(),
    };
    let mut material_slots: HashMap<Option<usize>, MaterialSlot> = HashMap::new();
    // Materials without their normal map, for meshes without texture coordinates.
    let mut stripped: HashMap<Option<usize>, u32> = HashMap::new();
    let mut mesh_slots: HashMap<(usize, usize), Option<(u32, bool)>> = HashMap::new();
    let gltf_meshes: Vec<gltf::Mesh> = doc.meshes().collect();
    for placed in &graph.meshes {
        let mesh = &gltf_meshes[placed.item];
        let affine = Affine3A::from_mat4(placed.world);
        let Some(transform) = crate::math::Transform::from_affine(affine) else {
            ctx.warn(
                &format!("/nodes/{}", placed.node),
                "the node's transform is singular (a zero scale): its mesh is not rendered",
            );
            continue;
        };
        for prim in mesh.primitives() {
            let key = prim.material().index();
            let slot = match material_slots.get(&key) {
                Some(s) => *s,
                None => {
                    let Built {
                        material,
                        medium,
                        normal_mapped,
                    } = match key {
                        Some(_) => materials::material(ctx, &prim.material())?,
                        None => Built {
                            material: materials::default_material(),
                            medium: None,
                            normal_mapped: false,
                        },
                    };
                    let pointer = key.map_or_else(String::new, |k| format!("/materials/{k}"));
                    out.materials.push((material, ctx.origin(pointer)));
                    let medium = medium.map(|m| {
                        out.media.push(m);
                        (out.media.len() - 1) as u32
                    });
                    let s = MaterialSlot {
                        index: (out.materials.len() - 1) as u32,
                        medium,
                        normal_mapped,
                    };
                    material_slots.insert(key, s);
                    s
                }
            };
            let mesh_key = (mesh.index(), prim.index());
            let built = match mesh_slots.get(&mesh_key) {
                Some(b) => *b,
                None => {
                    let b = meshes::primitive(ctx, mesh, &prim, slot.normal_mapped)?.map(|p| {
                        if slot.normal_mapped && p.mesh.uvs.is_empty() {
                            ctx.warn(
                                &format!("/meshes/{}/primitives/{}", mesh.index(), prim.index()),
                                "the material has a normal map but the primitive has no TEXCOORD_0: the map is not applied",
                            );
                        }
                        out.meshes.push(Arc::new(p.mesh));
                        ((out.meshes.len() - 1) as u32, p.smooth)
                    });
                    mesh_slots.insert(mesh_key, b);
                    b
                }
            };
            let Some((mesh_index, smooth)) = built else { continue };
            let mut material = slot.index;
            if slot.normal_mapped && out.meshes[mesh_index as usize].uvs.is_empty() {
                // The map cannot be applied without texture coordinates:
                // this mesh gets a copy of the material without it.
                material = *stripped.entry(key).or_insert_with(|| {
                    let (mut m, origin) = out.materials[slot.index as usize].clone();
                    if let Some(t) = m.textures.as_deref_mut() {
                        t.normal_map = None;
                    }
                    out.materials.push((m, origin));
                    (out.materials.len() - 1) as u32
                });
            }
            let node_name = doc
                .nodes()
                .nth(placed.node)
                .and_then(|n| n.name().map(str::to_string))
                .unwrap_or_else(|| format!("node {}", placed.node));
            let object = Object {
                name: format!("{node_name}#{}", prim.index()),
                shape: Shape::Mesh {
                    mesh: mesh_index,
                    transform,
                    smooth,
                },
                material,
            };
            let origin = ctx.origin(format!("/meshes/{}/primitives/{}", mesh.index(), prim.index()));
            out.objects.push((object, origin));
            out.interfaces.push(MediumInterface {
                interior: slot.medium,
                exterior: None,
            });
        }
    }
    Ok(out)
}
