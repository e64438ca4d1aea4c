//! PLY (Stanford polygon format, Turk 1994): ASCII, binary little endian and
//! binary big endian.
//!
//! Reads `element vertex` (properties `x y z`, optional `nx ny nz`; any other
//! property skipped by its size) and `element face` (a `property list`
//! named `vertex_indices` or `vertex_index`; polygons fan-triangulated). Every
//! other element is skipped record by record. Header counts are checked against
//! the file size before anything is reserved, and reservations are capped:
//! the vectors grow only as real data arrives.

use super::source::{parse_f32, parse_i64, show, ByteStream, Source};
use super::{bounded_capacity, fan, LoadLimits, ParseError, Place};
use crate::geometry::Mesh;
use crate::math::{Vec2, Vec3};

/// Largest polygon accepted (vertices per face).
pub const MAX_POLYGON: u64 = 1 << 16;

/// Largest up-front reservation (items) from a header count.
const RESERVE_CAP: u64 = 1 << 20;

/// Most header lines before `end_header`.
const MAX_HEADER_LINES: u64 = 10_000;

/// PLY scalar types (both the old and the sized names).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> u64 {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

#[derive(Clone, Debug)]
enum Property {
    Scalar { name: String, ty: Scalar },
    List { name: String, count: Scalar, item: Scalar },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    properties: Vec<Property>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
}

fn header_error(line: u64, problem: String) -> ParseError {
    ParseError::new(Some(Place::Line(line)), problem)
}

fn parse_header(s: &mut ByteStream, limits: &LoadLimits) -> Result<Header, ParseError> {
    match s.header_line()? {
        Some((_, l)) if l.trim_end() == "ply" => {}
        _ => return Err(header_error(1, "not a PLY file: the first line must be 'ply'".into())),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some((line, text)) = s.header_line()? else {
            return Err(header_error(
                s.line(),
                "the file ends inside the header (no 'end_header')".into(),
            ));
        };
        if line > MAX_HEADER_LINES {
            return Err(header_error(
                line,
                format!("no 'end_header' within {MAX_HEADER_LINES} lines"),
            ));
        }
        let words: Vec<&str> = text.split_ascii_whitespace().collect();
        match words.as_slice() {
            [] => {}
            ["end_header"] => break,
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", kind, version] => {
                if *version != "1.0" {
                    return Err(header_error(line, format!("unsupported PLY version '{version}'")));
                }
                encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::BinaryLittleEndian,
                    "binary_big_endian" => Encoding::BinaryBigEndian,
                    other => return Err(header_error(line, format!("unknown PLY format '{other}'"))),
                });
            }
            ["element", name, count] => {
                let count: i64 = count.parse().map_err(|_| {
                    header_error(line, format!("element '{name}': the count '{count}' is not an integer"))
                })?;
                if count < 0 {
                    return Err(header_error(
                        line,
                        format!("element '{name}' has a negative count {count}"),
                    ));
                }
                if count as u64 > limits.max_elements {
                    return Err(header_error(
                        line,
                        format!(
                            "element '{name}' announces {count} items, more than the limit of {}",
                            limits.max_elements
                        ),
                    ));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count: count as u64,
                    properties: Vec::new(),
                });
            }
            ["property", "list", count, item, name] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| header_error(line, "a property before any element".into()))?;
                let count_ty = Scalar::from_name(count)
                    .ok_or_else(|| header_error(line, format!("unknown property type '{count}'")))?;
                let item_ty = Scalar::from_name(item)
                    .ok_or_else(|| header_error(line, format!("unknown property type '{item}'")))?;
                if !count_ty.is_integer() {
                    return Err(header_error(
                        line,
                        format!("list '{name}' has a non-integer count type '{count}'"),
                    ));
                }
                element.properties.push(Property::List {
                    name: name.to_string(),
                    count: count_ty,
                    item: item_ty,
                });
            }
            ["property", ty, name] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| header_error(line, "a property before any element".into()))?;
                let ty =
                    Scalar::from_name(ty).ok_or_else(|| header_error(line, format!("unknown property type '{ty}'")))?;
                element.properties.push(Property::Scalar {
                    name: name.to_string(),
                    ty,
                });
            }
            _ => {
                return Err(header_error(
                    line,
                    format!(
                        "unrecognised header line '{}'",
                        text.chars().take(80).collect::<String>()
                    ),
                ))
            }
        }
    }
    let encoding = encoding.ok_or_else(|| header_error(s.line(), "the header has no 'format' line".into()))?;
    // Records of an element without properties take no bytes, so the file
    // size cannot bound their count: 2^28 empty records per element line
    // would make the loader spin for hours (found by fuzzing).
    if let Some(e) = elements.iter().find(|e| e.properties.is_empty() && e.count > 0) {
        return Err(header_error(
            s.line(),
            format!("element '{}' has {} items but no properties", e.name, e.count),
        ));
    }
    Ok(Header { encoding, elements })
}

