//! Typed reads of accessors (glTF 2.0 §3.6): every element's bytes are
//! checked to lie inside its buffer view and the view inside its buffer
//! before anything is allocated, so a lying offset, stride or count is an
//! error naming the accessor, never a panic or an allocation the data does
//! not back.

use super::Ctx;
use crate::io::LoadLimits;
use crate::scene::load::SceneError;
use gltf::accessor::{DataType, Dimensions};

/// The bytes of one accessor's elements: element `i` starts at
/// `offset + i · stride` in `data`.
struct Layout<'b> {
    data: &'b [u8],
    offset: usize,
    stride: usize,
    component: DataType,
}

fn component_size(t: DataType) -> usize {
    match t {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

fn type_name(t: DataType, normalized: bool) -> String {
    let name = match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    };
    if normalized {
        format!("normalized {name}")
    } else {
        name.to_string()
    }
}

fn dimension_count(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 => 4,
        Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

impl Layout<'_> {
    /// Component `c` of element `i` as a number, normalized integers mapped
    /// to [0, 1] or [−1, 1] (glTF 2.0 §3.11, "Animations": `max(c / 127, −1)`
    /// and friends).
    fn get(&self, i: usize, c: usize, normalized: bool) -> f64 {
        let size = component_size(self.component);
        let at = self.offset + i * self.stride + c * size;
        let b = &self.data[at..at + size];
        match self.component {
            DataType::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            DataType::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            DataType::U16 => {
                let v = f64::from(u16::from_le_bytes([b[0], b[1]]));
                if normalized {
                    v / 65535.0
                } else {
                    v
                }
            }
            DataType::I16 => {
                let v = f64::from(i16::from_le_bytes([b[0], b[1]]));
                if normalized {
                    (v / 32767.0).max(-1.0)
                } else {
                    v
                }
            }
            DataType::U8 => {
                let v = f64::from(b[0]);
                if normalized {
                    v / 255.0
                } else {
                    v
                }
            }
            DataType::I8 => {
                let v = f64::from(b[0] as i8);
                if normalized {
                    (v / 127.0).max(-1.0)
                } else {
                    v
                }
            }
        }
    }
}

impl<'a> Ctx<'a> {
    /// The checked layout of `count` elements of `components` components of
    /// type `component` in buffer view `view` at `offset`.
    fn layout(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        component: DataType,
        components: usize,
        pointer: &str,
    ) -> Result<Layout<'a>, SceneError> {
        let buffers: &'a [Vec<u8>] = self.buffers;
        let view_pointer = format!("/bufferViews/{}", view.index());
        let buffer = &buffers[view.buffer().index()];
        let view_end = view
            .offset()
            .checked_add(view.length())
            .filter(|&e| e <= buffer.len())
            .ok_or_else(|| {
                self.error(
                    &view_pointer,
                    format!(
                        "bytes {}..{} + {} lie outside buffer {} ({} bytes)",
                        view.offset(),
                        view.offset(),
                        view.length(),
                        view.buffer().index(),
                        buffer.len()
                    ),
                )
            })?;
        let data = &buffer[view.offset()..view_end];
        let element = component_size(component) * components;
        let stride = view.stride().unwrap_or(element);
        if stride < element {
            return Err(self.error(
                format!("{view_pointer}/byteStride"),
                format!("stride {stride} is smaller than an element ({element} bytes)"),
            ));
        }
        if count > 0 {
            let last = (count as u128 - 1) * stride as u128 + offset as u128 + element as u128;
            if last > data.len() as u128 {
                return Err(self.error(
                    pointer,
                    format!(
                        "{count} elements of {element} bytes every {stride} from byte offset {offset} need {last} bytes; \
                         buffer view {} has {}",
                        view.index(),
                        data.len()
                    ),
                ));
            }
        }
        Ok(Layout {
            data,
            offset,
            stride,
            component,
        })
    }

    /// The values of `accessor`, `N` per element, each converted by `conv`
    /// from `f64` (exact for every component type), after checking its type
    /// against `allowed` (component type, normalized). `pointer` is where
    /// the accessor is used, for messages.
    fn values<const N: usize, T: Copy + Default>(
        &self,
        accessor: &gltf::Accessor,
        pointer: &str,
        what: &str,
        allowed: &[(DataType, bool)],
        conv: fn(f64) -> T,
    ) -> Result<Vec<[T; N]>, SceneError> {
        let at = format!("/accessors/{}", accessor.index());
        let used = format!("{pointer} (accessor {})", accessor.index());
        let n = dimension_count(accessor.dimensions());
        if n != N || matches!(accessor.dimensions(), Dimensions::Mat2) {
            return Err(self.error(
                pointer,
                format!(
                    "{what} needs {N} components per element; accessor {} has type {:?}",
                    accessor.index(),
                    accessor.dimensions()
                ),
            ));
        }
        let (component, normalized) = (accessor.data_type(), accessor.normalized());
        if !allowed.contains(&(component, normalized)) {
            let names: Vec<String> = allowed.iter().map(|&(t, n)| type_name(t, n)).collect();
            return Err(self.error(
                pointer,
                format!(
                    "{what}: accessor {} has component type {}; glTF allows {}",
                    accessor.index(),
                    type_name(component, normalized),
                    names.join(", ")
                ),
            ));
        }
        let count = accessor.count();
        let limits = LoadLimits::default();
        if count as u64 > limits.max_elements {
            return Err(self.error(
                format!("{at}/count"),
                format!("{count} elements: more than the limit of {}", limits.max_elements),
            ));
        }
        let mut out = match accessor.view() {
            Some(view) => {
                let layout = self.layout(&view, accessor.offset(), count, component, N, &used)?;
                (0..count)
                    .map(|i| std::array::from_fn(|c| conv(layout.get(i, c, normalized))))
                    .collect::<Vec<_>>()
            }
            // Without a view the elements are zeros (§3.6.2.3), replaced by sparse values.
            None => {
                if accessor.sparse().is_none() {
                    return Err(self.error(&at, "an accessor without a bufferView or sparse values"));
                }
                vec![[T::default(); N]; count]
            }
        };
        if let Some(sparse) = accessor.sparse() {
            let sp = format!("{at}/sparse");
            let k = sparse.count();
            if k > count {
                return Err(self.error(format!("{sp}/count"), format!("{k} sparse values for {count} elements")));
            }
            let indices = sparse.indices();
            let index_type = match indices.index_type() {
                gltf::accessor::sparse::IndexType::U8 => DataType::U8,
                gltf::accessor::sparse::IndexType::U16 => DataType::U16,
                gltf::accessor::sparse::IndexType::U32 => DataType::U32,
            };
            let il = self.layout(
                &indices.view(),
                indices.offset(),
                k,
                index_type,
                1,
                &format!("{sp}/indices"),
            )?;
            let values = sparse.values();
            let vl = self.layout(
                &values.view(),
                values.offset(),
                k,
                component,
                N,
                &format!("{sp}/values"),
            )?;
            for j in 0..k {
                let i = il.get(j, 0, false) as usize;
                if i >= count {
                    return Err(self.error(
                        format!("{sp}/indices"),
                        format!("sparse index {i} of entry {j} is out of range ({count} elements)"),
                    ));
                }
                out[i] = std::array::from_fn(|c| conv(vl.get(j, c, normalized)));
            }
        }
        Ok(out)
    }

    /// Floats of `accessor`, `N` per element; non-finite values refused.
    pub(super) fn floats<const N: usize>(
        &self,
        accessor: &gltf::Accessor,
        pointer: &str,
        what: &str,
        allowed: &[(DataType, bool)],
    ) -> Result<Vec<[f32; N]>, SceneError> {
        let values = self.values::<N, f32>(accessor, pointer, what, allowed, |x| x as f32)?;
        if let Some(i) = values.iter().position(|v| v.iter().any(|x| !x.is_finite())) {
            return Err(self.error(
                pointer,
                format!("{what}: element {i} of accessor {} is not finite", accessor.index()),
            ));
        }
        Ok(values)
    }

    /// Vertex indices (`UNSIGNED_BYTE`, `_SHORT` or `_INT` scalars), each
    /// checked against `vertices`.
    pub(super) fn indices(
        &self,
        accessor: &gltf::Accessor,
        pointer: &str,
        vertices: usize,
    ) -> Result<Vec<u32>, SceneError> {
        let allowed = [(DataType::U8, false), (DataType::U16, false), (DataType::U32, false)];
        // Unsigned integers of at most 32 bits: exact as f64 and as u32.
        let values = self.values::<1, u32>(accessor, pointer, "indices", &allowed, |x| x as u32)?;
        if let Some(i) = values.iter().position(|v| v[0] as usize >= vertices) {
            return Err(self.error(
                pointer,
                format!(
                    "index {i} of accessor {} is {}, but the primitive has {vertices} vertices",
                    accessor.index(),
                    values[i][0]
                ),
            ));
        }
        Ok(values.into_iter().map(|v| v[0]).collect())
    }
}
