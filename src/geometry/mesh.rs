//! Triangle meshes in object space, shared by `Arc` between the objects that use them.

use crate::math::{Aabb, Vec2, Vec3, Vec3A, Vec4};
use rayon::prelude::*;
use thiserror::Error;

/// A triangle mesh with per-vertex normals (computed when the file has none).
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Where it came from (a file path, or the generator's name): used in messages.
    pub name: String,
    /// Vertex positions, object space.
    pub positions: Vec<Vec3>,
    /// Unit per-vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Vertex indices of each triangle, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Texture coordinates, one per position, or none (`v = 0` at an
    /// image's top row, as in glTF and Mitsuba).
    pub uvs: Vec<Vec2>,
    /// Unit tangents along increasing `u` with the bitangent's sign in `w`
    /// (glTF's `TANGENT`), one per position, or none.
    pub tangents: Vec<Vec4>,
}

/// What is wrong with a mesh's data (the loaders add the file and place).
#[derive(Debug, Error, PartialEq)]
pub enum MeshDataError {
    /// A vertex coordinate or normal component is NaN or infinite.
    #[error("vertex {0} has a non-finite coordinate")]
    NonFiniteVertex(usize),
    /// A triangle names a vertex that does not exist.
    #[error("face {face} uses vertex index {index}, but there are only {count} vertices")]
    IndexOutOfRange {
        /// Triangle number.
        face: usize,
        /// The bad index.
        index: u64,
        /// Number of vertices.
        count: usize,
    },
    /// The normal array does not match the vertex array.
    #[error("{normals} normals for {vertices} vertices")]
    NormalCount {
        /// Normals given.
        normals: usize,
        /// Vertices given.
        vertices: usize,
    },
    /// No triangle at all.
    #[error("the mesh has no faces")]
    Empty,
    /// The texture-coordinate or tangent array does not match the vertex array.
    #[error("{given} {what} for {vertices} vertices")]
    AttributeCount {
        /// `"texture coordinates"` or `"tangents"`.
        what: &'static str,
        /// Values given.
        given: usize,
        /// Vertices.
        vertices: usize,
    },
    /// A texture coordinate or tangent is NaN or infinite.
    #[error("vertex {1} has a non-finite {0}")]
    NonFiniteAttribute(&'static str, usize),
}

impl Mesh {
    /// Builds a validated mesh. `normals = None` computes angle-weighted vertex
    /// normals; given normals are normalised (zero ones are recomputed).
    /// Degenerate (zero-area) triangles are kept: they are legal and never hit.
    pub fn new(
        name: impl Into<String>,
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        normals: Option<Vec<Vec3>>,
    ) -> Result<Self, MeshDataError> {
        if triangles.is_empty() {
            return Err(MeshDataError::Empty);
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(MeshDataError::NonFiniteVertex(i));
        }
        let count = positions.len();
        for (face, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= count) {
                return Err(MeshDataError::IndexOutOfRange {
                    face,
                    index: index as u64,
                    count,
                });
            }
        }
        let computed = Self::angle_weighted_normals(&positions, &triangles);
        let normals = match normals {
            None => computed,
            Some(n) => {
                if n.len() != count {
                    return Err(MeshDataError::NormalCount {
                        normals: n.len(),
                        vertices: count,
                    });
                }
                if let Some(i) = n.iter().position(|v| !v.is_finite()) {
                    return Err(MeshDataError::NonFiniteVertex(i));
                }
                n.iter()
                    .zip(&computed)
                    .map(|(&given, &fallback)| given.try_normalize().unwrap_or(fallback))
                    .collect()
            }
        };
        Ok(Self {
            name: name.into(),
            positions,
            normals,
            triangles,
            uvs: Vec::new(),
            tangents: Vec::new(),
        })
    }

    /// Adds texture coordinates, one per vertex.
    pub fn with_uvs(mut self, uvs: Vec<Vec2>) -> Result<Self, MeshDataError> {
        if uvs.len() != self.positions.len() {
            return Err(MeshDataError::AttributeCount {
                what: "texture coordinates",
                given: uvs.len(),
                vertices: self.positions.len(),
            });
        }
        if let Some(i) = uvs.iter().position(|v| !v.is_finite()) {
            return Err(MeshDataError::NonFiniteAttribute("texture coordinate", i));
        }
        self.uvs = uvs;
        Ok(self)
    }

