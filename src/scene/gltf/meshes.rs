//! Mesh primitives (glTF 2.0 §3.7.2) as caustic meshes: positions,
//! normals, the first texture coordinates and tangents, triangle lists,
//! strips and fans; MikkTSpace tangents where a normal map needs them and
//! the file has none.

use super::Ctx;
use crate::geometry::Mesh;
use crate::math::{Vec2, Vec3, Vec4};
use crate::scene::load::SceneError;
use gltf::accessor::DataType;
use gltf::mesh::{Mode, Semantic};

/// A primitive as a mesh, and whether its normals are interpolated (the
/// file's `NORMAL`) or flat (computed: glTF 2.0 §3.7.2.1 asks for flat
/// normals when a primitive has none).
pub(super) struct Primitive {
    pub mesh: Mesh,
    pub smooth: bool,
}

const FLOAT: (DataType, bool) = (DataType::F32, false);

/// The mesh of primitive `prim` of `mesh`; `None` (with a warning) for a
/// primitive that draws points or lines, or no triangle at all.
pub(super) fn primitive(
    ctx: &mut Ctx,
    mesh: &gltf::Mesh,
    prim: &gltf::Primitive,
    wants_tangents: bool,
) -> Result<Option<Primitive>, SceneError> {
    let pointer = format!("/meshes/{}/primitives/{}", mesh.index(), prim.index());
    let mode = prim.mode();
    if matches!(mode, Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip) {
        ctx.warn(
            &format!("{pointer}/mode"),
            format!("a primitive of {mode:?}: caustic renders triangles only; skipped"),
        );
        return Ok(None);
    }
    let positions_accessor = prim
        .get(&Semantic::Positions)
        .ok_or_else(|| ctx.error(format!("{pointer}/attributes"), "a primitive without POSITION"))?;
    let vertices = positions_accessor.count();
    let index_count = prim.indices().map_or(vertices, |a| a.count());
    let triangles_announced = match mode {
        Mode::Triangles => index_count / 3,
        _ => index_count.saturating_sub(2),
    };
    let max_elements = crate::io::LoadLimits::default().max_elements;
    if vertices as u64 > max_elements || index_count as u64 > max_elements {
        let (accessor, count) = match prim.indices() {
            Some(a) if a.count() as u64 > max_elements => (a.index(), a.count()),
            _ => (positions_accessor.index(), vertices),
        };
        return Err(ctx.error(
            format!("/accessors/{accessor}/count"),
            format!("{count} elements: more than the limit of {max_elements}"),
        ));
    }
    // Before reading anything: the mesh must fit the memory budget.
    if let Some(budget) = crate::io::LoadLimits::default().memory {
        let need = crate::io::mesh_memory_bytes(vertices as u64, triangles_announced as u64);
        if need > u128::from(budget.bytes) {
            return Err(ctx.error(
                &pointer,
                format!(
                    "{vertices} vertices and {triangles_announced} triangles need about {} of memory, {budget}",
                    crate::memory::format_bytes(u64::try_from(need).unwrap_or(u64::MAX))
                ),
            ));
        }
    }
    let positions: Vec<Vec3> = ctx
        .floats::<3>(
            &positions_accessor,
            &format!("{pointer}/attributes/POSITION"),
            "POSITION",
            &[FLOAT],
        )?
        .into_iter()
        .map(Vec3::from_array)
        .collect();
    let normals = match prim.get(&Semantic::Normals) {
        None => None,
        Some(a) => Some(attribute::<3>(ctx, &a, &pointer, "NORMAL", vertices, &[FLOAT])?),
    };
    let uv_types = [FLOAT, (DataType::U8, true), (DataType::U16, true)];
    let uvs = match prim.get(&Semantic::TexCoords(0)) {
        None => None,
        Some(a) => Some(attribute::<2>(ctx, &a, &pointer, "TEXCOORD_0", vertices, &uv_types)?),
    };
    let tangents = match prim.get(&Semantic::Tangents) {
        None => None,
        Some(a) => Some(attribute::<4>(ctx, &a, &pointer, "TANGENT", vertices, &[FLOAT])?),
    };
    for (semantic, _) in prim.attributes() {
        let ignored = match semantic {
            Semantic::Colors(_) => Some("vertex colours (COLOR_n) are not rendered"),
            Semantic::TexCoords(n) if n > 0 => Some("only TEXCOORD_0 is read"),
            Semantic::Joints(_) | Semantic::Weights(_) => {
                Some("skins are not applied: the mesh is rendered in its bind pose")
            }
            _ => None,
        };
        if let Some(why) = ignored {
            ctx.warn(&format!("{pointer}/attributes/{}", semantic.to_string()), why);
        }
    }
    if prim.morph_targets().len() > 0 {
        ctx.warn(
            &format!("{pointer}/targets"),
            "morph targets are not applied: the base shape is rendered",
        );
    }
    let corners: Vec<u32> = match prim.indices() {
        Some(a) => ctx.indices(&a, &format!("{pointer}/indices"), vertices)?,
        None => (0..vertices as u32).collect(),
    };
    let triangles = triangles_of(mode, &corners);
    if triangles.is_empty() {
        ctx.warn(&pointer, "a primitive without a triangle; skipped");
        return Ok(None);
    }
    let smooth = normals.is_some();
    let name = match mesh.name() {
        Some(n) => format!("{n}#{}", prim.index()),
        None => format!("mesh {} primitive {}", mesh.index(), prim.index()),
    };
    let bad = |e: crate::geometry::MeshDataError| ctx.error(&pointer, e.to_string());
    let mut built = Mesh::new(
        name,
        positions,
        triangles,
        normals.map(|n| n.into_iter().map(Vec3::from_array).collect()),
    )
    .map_err(bad)?;
    if let Some(uvs) = uvs {
        built = built
            .with_uvs(uvs.into_iter().map(Vec2::from_array).collect())
            .map_err(bad)?;
    }
    match tangents {
        Some(t) if !built.uvs.is_empty() => {
            built = built
                .with_tangents(t.into_iter().map(Vec4::from_array).collect())
                .map_err(bad)?;
        }
        _ if wants_tangents && !built.uvs.is_empty() => {
            let t = mikktspace_tangents(&built);
            built = built.with_tangents(t).map_err(bad)?;
        }
        _ => {}
    }
    Ok(Some(Primitive { mesh: built, smooth }))
}

