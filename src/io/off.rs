//! OFF (Geomview Object File Format), the original report's mesh format.
//!
//! ```text
//! OFF                 optional header: [ST][C][N]OFF (NOFF: per-vertex normals)
//! V F E               counts (E, the edge count, is optional and ignored)
//! x y z [nx ny nz] [colour ignored] [s t]    V lines (s t with STOFF)
//! n i0 i1 ... i(n-1) [colour ignored]                        F lines
//! ```
//! `#` starts a comment anywhere. Polygons are fan-triangulated (they are
//! assumed convex, as OFF writers produce). Vertex records are read one per
//! line, so a missing coordinate is reported on its line.

use super::source::{parse_f32, parse_i64, show, Source};
use super::{bounded_capacity, fan, LoadLimits, ParseError, Place};
use crate::geometry::Mesh;
use crate::math::{Vec2, Vec3};

/// Largest polygon accepted (vertices per face).
pub const MAX_POLYGON: u64 = 1 << 16;

/// Largest up-front reservation (items) from a header count.
const RESERVE_CAP: u64 = 1 << 20;

/// What the header line announced.
#[derive(Default)]
struct Header {
    normals: bool,
    uvs: bool,
}

/// Parses an `[ST][C][N]OFF` keyword. `Ok(None)`: not a header (the file starts with the counts).
fn header_keyword(token: &[u8], line: u64) -> Result<Option<Header>, ParseError> {
    let Some(mut prefix) = token.strip_suffix(b"OFF") else {
        return Ok(None);
    };
    let mut header = Header::default();
    if let Some(rest) = prefix.strip_prefix(b"ST") {
        header.uvs = true;
        prefix = rest;
    }
    if let Some(rest) = prefix.strip_prefix(b"C") {
        prefix = rest; // colours: skipped with the rest of the line
    }
    if let Some(rest) = prefix.strip_prefix(b"N") {
        header.normals = true;
        prefix = rest;
    }
    if !prefix.is_empty() {
        return Err(ParseError::new(
            Some(Place::Line(line)),
            format!(
                "unsupported OFF variant {} (4D and n-dimensional OFF are not supported)",
                show(token)
            ),
        ));
    }
    Ok(Some(header))
}

/// Reads a count from the header.
fn count(token: Option<&[u8]>, what: &str, line: u64, limits: &LoadLimits) -> Result<u64, ParseError> {
    let here = Some(Place::Line(line));
    let Some(token) = token else {
        return Err(ParseError::new(here, format!("missing the {what} count")));
    };
    let value = parse_i64(token).ok_or_else(|| {
        ParseError::new(
            here.clone(),
            format!("the {what} count {} is not an integer", show(token)),
        )
    })?;
    if value < 0 {
        return Err(ParseError::new(here, format!("negative {what} count {value}")));
    }
    let value = value as u64;
    if value > limits.max_elements {
        return Err(ParseError::new(
            here,
            format!(
                "the header announces {value} {}, more than the limit of {}",
                if what == "vertex" { "vertices" } else { "faces" },
                limits.max_elements
            ),
        ));
    }
    Ok(value)
}