/// Where the vertex data sits in a vertex record.
struct VertexLayout {
    /// For each property: which of x y z nx ny nz u v it fills (0..8), if any.
    slots: Vec<Option<usize>>,
    normals: bool,
    uvs: bool,
}

/// Names of the texture-coordinate properties, by slot (6: u, 7: v), as
/// the common exporters write them.
const UV_NAMES: [&[&str]; 2] = [
    &["u", "s", "texture_u", "texture_s"],
    &["v", "t", "texture_v", "texture_t"],
];

fn vertex_layout(element: &Element) -> Result<VertexLayout, ParseError> {
    let names = ["x", "y", "z", "nx", "ny", "nz"];
    let mut slots = vec![None; element.properties.len()];
    let mut found = [false; 8];
    for (i, p) in element.properties.iter().enumerate() {
        let uv = UV_NAMES.iter().position(|set| set.contains(&p.name())).map(|k| 6 + k);
        if let Some(k) = names.iter().position(|&n| n == p.name()).or(uv) {
            if found[k] {
                // A second spelling of the same coordinate: the first wins.
                continue;
            }
            if let Property::List { .. } = p {
                return Err(ParseError::new(
                    None,
                    format!("vertex property '{}' is a list, expected a number", p.name()),
                ));
            }
            slots[i] = Some(k);
            found[k] = true;
        }
    }
    if !(found[0] && found[1] && found[2]) {
        return Err(ParseError::new(
            None,
            "the vertex element lacks one of the properties x, y, z".into(),
        ));
    }
    let normals = found[3] && found[4] && found[5];
    let uvs = found[6] && found[7];
    // A partial normal (say nx ny without nz) or a lone u is ignored.
    for s in slots.iter_mut() {
        if matches!(s, Some(k) if (3..6).contains(k) && !normals || *k >= 6 && !uvs) {
            *s = None;
        }
    }
    Ok(VertexLayout { slots, normals, uvs })
}

/// Why reading one value failed.
enum ValueError {
    End,
    NotANumber(String),
    Stream(ParseError),
}

impl From<ParseError> for ValueError {
    fn from(e: ParseError) -> Self {
        Self::Stream(e)
    }
}

/// One encoding's way of reading values.
trait Values {
    fn float(&mut self, ty: Scalar) -> Result<f32, ValueError>;
    fn int(&mut self, ty: Scalar) -> Result<i64, ValueError>;
    fn skip(&mut self, ty: Scalar) -> Result<(), ValueError>;
    fn place(&self) -> Place;
    /// Data after the last element: an error, since the counts must be wrong.
    fn trailing_data(&mut self) -> Result<bool, ParseError>;
    fn end_message(&self) -> &'static str;
}

struct Ascii<'a>(&'a mut ByteStream);