/// An attribute of `N` components per vertex, one per vertex.
fn attribute<const N: usize>(
    ctx: &Ctx,
    accessor: &gltf::Accessor,
    pointer: &str,
    name: &str,
    vertices: usize,
    allowed: &[(DataType, bool)],
) -> Result<Vec<[f32; N]>, SceneError> {
    let at = format!("{pointer}/attributes/{name}");
    if accessor.count() != vertices {
        return Err(ctx.error(
            &at,
            format!(
                "accessor {} has {} elements, POSITION has {vertices}",
                accessor.index(),
                accessor.count()
            ),
        ));
    }
    ctx.floats::<N>(accessor, &at, name, allowed)
}

/// Triangles of a list, strip or fan of vertex indices (glTF 2.0
/// §3.7.2.1: strip triangle `i` is `(vᵢ, v_{i+1+i%2}, v_{i+2−i%2})`, fan
/// triangle `i` is `(v_{i+1}, v_{i+2}, v₀)`), so that every triangle keeps
/// the winding of the first.
pub(super) fn triangles_of(mode: Mode, v: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..v.len().saturating_sub(2))
            .map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..v.len().saturating_sub(2))
            .map(|i| [v[i + 1], v[i + 2], v[0]])
            .collect(),
        _ => v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

/// MikkTSpace's view of a mesh: texture coordinates with `v` flipped, as
/// Blender hands them to MikkTSpace (its `v` runs up the image), so the
/// tangents and their bitangent signs are those Blender computes and
/// exports for the same model.
struct MikkMesh<'m> {
    mesh: &'m Mesh,
    /// Per vertex, the sum of the tangents MikkTSpace gave its corners and
    /// the last bitangent sign.
    sums: Vec<Vec4>,
}

impl mikktspace::Geometry for MikkMesh<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.triangles[face][vert] as usize].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.mesh.triangles[face][vert] as usize].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.mesh.uvs[self.mesh.triangles[face][vert] as usize];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        let i = self.mesh.triangles[face][vert] as usize;
        let s = &mut self.sums[i];
        *s = Vec4::from((s.truncate() + Vec3::from_slice(&tangent[..3]), tangent[3]));
    }
}

/// Per-vertex MikkTSpace tangents. MikkTSpace works per corner; a vertex
/// shared by corners that disagree gets their mean (glTF splits vertices
/// along UV seams already, where they disagree most). Vertices MikkTSpace
/// leaves out get any unit vector orthogonal to their normal.
pub(super) fn mikktspace_tangents(mesh: &Mesh) -> Vec<Vec4> {
    let mut m = MikkMesh {
        mesh,
        sums: vec![Vec4::new(0.0, 0.0, 0.0, 1.0); mesh.positions.len()],
    };
    // The mikktspace crate reads freed memory when every triangle is
    // degenerate (two corners at the same position, its own test): its
    // count of the others underflows. Such a mesh has no tangents to find.
    let proper = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize].to_array());
        a != b && a != c && b != c
    };
    if mesh.triangles.iter().any(proper) {
        mikktspace::generate_tangents(&mut m);
    }
    m.sums
        .iter()
        .zip(&mesh.normals)
        .map(|(s, n)| {
            let t = s
                .truncate()
                .try_normalize()
                .unwrap_or_else(|| n.any_orthonormal_vector());
            Vec4::from((t, if s.w < 0.0 { -1.0 } else { 1.0 }))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_the_winding() {
        let v = [0, 1, 2, 3, 4];
        assert_eq!(triangles_of(Mode::TriangleStrip, &v), [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        assert_eq!(triangles_of(Mode::TriangleFan, &v), [[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
        assert_eq!(triangles_of(Mode::Triangles, &v), [[0, 1, 2]]);
    }

    #[test]
    fn mikktspace_tangents_follow_u_and_the_flipped_v() {
        // A quad in the xy plane facing +z, u along +x, glTF v along −y
        // (v = 0 at the top): the tangent is +x and the bitangent
        // sign · n × t = sign · (+y) must point up the image, toward −v: +y.
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let uvs = vec![
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.0, 0.0),
        ];
        let mesh = Mesh::new("q", positions, vec![[0, 1, 2], [0, 2, 3]], None)
            .unwrap()
            .with_uvs(uvs)
            .unwrap();
        for t in mikktspace_tangents(&mesh) {
            assert!((t.truncate() - Vec3::X).length() < 1e-5, "{t}");
            assert_eq!(t.w, 1.0);
        }
    }
}