pub(crate) fn parse(src: &mut Source, limits: &LoadLimits, name: String) -> Result<Mesh, ParseError> {
    let s = &mut src.stream;
    let Some(first) = s.token(true, true)?.map(<[u8]>::to_vec) else {
        return Err(ParseError::new(
            Some(s.here()),
            "empty file: no OFF header or counts".into(),
        ));
    };
    let header_line = s.line();
    let (header, vertex_count) = match header_keyword(&first, header_line)? {
        Some(h) => {
            if let Some(t) = s.token(false, true)? {
                if t == b"BINARY" {
                    return Err(ParseError::new(
                        Some(Place::Line(header_line)),
                        "binary OFF is not supported".into(),
                    ));
                }
                // Counts on the header line ("OFF 8 6 0"): accepted.
                let v = count(Some(t), "vertex", header_line, limits)?;
                (h, v)
            } else {
                let t = s.token(true, true)?.map(<[u8]>::to_vec);
                let line = s.line();
                (h, count(t.as_deref(), "vertex", line, limits)?)
            }
        }
        None => (Header::default(), count(Some(&first), "vertex", header_line, limits)?),
    };
    let counts_line = s.line();
    let face_count = count(s.token(false, true)?, "face", counts_line, limits)?;
    // The edge count is optional and unused, but must be a number if present.
    if let Some(t) = s.token(false, true)? {
        if parse_i64(t).is_none() {
            return Err(ParseError::new(
                Some(Place::Line(counts_line)),
                format!("the edge count {} is not an integer", show(t)),
            ));
        }
    }
    s.next_line()?;

    // The shortest vertex line is "0 0 0\n" (6 bytes), the shortest face line
    // "3 0 1 2\n" (8 bytes): a header announcing more than the file can hold is
    // wrong, and is refused before anything is reserved.
    if !src.compressed {
        let need = (vertex_count * 6 + face_count * 8).saturating_sub(1);
        if need > src.file_len {
            return Err(ParseError::new(
                Some(Place::Line(counts_line)),
                format!(
                    "the header announces {vertex_count} vertices and {face_count} faces, which need at \
                     least {need} bytes, but the file has only {} bytes (wrong counts or truncated file)",
                    src.file_len
                ),
            ));
        }
    }

    super::check_mesh_memory(vertex_count, face_count, limits, Some(Place::Line(counts_line)))?;

    let values_per_vertex = if header.normals { 6 } else { 3 };
    let mut positions = Vec::with_capacity(bounded_capacity(vertex_count, RESERVE_CAP));
    let mut normals = header
        .normals
        .then(|| Vec::with_capacity(bounded_capacity(vertex_count, RESERVE_CAP)));
    let mut uvs = header
        .uvs
        .then(|| Vec::with_capacity(bounded_capacity(vertex_count, RESERVE_CAP)));
    let mut values = [0f32; 6];
    for v in 0..vertex_count {
        for (k, slot) in values.iter_mut().take(values_per_vertex).enumerate() {
            let parsed = s.token(k == 0, true)?.map(|t| parse_f32(t).ok_or_else(|| show(t)));
            let here = Some(Place::Line(s.line()));
            *slot = match parsed {
                Some(Ok(x)) => x,
                Some(Err(found)) => {
                    return Err(ParseError::new(
                        here,
                        format!("vertex {v}: expected a number, found {found}"),
                    ))
                }
                None if k == 0 => {
                    return Err(ParseError::new(
                        here,
                        format!(
                            "unexpected end of file: vertex {v} of the {vertex_count} the header \
                             announces is missing"
                        ),
                    ))
                }
                None => {
                    return Err(ParseError::new(
                        here,
                        format!("vertex {v} has {k} values, expected {values_per_vertex}"),
                    ))
                }
            };
        }
        if let Some(bad) = values[..values_per_vertex].iter().find(|x| !x.is_finite()) {
            return Err(ParseError::new(
                Some(s.here()),
                format!("vertex {v} has a non-finite value ({bad})"),
            ));
        }
        positions.push(Vec3::new(values[0], values[1], values[2]));
        if let Some(n) = normals.as_mut() {
            n.push(Vec3::new(values[3], values[4], values[5]));
        }
        if let Some(uvs) = uvs.as_mut() {
            // `s t` are the line's last two values (a colour of 1, 3 or 4
            // values may come before them). Taken as written, as for PLY.
            let mut last = [f32::NAN; 2];
            let mut seen = 0;
            let line = s.line();
            while let Some(t) = s.token(false, true)? {
                let x = parse_f32(t).ok_or_else(|| {
                    ParseError::new(
                        Some(Place::Line(line)),
                        format!("vertex {v}: expected a number, found {}", show(t)),
                    )
                })?;
                last = [last[1], x];
                seen += 1;
            }
            if seen < 2 || !last[0].is_finite() || !last[1].is_finite() {
                return Err(ParseError::new(
                    Some(Place::Line(s.line())),
                    format!("vertex {v}: STOFF needs finite texture coordinates s t at the end of the line"),
                ));
            }
            uvs.push(Vec2::new(last[0], last[1]));
        }
        // Colours end the line: skipped.
        s.next_line()?;
    }

    let mut triangles = Vec::with_capacity(bounded_capacity(face_count, RESERVE_CAP));
    let mut polygon: Vec<u32> = Vec::with_capacity(16);
    for f in 0..face_count {
        let parsed = s.token(true, true)?.map(|t| parse_i64(t).ok_or_else(|| show(t)));
        let line = s.line();
        let here = || Some(Place::Line(line));
        let n = match parsed {
            Some(Ok(n)) => n,
            Some(Err(found)) => {
                return Err(ParseError::new(
                    here(),
                    format!("face {f}: expected a vertex count, found {found}"),
                ))
            }
            None => {
                return Err(ParseError::new(
                    here(),
                    format!(
                        "unexpected end of file: face {f} of the {face_count} the header announces \
                         is missing"
                    ),
                ))
            }
        };
        if n < 3 {
            return Err(ParseError::new(
                here(),
                format!("face {f} has {n} vertices; a face needs at least 3"),
            ));
        }
        if n as u64 > MAX_POLYGON {
            return Err(ParseError::new(
                here(),
                format!("face {f} has {n} vertices, more than the {MAX_POLYGON} supported"),
            ));
        }
        polygon.clear();
        for k in 0..n {
            let index = match s.token(false, true)?.map(|t| parse_i64(t).ok_or_else(|| show(t))) {
                Some(Ok(i)) => i,
                Some(Err(found)) => {
                    return Err(ParseError::new(
                        here(),
                        format!("face {f}: expected a vertex index, found {found}"),
                    ))
                }
                None => {
                    return Err(ParseError::new(
                        here(),
                        format!("face {f} announces {n} vertices but lists {k}"),
                    ))
                }
            };
            if index < 0 || index as u64 >= vertex_count {
                return Err(ParseError::new(
                    here(),
                    format!("face {f} uses vertex index {index}, but there are only {vertex_count} vertices"),
                ));
            }
            polygon.push(index as u32);
        }
        fan(&polygon, &mut triangles);
        s.next_line()?;
    }
    if !s.rest_is_blank(true, 1 << 20)? {
        return Err(ParseError::new(
            Some(s.here()),
            format!("unexpected data after the last of the {face_count} faces the header announces (wrong counts?)"),
        ));
    }
    let mesh = Mesh::new(name, positions, triangles, normals)?;
    Ok(match uvs {
        Some(uvs) => mesh.with_uvs(uvs)?,
        None => mesh,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::{load_mesh, LoadLimits};
    use std::io::Write;

    fn load_text(text: &str) -> Result<Mesh, crate::io::MeshError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.off");
        std::fs::write(&path, text).unwrap();
        load_mesh(&path)
    }

    #[test]
    fn stoff_reads_texture_coordinates_after_colours() {
        let m = load_text("STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0.5\n0 1 0 0.25 1\n3 0 1 2\n").unwrap();
        assert_eq!(m.uvs, vec![Vec2::ZERO, Vec2::new(1.0, 0.5), Vec2::new(0.25, 1.0)]);
        let m = load_text("STCOFF\n3 1 0\n0 0 0 1 0 0 1 0 0\n1 0 0 0 1 0 1 1 0.5\n0 1 0 0 0 1 1 0.25 1\n3 0 1 2\n")
            .unwrap();
        assert_eq!(m.uvs[1], Vec2::new(1.0, 0.5));
        let e = load_text("STOFF\n3 1 0\n0 0 0 0\n1 0 0 1 0.5\n0 1 0 0.25 1\n3 0 1 2\n").unwrap_err();
        assert!(
            e.message.contains("line 3") && e.message.contains("texture coordinates"),
            "{e}"
        );
        // Plain OFF keeps ignoring whatever follows the coordinates.
        assert!(load_text("OFF\n3 1 0\n0 0 0 7\n1 0 0 7\n0 1 0 7\n3 0 1 2\n")
            .unwrap()
            .uvs
            .is_empty());
    }

    #[test]
    fn cube_with_quads_is_triangulated() {
        let text = "OFF\n# a unit cube\n8 6 12\n\
            0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n\
            4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 2 3 7 6\n4 1 2 6 5\n4 0 4 7 3  255 0 0\n";
        let m = load_text(text).unwrap();
        assert_eq!(m.positions.len(), 8);
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.triangles[0], [0, 3, 2]);
        assert_eq!(m.triangles[1], [0, 2, 1]);
        // Computed normals point away from the centre.
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((*p - Vec3::splat(0.5)).dot(*n) > 0.0);
        }
    }

    #[test]
    fn headerless_and_counts_on_header_line() {
        let a = load_text("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        let b = load_text("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(a.positions, b.positions);
    }

    #[test]
    fn noff_normals_are_used() {
        let m = load_text("NOFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 2 0\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(m.normals, vec![Vec3::X, Vec3::Y, Vec3::Z]);
    }

    #[test]
    fn coloured_vertices_are_skipped() {
        let m = load_text("COFF\n3 1 0\n0 0 0 1 0 0 1\n1 0 0 0 1 0 1\n0 1 0 0 0 1 1\n3 0 1 2\n").unwrap();
        assert_eq!(m.positions[1], Vec3::X);
    }

    #[test]
    fn gzip_by_extension_and_by_magic() {
        let text = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let dir = tempfile::tempdir().unwrap();
        for name in ["m.off.gz", "m.off"] {
            let path = dir.path().join(name);
            let mut enc =
                flate2::write::GzEncoder::new(std::fs::File::create(&path).unwrap(), flate2::Compression::default());
            enc.write_all(text.as_bytes()).unwrap();
            enc.finish().unwrap();
            let m = load_mesh(&path).unwrap();
            assert_eq!(m.triangles, vec![[0, 1, 2]]);
        }
    }

    #[test]
    fn errors_carry_line_numbers() {
        let e = load_text("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n").unwrap_err();
        assert!(e.message.starts_with("line 4: vertex 1 has 2 values"), "{e}");
        let e = load_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n\n3 0 1 7\n").unwrap_err();
        assert!(e.message.starts_with("line 7: face 0 uses vertex index 7"), "{e}");
        let _ = LoadLimits::default();
    }
}