impl Values for Ascii<'_> {
    #[inline]
    fn float(&mut self, _: Scalar) -> Result<f32, ValueError> {
        let t = self.0.token(true, false)?.ok_or(ValueError::End)?;
        parse_f32(t).ok_or_else(|| ValueError::NotANumber(show(t)))
    }
    #[inline]
    fn int(&mut self, _: Scalar) -> Result<i64, ValueError> {
        let t = self.0.token(true, false)?.ok_or(ValueError::End)?;
        parse_i64(t).ok_or_else(|| ValueError::NotANumber(show(t)))
    }
    #[inline]
    fn skip(&mut self, _: Scalar) -> Result<(), ValueError> {
        self.0.token(true, false)?.ok_or(ValueError::End)?;
        Ok(())
    }
    fn place(&self) -> Place {
        self.0.here()
    }
    fn trailing_data(&mut self) -> Result<bool, ParseError> {
        Ok(!self.0.rest_is_blank(false, 1 << 20)?)
    }
    fn end_message(&self) -> &'static str {
        "unexpected end of file"
    }
}

struct Binary<'a, const BIG: bool>(&'a mut ByteStream);

macro_rules! read_num {
    ($s:expr, $t:ty, $n:literal) => {{
        let b = $s.read_array::<$n>()?.ok_or(ValueError::End)?;
        if BIG {
            <$t>::from_be_bytes(b)
        } else {
            <$t>::from_le_bytes(b)
        }
    }};
}

impl<const BIG: bool> Values for Binary<'_, BIG> {
    #[inline]
    fn float(&mut self, ty: Scalar) -> Result<f32, ValueError> {
        let s = &mut *self.0;
        Ok(match ty {
            Scalar::F32 => read_num!(s, f32, 4),
            Scalar::F64 => read_num!(s, f64, 8) as f32,
            _ => self.int(ty)? as f32,
        })
    }
    #[inline]
    fn int(&mut self, ty: Scalar) -> Result<i64, ValueError> {
        let s = &mut *self.0;
        Ok(match ty {
            Scalar::I8 => read_num!(s, i8, 1) as i64,
            Scalar::U8 => read_num!(s, u8, 1) as i64,
            Scalar::I16 => read_num!(s, i16, 2) as i64,
            Scalar::U16 => read_num!(s, u16, 2) as i64,
            Scalar::I32 => read_num!(s, i32, 4) as i64,
            Scalar::U32 => read_num!(s, u32, 4) as i64,
            Scalar::F32 | Scalar::F64 => {
                let x = self.float(ty)?;
                if x.fract() != 0.0 || !x.is_finite() {
                    return Err(ValueError::NotANumber(format!("{x} (not an integer)")));
                }
                x as i64
            }
        })
    }
    #[inline]
    fn skip(&mut self, ty: Scalar) -> Result<(), ValueError> {
        let s = &mut *self.0;
        let present = match ty.size() {
            1 => s.read_array::<1>()?.is_some(),
            2 => s.read_array::<2>()?.is_some(),
            4 => s.read_array::<4>()?.is_some(),
            _ => s.read_array::<8>()?.is_some(),
        };
        if present {
            Ok(())
        } else {
            Err(ValueError::End)
        }
    }
    fn place(&self) -> Place {
        Place::Byte(self.0.offset())
    }
    fn trailing_data(&mut self) -> Result<bool, ParseError> {
        self.0.has_more()
    }
    fn end_message(&self) -> &'static str {
        "truncated binary data: the file ends"
    }
}

/// Everything the body parse produces.
struct Body {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
}

/// Names the record being read, for messages.
fn record(element: &Element, index: u64) -> String {
    format!("{} {index} of {}", element.name, element.count)
}

fn value_error(v: &impl Values, e: ValueError, element: &Element, index: u64) -> ParseError {
    match e {
        ValueError::Stream(e) => e,
        ValueError::End => ParseError::new(
            Some(v.place()),
            format!("{} in {}", v.end_message(), record(element, index)),
        ),
        ValueError::NotANumber(found) => ParseError::new(
            Some(v.place()),
            format!("{}: expected a number, found {found}", record(element, index)),
        ),
    }
}

