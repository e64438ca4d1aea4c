//! Wavefront OBJ through the `tobj` crate: polygons triangulated, every
//! object and group merged into one mesh, materials ignored (the scene file
//! assigns materials). File normals are kept: a position that carries
//! different normals on different faces (a hard edge) becomes one vertex per
//! normal, as in Mitsuba's loader; when some corners name no normal, the
//! normals are computed. `tobj` reports no positions, so on error the loader finds the
//! first offending line itself.

use super::source::{parse_f32, parse_i64, Source};
use super::{LoadLimits, ParseError, Place};
use crate::geometry::Mesh;
use crate::math::{Vec2, Vec3};
use std::collections::HashMap;
use std::io::Read;

/// Largest OBJ text (after decompression) read into memory: `tobj` needs it whole.
pub const MAX_OBJ_BYTES: u64 = 2 << 30;

pub(crate) fn parse(src: &mut Source, limits: &LoadLimits, name: String) -> Result<Mesh, ParseError> {
    let mut text = Vec::new();
    let read = (&mut src.stream)
        .take(MAX_OBJ_BYTES + 1)
        .read_to_end(&mut text)
        .map_err(|e| ParseError::new(None, e.to_string()))?;
    if read as u64 > MAX_OBJ_BYTES {
        return Err(ParseError::new(
            None,
            format!("more than {MAX_OBJ_BYTES} bytes of OBJ text: refusing to read further"),
        ));
    }
    if let Err(e) = std::str::from_utf8(&text) {
        let line = line_of(&text, e.valid_up_to());
        return Err(ParseError::new(
            Some(Place::Line(line)),
            "not UTF-8 text (a binary file named .obj?)".into(),
        ));
    }
    // The memory check before `tobj` allocates: count the `v` and `f` records.
    let (mut vertices, mut faces) = (0u64, 0u64);
    for line in text.split(|&b| b == b'\n') {
        match line.trim_ascii_start() {
            [b'v', b' ' | b'\t', ..] => vertices += 1,
            [b'f', b' ' | b'\t', ..] => faces += 1,
            _ => {}
        }
    }
    super::check_mesh_memory(vertices, faces, limits, None)?;
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut &text[..], &options, |_| Ok((Vec::new(), HashMap::new())))
        .map_err(|e| ParseError::new(locate(&text, &e), format!("invalid OBJ: {e}")))?;

    // Does each position carry one normal? OBJ lets a position carry
    // different normals on different faces (a hard edge); such a file is
    // split into one vertex per (position, normal) pair, as Mitsuba's
    // loader does, when every corner names a normal.
    let mut position_normal: Vec<Option<u32>> = Vec::new();
    let mut normals_consistent = true;
    let mut every_corner_has_a_normal = true;
    for model in &models {
        let m = &model.mesh;
        let offset = position_normal.len();
        position_normal.resize(offset + m.positions.len() / 3, None);
        if m.normal_indices.len() != m.indices.len() {
            normals_consistent = false;
            every_corner_has_a_normal = false;
            continue;
        }
        for (&pi, &ni) in m.indices.iter().zip(&m.normal_indices) {
            if m.normals.get(ni as usize * 3..ni as usize * 3 + 3).is_none() {
                normals_consistent = false;
                every_corner_has_a_normal = false;
                continue;
            }
            let n = |i: u32| &m.normals[i as usize * 3..i as usize * 3 + 3];
            let slot = &mut position_normal[offset + pi as usize];
            match *slot {
                None => *slot = Some(ni),
                Some(old) if old == ni || n(old) == n(ni) => {}
                Some(_) => normals_consistent = false,
            }
        }
    }
    let split_normals = !normals_consistent && every_corner_has_a_normal;

    // Vertices are (position, texture coordinate) pairs once the file has
    // UVs: a seam gives one position two UVs, so it becomes two vertices,
    // whose normals still come from the position (`origin`); with hard
    // edges, (position, texture coordinate, normal) triples.
    let with_uvs = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    let split = with_uvs || split_normals;
    let mut positions: Vec<Vec3> = Vec::new();
    let mut origin: Vec<u32> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    let mut own_normals: Vec<Vec3> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut position_triangles: Vec<[u32; 3]> = Vec::new();
    let mut all_positions: Vec<Vec3> = Vec::new();
    let mut normals: Vec<Option<Vec3>> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let offset = all_positions.len();
        if offset + m.positions.len() / 3 > u32::MAX as usize {
            return Err(ParseError::new(None, "more than 2^32 vertices".into()));
        }
        all_positions.extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        normals.resize(all_positions.len(), None);
        position_triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]].map(|i| i + offset as u32)),
        );
        if split {
            let has_uv = !m.texcoords.is_empty() && m.texcoord_indices.len() == m.indices.len();
            let mut vertex_of: HashMap<(u32, u32, u32), u32> = HashMap::new();
            let mut corners = Vec::with_capacity(m.indices.len());
            for (k, &pi) in m.indices.iter().enumerate() {
                let ti = if has_uv { m.texcoord_indices[k] } else { u32::MAX };
                let ni = if split_normals { m.normal_indices[k] } else { u32::MAX };
                let key = (pi + offset as u32, ti, ni);
                let next = positions.len() as u32;
                let v = *vertex_of.entry(key).or_insert_with(|| {
                    positions.push(all_positions[key.0 as usize]);
                    origin.push(key.0);
                    // OBJ's v runs up the image; caustic's runs down.
                    let uv = m
                        .texcoords
                        .get(2 * ti as usize..2 * ti as usize + 2)
                        .map_or(Vec2::ZERO, |t| Vec2::new(t[0], 1.0 - t[1]));
                    uvs.push(uv);
                    if split_normals {
                        let n = &m.normals[3 * ni as usize..3 * ni as usize + 3];
                        own_normals.push(Vec3::new(n[0], n[1], n[2]));
                    }
                    next
                });
                corners.push(v);
            }
            if positions.len() > u32::MAX as usize {
                return Err(ParseError::new(None, "more than 2^32 vertices".into()));
            }
            triangles.extend(corners.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
        }
        if normals_consistent {
            for (&pi, &ni) in m.indices.iter().zip(&m.normal_indices) {
                let n = &m.normals[ni as usize * 3..ni as usize * 3 + 3];
                normals[offset + pi as usize] = Some(Vec3::new(n[0], n[1], n[2]));
            }
        }
    }
    let normals = if normals_consistent {
        normals.into_iter().collect::<Option<Vec<Vec3>>>()
    } else {
        None
    };
    if let Some(i) = all_positions.iter().position(|p| !p.is_finite()) {
        return Err(ParseError::new(
            None,
            format!("vertex {i} (counting from 0 in file order) has a non-finite coordinate"),
        ));
    }
    if !split {
        return Ok(Mesh::new(name, all_positions, position_triangles, normals)?);
    }
    let normals = if split_normals {
        own_normals
    } else {
        let normals = normals.unwrap_or_else(|| Mesh::angle_weighted_normals(&all_positions, &position_triangles));
        origin.iter().map(|&o| normals[o as usize]).collect()
    };
    let mesh = Mesh::new(name, positions, triangles, Some(normals))?;
    if with_uvs {
        Ok(mesh.with_uvs(uvs)?)
    } else {
        Ok(mesh)
    }
}