    /// Adds tangents (`xyz` along increasing `u`, `w` = ±1 the bitangent's
    /// sign), one per vertex; `xyz` is normalised.
    pub fn with_tangents(mut self, tangents: Vec<Vec4>) -> Result<Self, MeshDataError> {
        if tangents.len() != self.positions.len() {
            return Err(MeshDataError::AttributeCount {
                what: "tangents",
                given: tangents.len(),
                vertices: self.positions.len(),
            });
        }
        if let Some(i) = tangents.iter().position(|v| !v.is_finite()) {
            return Err(MeshDataError::NonFiniteAttribute("tangent", i));
        }
        self.tangents = tangents
            .into_iter()
            .map(|t| {
                let xyz = t.truncate().normalize_or_zero();
                Vec4::from((xyz, if t.w < 0.0 { -1.0 } else { 1.0 }))
            })
            .collect();
        Ok(self)
    }

    /// Texture coordinates of triangle `i`'s corners; without UVs `(0,0),
    /// (1,0), (0,1)`, so that `(u, v)` are the barycentrics (Mitsuba's
    /// parametrisation of a mesh without texture coordinates).
    #[inline]
    pub fn corner_uvs(&self, i: usize) -> [Vec2; 3] {
        if self.uvs.is_empty() {
            [Vec2::ZERO, Vec2::X, Vec2::Y]
        } else {
            self.triangles[i].map(|v| self.uvs[v as usize])
        }
    }

    /// Per-vertex normals weighted by the angle of each incident corner
    /// (Thürmer & Wüthrich 1998): independent of how faces are tessellated.
    /// Vertices with no (non-degenerate) face get +z.
    pub fn angle_weighted_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
        // The corner weights (the costly part: three angles per face) in
        // parallel; the scatter into vertices stays serial and in face order,
        // so the sums do not depend on the number of threads.
        let corners: Vec<[Vec3; 3]> = triangles
            .par_iter()
            .map(|tri| {
                let p = tri.map(|i| positions[i as usize]);
                let Some(n) = (p[1] - p[0]).cross(p[2] - p[0]).try_normalize() else {
                    return [Vec3::ZERO; 3];
                };
                std::array::from_fn(|k| {
                    let e1 = (p[(k + 1) % 3] - p[k]).try_normalize();
                    let e2 = (p[(k + 2) % 3] - p[k]).try_normalize();
                    match (e1, e2) {
                        // atan2(|e1×e2|, e1·e2) is the corner angle, accurate near 0 and π.
                        (Some(e1), Some(e2)) => n * e1.cross(e2).length().atan2(e1.dot(e2)),
                        _ => Vec3::ZERO,
                    }
                })
            })
            .collect();
        let mut acc = vec![Vec3::ZERO; positions.len()];
        for (tri, w) in triangles.iter().zip(&corners) {
            for k in 0..3 {
                acc[tri[k] as usize] += w[k];
            }
        }
        acc.into_par_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Z))
            .collect()
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn corners(&self, i: usize) -> [Vec3A; 3] {
        self.triangles[i].map(|v| Vec3A::from(self.positions[v as usize]))
    }

    /// Bounds of the vertices that faces use.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().map(|&p| Vec3A::from(p)))
    }

    /// Bytes held by the vertex attribute and index arrays.
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * 24 + self.uvs.len() * 8 + self.tangents.len() * 16 + self.triangles.len() * 12
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (p, t)
    }

    #[test]
    fn normals_point_outwards() {
        let (p, t) = tetra();
        let m = Mesh::new("tetra", p, t, None).unwrap();
        let c = Vec3::splat(0.25);
        for (pos, n) in m.positions.iter().zip(&m.normals) {
            assert!((*pos - c).dot(*n) > 0.0);
            assert!((n.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn bad_data_is_rejected() {
        let (p, _) = tetra();
        assert_eq!(
            Mesh::new("x", p.clone(), vec![[0, 1, 9]], None).unwrap_err(),
            MeshDataError::IndexOutOfRange {
                face: 0,
                index: 9,
                count: 4
            }
        );
        let mut nan = p.clone();
        nan[2].y = f32::NAN;
        assert_eq!(
            Mesh::new("x", nan, vec![[0, 1, 2]], None).unwrap_err(),
            MeshDataError::NonFiniteVertex(2)
        );
        assert_eq!(Mesh::new("x", p, vec![], None).unwrap_err(), MeshDataError::Empty);
    }
}