fn parse_body<V: Values>(v: &mut V, header: &Header) -> Result<Body, ParseError> {
    let vertex = header.elements.iter().find(|e| e.name == "vertex");
    let face = header.elements.iter().find(|e| e.name == "face");
    let (Some(vertex), Some(face)) = (vertex, face) else {
        return Err(ParseError::new(
            None,
            "the header needs a 'vertex' and a 'face' element".into(),
        ));
    };
    let layout = vertex_layout(vertex)?;
    let index_list = face
        .properties
        .iter()
        .position(|p| matches!(p, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index"))
        .ok_or_else(|| {
            ParseError::new(
                None,
                "the face element has no 'vertex_indices' (or 'vertex_index') list".into(),
            )
        })?;
    if let Property::List { item, .. } = face.properties[index_list] {
        if !item.is_integer() {
            return Err(ParseError::new(
                None,
                "face vertex indices have a non-integer type".into(),
            ));
        }
    }
    let vertex_count = vertex.count;
    let mut body = Body {
        positions: Vec::with_capacity(bounded_capacity(vertex_count, RESERVE_CAP)),
        normals: layout
            .normals
            .then(|| Vec::with_capacity(bounded_capacity(vertex_count, RESERVE_CAP))),
        uvs: layout
            .uvs
            .then(|| Vec::with_capacity(bounded_capacity(vertex_count, RESERVE_CAP))),
        triangles: Vec::with_capacity(bounded_capacity(face.count, RESERVE_CAP)),
    };
    let mut polygon: Vec<u32> = Vec::with_capacity(16);

    for element in &header.elements {
        let is_vertex = std::ptr::eq(element, vertex);
        let is_face = std::ptr::eq(element, face);
        for index in 0..element.count {
            let fail = |v: &V, e| value_error(v, e, element, index);
            if is_vertex {
                let mut values = [0f32; 8];
                for (p, slot) in element.properties.iter().zip(&layout.slots) {
                    match (p, slot) {
                        (Property::Scalar { ty, .. }, Some(k)) => values[*k] = v.float(*ty).map_err(|e| fail(v, e))?,
                        (Property::Scalar { ty, .. }, None) => v.skip(*ty).map_err(|e| fail(v, e))?,
                        (Property::List { count, item, .. }, _) => {
                            skip_list(v, *count, *item).map_err(|e| fail(v, e))?
                        }
                    }
                }
                let used = [
                    true,
                    true,
                    true,
                    layout.normals,
                    layout.normals,
                    layout.normals,
                    layout.uvs,
                    layout.uvs,
                ];
                if let Some(bad) = values
                    .iter()
                    .zip(used)
                    .find(|(x, u)| *u && !x.is_finite())
                    .map(|(x, _)| x)
                {
                    return Err(ParseError::new(
                        Some(v.place()),
                        format!("{} has a non-finite value ({bad})", record(element, index)),
                    ));
                }
                body.positions.push(Vec3::new(values[0], values[1], values[2]));
                if let Some(n) = body.normals.as_mut() {
                    n.push(Vec3::new(values[3], values[4], values[5]));
                }
                // PLY's texture coordinates are taken as written (as Mitsuba does).
                if let Some(uv) = body.uvs.as_mut() {
                    uv.push(Vec2::new(values[6], values[7]));
                }
            } else if is_face {
                for (k, p) in element.properties.iter().enumerate() {
                    match p {
                        Property::List { count, item, .. } if k == index_list => {
                            let n = v.int(*count).map_err(|e| fail(v, e))?;
                            if n < 3 {
                                return Err(ParseError::new(
                                    Some(v.place()),
                                    format!("{} has {n} vertices; a face needs at least 3", record(element, index)),
                                ));
                            }
                            if n as u64 > MAX_POLYGON {
                                return Err(ParseError::new(
                                    Some(v.place()),
                                    format!(
                                        "{} has {n} vertices, more than the {MAX_POLYGON} supported",
                                        record(element, index)
                                    ),
                                ));
                            }
                            polygon.clear();
                            for _ in 0..n {
                                let i = v.int(*item).map_err(|e| fail(v, e))?;
                                if i < 0 || i as u64 >= vertex_count {
                                    return Err(ParseError::new(
                                        Some(v.place()),
                                        format!(
                                            "{} uses vertex index {i}, but there are only \
                                             {vertex_count} vertices",
                                            record(element, index)
                                        ),
                                    ));
                                }
                                polygon.push(i as u32);
                            }
                            fan(&polygon, &mut body.triangles);
                        }
                        Property::List { count, item, .. } => skip_list(v, *count, *item).map_err(|e| fail(v, e))?,
                        Property::Scalar { ty, .. } => v.skip(*ty).map_err(|e| fail(v, e))?,
                    }
                }
            } else {
                for p in &element.properties {
                    match p {
                        Property::List { count, item, .. } => skip_list(v, *count, *item).map_err(|e| fail(v, e))?,
                        Property::Scalar { ty, .. } => v.skip(*ty).map_err(|e| fail(v, e))?,
                    }
                }
            }
        }
    }
    if v.trailing_data()? {
        return Err(ParseError::new(
            Some(v.place()),
            "unexpected data after the last element the header announces (wrong counts?)".into(),
        ));
    }
    Ok(body)
}

fn skip_list<V: Values>(v: &mut V, count: Scalar, item: Scalar) -> Result<(), ValueError> {
    let n = v.int(count)?;
    if n < 0 {
        return Err(ValueError::NotANumber(format!("{n} (a negative list length)")));
    }
    for _ in 0..n {
        v.skip(item)?;
    }
    Ok(())
}

/// The fewest bytes a record of `element` can take: a header whose counts
/// need more than the file holds is refused before any reservation.
fn min_record_bytes(element: &Element, encoding: Encoding) -> u64 {
    let is_face = element.name == "face";
    element
        .properties
        .iter()
        .map(|p| {
            let indexed = is_face && matches!(p.name(), "vertex_indices" | "vertex_index");
            match (p, encoding) {
                // "0 " per ASCII value; a face list holds at least 3 indices.
                (Property::Scalar { .. }, Encoding::Ascii) => 2,
                (Property::List { .. }, Encoding::Ascii) => 2 + if indexed { 6 } else { 0 },
                (Property::Scalar { ty, .. }, _) => ty.size(),
                (Property::List { count, item, .. }, _) => count.size() + if indexed { 3 * item.size() } else { 0 },
            }
        })
        .sum()
}

pub(crate) fn parse(src: &mut Source, limits: &LoadLimits, name: String) -> Result<Mesh, ParseError> {
    let header = parse_header(&mut src.stream, limits)?;
    if !src.compressed {
        let available = src.file_len.saturating_sub(src.stream.offset());
        let mut need: u128 = 0;
        for e in &header.elements {
            need += u128::from(e.count) * u128::from(min_record_bytes(e, header.encoding));
        }
        // ASCII: the last value needs no separator.
        if header.encoding == Encoding::Ascii {
            need = need.saturating_sub(1);
        }
        if need > u128::from(available) {
            let counts: Vec<String> = header
                .elements
                .iter()
                .map(|e| format!("{} {}", e.count, e.name))
                .collect();
            return Err(ParseError::new(
                Some(Place::Byte(src.stream.offset())),
                format!(
                    "the header announces {} elements, which need at least {need} bytes, but only \
                     {available} bytes follow the header (wrong counts or truncated file)",
                    counts.join(", ")
                ),
            ));
        }
    }
    let count_of = |name: &str| header.elements.iter().find(|e| e.name == name).map_or(0, |e| e.count);
    super::check_mesh_memory(
        count_of("vertex"),
        count_of("face"),
        limits,
        Some(Place::Byte(src.stream.offset())),
    )?;
    let s = &mut src.stream;
    let body = match header.encoding {
        Encoding::Ascii => parse_body(&mut Ascii(s), &header)?,
        Encoding::BinaryLittleEndian => parse_body(&mut Binary::<false>(s), &header)?,
        Encoding::BinaryBigEndian => parse_body(&mut Binary::<true>(s), &header)?,
    };
    let mesh = Mesh::new(name, body.positions, body.triangles, body.normals)?;
    Ok(match body.uvs {
        Some(uvs) => mesh.with_uvs(uvs)?,
        None => mesh,
    })
}

/// Writes `mesh` as a binary little-endian PLY: positions, normals unless
/// they are the ones the reader computes from the triangles (given normals
/// are normalised again on reading), texture coordinates when present, and
/// the triangles. Read back with [`parse`], the mesh is the same, tangents
/// aside (PLY holds none).
pub fn write_binary(w: &mut impl std::io::Write, mesh: &Mesh) -> std::io::Result<()> {
    let computed = Mesh::new("", mesh.positions.clone(), mesh.triangles.clone(), None)
        .map(|m| m.normals == mesh.normals)
        .unwrap_or(false);
    let normals = !computed;
    let uvs = !mesh.uvs.is_empty();
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by caustic\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n",
        mesh.positions.len()
    );
    if normals {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if uvs {
        header += "property float u\nproperty float v\n";
    }
    header += &format!(
        "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.triangles.len()
    );
    w.write_all(header.as_bytes())?;
    let mut record = Vec::with_capacity(32);
    for (i, p) in mesh.positions.iter().enumerate() {
        record.clear();
        let mut put = |x: f32| record.extend_from_slice(&x.to_le_bytes());
        p.to_array().into_iter().for_each(&mut put);
        if normals {
            mesh.normals[i].to_array().into_iter().for_each(&mut put);
        }
        if uvs {
            mesh.uvs[i].to_array().into_iter().for_each(&mut put);
        }
        w.write_all(&record)?;
    }
    for t in &mesh.triangles {
        record.clear();
        record.push(3u8);
        for i in t {
            record.extend_from_slice(&i.to_le_bytes());
        }
        w.write_all(&record)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::load_mesh;

    /// Writes a binary PLY of a square (two triangles as one quad) with an
    /// extra property of every scalar type in the vertex and face records.
    fn binary_square(big: bool, normals: bool) -> Vec<u8> {
        let mut out = String::from("ply\n");
        out += if big {
            "format binary_big_endian 1.0\n"
        } else {
            "format binary_little_endian 1.0\n"
        };
        out += "comment test\nelement vertex 4\nproperty double x\nproperty float y\n\
                property char c\nproperty float z\n";
        if normals {
            out += "property float nx\nproperty float ny\nproperty float nz\n";
        }
        out += "property ushort u\nproperty list uchar int extra\n";
        out += "element face 1\nproperty uint8 flags\nproperty list uchar uint vertex_indices\n\
                property int16 tag\nelement edge 1\nproperty int vertex1\nproperty uint vertex2\n\
                end_header\n";
        let mut b = out.into_bytes();
        fn put<const N: usize>(b: &mut Vec<u8>, le: [u8; N], big: bool) {
            if big {
                b.extend(le.iter().rev());
            } else {
                b.extend(le);
            }
        }
        let corners: [[f64; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        for (i, [x, y]) in corners.iter().enumerate() {
            put(&mut b, x.to_le_bytes(), big);
            put(&mut b, (*y as f32).to_le_bytes(), big);
            b.push(0xff);
            put(&mut b, 2.0f32.to_le_bytes(), big);
            if normals {
                for c in [0.0f32, 0.0, 3.0] {
                    put(&mut b, c.to_le_bytes(), big);
                }
            }
            put(&mut b, 7u16.to_le_bytes(), big);
            b.push(i as u8); // list length i
            for k in 0..i {
                put(&mut b, (k as i32).to_le_bytes(), big);
            }
        }
        b.push(1);
        b.push(4);
        for i in [0u32, 1, 2, 3] {
            put(&mut b, i.to_le_bytes(), big);
        }
        put(&mut b, (-5i16).to_le_bytes(), big);
        put(&mut b, 0i32.to_le_bytes(), big);
        put(&mut b, 1u32.to_le_bytes(), big);
        b
    }

    fn load_bytes(name: &str, bytes: &[u8]) -> Result<Mesh, crate::io::MeshError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        load_mesh(&path)
    }

    #[test]
    fn binary_little_and_big_endian() {
        for big in [false, true] {
            for normals in [false, true] {
                let m = load_bytes("sq.ply", &binary_square(big, normals)).unwrap();
                assert_eq!(m.positions.len(), 4);
                assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 2.0));
                assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
                // Given normals (0,0,3) are normalised; computed ones face +z
                // for this counter-clockwise square.
                assert!(m.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
            }
        }
    }

    #[test]
    fn ascii_with_normals_and_other_elements() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
            property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
            property uchar red\nelement material 1\nproperty list uchar float k\n\
            element face 1\nproperty list uchar int vertex_index\nend_header\n\
            0 0 0 1 0 0 255\n1 0 0 0 1 0 0\n0 1 0 0 0 1 9\n3 0.5 0.5 0.5\n3 0 1 2\n";
        let m = load_bytes("t.ply", text.as_bytes()).unwrap();
        assert_eq!(m.normals, vec![Vec3::X, Vec3::Y, Vec3::Z]);
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn texture_coordinates_under_their_common_names() {
        for (u, v) in [
            ("u", "v"),
            ("s", "t"),
            ("texture_u", "texture_v"),
            ("texture_s", "texture_t"),
        ] {
            let text = format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                 property float z\nproperty float {u}\nproperty float {v}\n\
                 element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                 0 0 0 0 0\n1 0 0 1 0.25\n0 1 0 0.5 1\n3 0 1 2\n"
            );
            let m = load_bytes("t.ply", text.as_bytes()).unwrap();
            assert_eq!(
                m.uvs,
                vec![Vec2::ZERO, Vec2::new(1.0, 0.25), Vec2::new(0.5, 1.0)],
                "{u} {v}"
            );
        }
        // A lone u is ignored.
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
            property float z\nproperty float u\nelement face 1\nproperty list uchar int vertex_indices\n\
            end_header\n0 0 0 0\n1 0 0 1\n0 1 0 0.5\n3 0 1 2\n";
        assert!(load_bytes("t.ply", text.as_bytes()).unwrap().uvs.is_empty());
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
            property float z\nproperty float u\nproperty float v\nelement face 1\n\
            property list uchar int vertex_indices\nend_header\n0 0 0 0 nan\n1 0 0 1 0\n0 1 0 0.5 1\n3 0 1 2\n";
        let e = load_bytes("t.ply", text.as_bytes()).unwrap_err();
        assert!(e.message.contains("non-finite"), "{e}");
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
            property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
            0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n";
        let e = load_bytes("t.ply", text.as_bytes()).unwrap_err();
        assert!(e.message.starts_with("line 13: face 0 of 1 uses vertex index 3"), "{e}");
    }

    #[test]
    fn binary_truncation_names_the_byte() {
        let bytes = binary_square(false, false);
        // Cut inside the vertex data but keep the header intact: the size
        // check refuses it before parsing.
        let cut = &bytes[..bytes.len() - 40];
        let e = load_bytes("t.ply", cut).unwrap_err();
        assert!(e.message.contains("bytes follow the header"), "{e}");
    }

    #[test]
    fn written_meshes_read_back_the_same() {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.1),
            Vec3::new(0.0, 1.0, 0.3),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        let triangles = vec![[0, 1, 2], [2, 1, 3]];
        let computed = Mesh::new("m", positions.clone(), triangles.clone(), None).unwrap();
        let given = Mesh::new("m", positions, triangles, Some(vec![Vec3::Z; 4]))
            .unwrap()
            .with_uvs(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(0.0, 1.0),
                Vec2::new(0.25, 0.5),
            ])
            .unwrap();
        for mesh in [computed, given] {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("m.ply");
            let mut bytes = Vec::new();
            write_binary(&mut bytes, &mesh).unwrap();
            std::fs::write(&path, bytes).unwrap();
            let again = load_mesh(&path).unwrap();
            assert_eq!(again.positions, mesh.positions);
            assert_eq!(again.normals, mesh.normals);
            assert_eq!(again.triangles, mesh.triangles);
            assert_eq!(again.uvs, mesh.uvs);
        }
    }
}
