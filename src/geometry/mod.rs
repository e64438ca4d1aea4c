//! Geometry vocabulary shared by the loaders, the scene and the
//! accelerators: triangle meshes, analytic spheres, quads, disks and
//! cylinders, procedural
//! meshes, the water height field, and the preliminary hit record that every
//! accelerator returns.

pub mod generate;
pub mod mesh;
pub mod shape;
pub mod water;

pub use mesh::{Mesh, MeshDataError};
pub use shape::{Cylinder, Disk, Quad, Sphere};
pub use water::{WaterSurface, Wave};

/// The closest hit of a ray. Surface data is computed afterwards from the
/// scene (`Scene::surface_interaction`), so every backend agrees on this alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (world space; `origin + t·dir`).
    pub t: f32,
    /// Object index (`Scene::objects`).
    pub instance: u32,
    /// Triangle index within the object's mesh; 0 for analytic shapes.
    pub prim: u32,
    /// Barycentric `u` (weight of the triangle's second vertex) or the quad's first coordinate.
    pub u: f32,
    /// Barycentric `v` (weight of the third vertex) or the quad's second coordinate.
    pub v: f32,
}

/// Ray–triangle intersection test used by the in-house backends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TriangleTest {
    /// Watertight test (Woop, Benthin, Wald 2013): no ray slips between
    /// triangles that share an edge.
    Watertight,
    /// Möller–Trumbore 1997 (the original report's choice).
    MollerTrumbore,
}