/// 1-based line number of byte `offset`.
fn line_of(text: &[u8], offset: usize) -> u64 {
    text[..offset].iter().filter(|&&b| b == b'\n').count() as u64 + 1
}

/// Finds the first line that explains a `tobj` error: a bad `v`/`vn`/`vt`
/// record, or a face whose vertex references do not parse or are out of range.
fn locate(text: &[u8], error: &tobj::LoadError) -> Option<Place> {
    use tobj::LoadError as E;
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    for (number, line) in text.split(|&b| b == b'\n').enumerate() {
        let mut words = line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty());
        let Some(keyword) = words.next() else { continue };
        let fields: Vec<&[u8]> = words.collect();
        let floats_ok = |min: usize| fields.len() >= min && fields.iter().all(|f| parse_f32(f).is_some());
        let here = Some(Place::Line(number as u64 + 1));
        match keyword {
            b"v" => {
                if matches!(error, E::PositionParseError) && !floats_ok(3) {
                    return here;
                }
                v += 1;
            }
            b"vt" => {
                if matches!(error, E::TexcoordParseError) && !floats_ok(1) {
                    return here;
                }
                vt += 1;
            }
            b"vn" => {
                if matches!(error, E::NormalParseError) && !floats_ok(3) {
                    return here;
                }
                vn += 1;
            }
            b"f" => {
                if fields.len() < 3 {
                    return here;
                }
                for field in &fields {
                    let parts: Vec<&[u8]> = field.split(|&b| b == b'/').collect();
                    for (k, part) in parts.iter().enumerate().take(3) {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let count = [v, vt, vn][k];
                        match parse_i64(part) {
                            Some(i) if i > 0 && i <= count => {}
                            Some(i) if i < 0 && -i <= count => {}
                            _ => return here,
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::load_mesh;

    fn load_text(text: &str) -> Result<Mesh, crate::io::MeshError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.obj");
        std::fs::write(&path, text).unwrap();
        load_mesh(&path)
    }

    #[test]
    fn groups_merged_and_polygons_triangulated() {
        let text = "# two objects\no a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
                    o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 5 6 7\n";
        let m = load_text(text).unwrap();
        assert_eq!(m.positions.len(), 7);
        assert_eq!(m.triangles.len(), 3);
        assert_eq!(m.triangles[2].map(|i| m.positions[i as usize].z), [1.0; 3]);
        assert!(m.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    }

    #[test]
    fn consistent_normals_are_used() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 1 0 0\nvn 0 1 0\nf 1//1 2//2 3//1\n";
        let m = load_text(text).unwrap();
        assert_eq!(m.normals, vec![Vec3::X, Vec3::Y, Vec3::X]);
    }

    #[test]
    fn hard_edges_split_their_vertices() {
        // Vertices 2 and 3 carry normal 1 on the first face and 2 on the second.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 1 0 0\nvn 0 1 0\n\
                    f 1//1 2//1 3//1\nf 2//2 4//2 3//2\n";
        let m = load_text(text).unwrap();
        assert_eq!(m.positions.len(), 6, "{:?}", m.positions);
        assert_eq!(m.normals, vec![Vec3::X, Vec3::X, Vec3::X, Vec3::Y, Vec3::Y, Vec3::Y]);
        assert_eq!(m.triangles, vec![[0, 1, 2], [3, 4, 5]]);
    }

    #[test]
    fn texture_coordinates_split_seams_and_flip_v() {
        // Two triangles sharing the edge 2-3, with different UVs on each side at vertex 3.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.25\n\
                    f 1/1 2/2 3/3\nf 2/2 4/4 3/1\n";
        let m = load_text(text).unwrap();
        // Vertex 3 has two UVs: five vertices in all.
        assert_eq!(m.positions.len(), 5);
        assert_eq!(m.uvs.len(), 5);
        let uv_at = |t: usize, k: usize| m.uvs[m.triangles[t][k] as usize];
        assert_eq!(uv_at(0, 0), Vec2::new(0.0, 1.0));
        assert_eq!(uv_at(0, 2), Vec2::new(0.0, 0.0));
        assert_eq!(uv_at(1, 1), Vec2::new(0.5, 0.75));
        assert_eq!(uv_at(1, 2), Vec2::new(0.0, 1.0));
        assert_eq!(
            m.positions[m.triangles[0][2] as usize],
            m.positions[m.triangles[1][2] as usize]
        );
        // A flat square: every normal is +z, seams included.
        assert!(m.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    }

    #[test]
    fn errors_are_located() {
        let e = load_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap_err();
        assert!(e.message.starts_with("line 4: invalid OBJ"), "{e}");
        let e = load_text("v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert!(e.message.starts_with("line 2: invalid OBJ"), "{e}");
    }
}
