//! `[[objects]]` and their meshes: analytic shapes by their parameters, a
//! mesh by the file it was read from when that file still holds exactly
//! the loaded mesh, else as a binary PLY file written beside the output.

use super::materials::Names;
use super::{num, path_from, string, unsupported, vec3, WriteError};
use crate::film::output::OutputError;
use crate::scene::{Mesh, Object, Scene, Shape};
use std::path::{Path, PathBuf};
use toml::{Table, Value};

/// Where each of the scene's meshes goes.
pub(super) struct MeshPlan {
    /// Per mesh of `Scene::meshes`: the `file` value written.
    files: Vec<String>,
    /// Per mesh: the PLY to write (absolute or relative to the working
    /// directory), when the mesh is written.
    ply: Vec<Option<PathBuf>>,
    /// Per mesh: the file it is read from, when referenced.
    source: Vec<Option<PathBuf>>,
}

impl MeshPlan {
    /// The mesh files referenced by path.
    pub(super) fn referenced(&self) -> Vec<PathBuf> {
        let mut out: Vec<PathBuf> = self.source.iter().flatten().cloned().collect();
        out.sort();
        out.dedup();
        out
    }
}

/// Decides for each mesh: referenced by path (its `name` is a readable
/// mesh file whose content is exactly the mesh) or written as
/// `STEM-mesh-N.ply` in `dir`.
pub(super) fn plan_meshes(scene: &Scene, dir: &Path, stem: &str) -> Result<MeshPlan, WriteError> {
    let used: Vec<bool> = (0..scene.meshes.len())
        .map(|i| {
            scene
                .objects
                .iter()
                .any(|o| matches!(o.shape, Shape::Mesh { mesh, .. } if mesh as usize == i))
        })
        .collect();
    let water = water_boundary(scene);
    let mut plan = MeshPlan {
        files: Vec::new(),
        ply: Vec::new(),
        source: Vec::new(),
    };
    for (i, mesh) in scene.meshes.iter().enumerate() {
        let is_water = water.is_some_and(|w| w.1 == i as u32);
        if !used[i] || is_water {
            plan.files.push(String::new());
            plan.ply.push(None);
            plan.source.push(None);
            continue;
        }
        if let Some(path) = same_file(mesh) {
            plan.files.push(path_from(dir, &path));
            plan.ply.push(None);
            plan.source.push(Some(path));
            continue;
        }
        if !mesh.tangents.is_empty() {
            return Err(unsupported(
                format!("mesh `{}`", mesh.name),
                "a mesh with tangents built in memory (a PLY file holds none)",
            ));
        }
        let name = format!("{stem}-mesh-{i}.ply");
        plan.files.push(name.clone());
        plan.ply.push(Some(dir.join(name)));
        plan.source.push(None);
    }
    Ok(plan)
}

/// The file `mesh` was read from, when reading it again gives the same mesh.
fn same_file(mesh: &Mesh) -> Option<PathBuf> {
    let path = PathBuf::from(&mesh.name);
    if !path.is_file() {
        return None;
    }
    let again = crate::io::load_mesh(&path).ok()?;
    crate::scene::compare::same_mesh(mesh, &again).then_some(path)
}

/// The object the water's `[medium]` fills and its mesh, when there is one.
fn water_boundary(scene: &Scene) -> Option<(usize, u32)> {
    let m = scene.water_medium.as_ref()?;
    match scene.objects.get(m.boundary as usize)?.shape {
        Shape::Mesh { mesh, .. } => Some((m.boundary as usize, mesh)),
        _ => None,
    }
}

/// Writes the planned PLY files (each atomically); returns their paths.
pub(super) fn write_meshes(scene: &Scene, plan: &MeshPlan) -> Result<Vec<PathBuf>, WriteError> {
    let mut written = Vec::new();
    for (mesh, path) in scene.meshes.iter().zip(&plan.ply) {
        let Some(path) = path else { continue };
        let result = crate::film::output::write_atomically(path, |w| {
            crate::io::ply::write_binary(w, mesh).map_err(|source| OutputError::Io {
                path: path.clone(),
                what: "writing",
                source,
            })
        });
        if let Err(e) = result {
            for p in &written {
                // Complete files from this run; the error is what matters.
                let _ = std::fs::remove_file(p);
            }
            return Err(e.into());
        }
        written.push(path.clone());
    }
    Ok(written)
}

/// Object `i` as an `[[objects]]` table.
pub(super) fn object(scene: &Scene, i: usize, o: &Object, names: &Names, plan: &MeshPlan) -> Table {
    let mut t = Table::new();
    t.insert("name".into(), string(&o.name));
    let material = &scene.materials[o.material as usize];
    debug_assert!(names.by_name.contains_key(&material.name));
    t.insert("material".into(), string(&material.name));
    match &o.shape {
        Shape::Sphere(s) => {
            t.insert("type".into(), string("sphere"));
            t.insert("center".into(), vec3(s.center));
            t.insert("radius".into(), num(s.radius));
        }
        Shape::Quad(q) => {
            t.insert("type".into(), string("quad"));
            t.insert("corner".into(), vec3(q.corner));
            t.insert("u".into(), vec3(q.u));
            t.insert("v".into(), vec3(q.v));
        }
        Shape::Disk(d) => {
            t.insert("type".into(), string("disk"));
            t.insert("center".into(), vec3(d.center));
            t.insert("u".into(), vec3(d.a));
            t.insert("v".into(), vec3(d.b));
            // The loader's disk faces `u × v` unless flipped.
            let front = d.a.cross(d.b);
            t.insert("flip_normals".into(), Value::Boolean(front.dot(d.normal) < 0.0));
        }
        Shape::Cylinder(c) => {
            t.insert("type".into(), string("cylinder"));
            t.insert("p0".into(), vec3(c.base));
            t.insert("p1".into(), vec3(c.base + c.axis * c.length));
            t.insert("radius".into(), num(c.radius));
            t.insert("flip_normals".into(), Value::Boolean(c.inward));
        }
        Shape::Mesh {
            mesh,
            transform,
            smooth,
        } => {
            if let Some((object, _)) = water_boundary(scene).filter(|(object, _)| *object == i) {
                debug_assert_eq!(object, i);
                let m = scene.water_medium.as_ref().expect("a water boundary has a medium");
                super::media::water_object(&m.surface, &mut t);
            } else {
                t.insert("type".into(), string("mesh"));
                t.insert("file".into(), string(&plan.files[*mesh as usize]));
                if !transform.is_identity() {
                    let a = transform.to_world;
                    let (c, d) = (a.matrix3, a.translation);
                    let row =
                        |r: usize| Value::Array(vec![num(c.x_axis[r]), num(c.y_axis[r]), num(c.z_axis[r]), num(d[r])]);
                    t.insert("matrix".into(), Value::Array(vec![row(0), row(1), row(2)]));
                }
                t.insert("smooth".into(), Value::Boolean(*smooth));
            }
        }
    }
    let f = scene.media.interface(i as u32);
    let medium = |m: Option<u32>| m.map(|m| string(&scene.media.list[m as usize].name));
    if let Some(v) = medium(f.interior) {
        t.insert("interior".into(), v);
    }
    if let Some(v) = medium(f.exterior) {
        t.insert("exterior".into(), v);
    }
    t
}
