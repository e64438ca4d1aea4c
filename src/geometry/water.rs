//! Procedural water: a height field made of a sum of sine waves (the
//! original report's "eau procédurale", §5.3), turned into a triangle mesh
//! with analytic normals.

use super::mesh::{Mesh, MeshDataError};
use crate::math::{Aabb, Vec2, Vec3, Vec3A};
use std::f32::consts::TAU;

/// One sine wave of the height field:
/// `h(x, z) = amplitude · sin(2π/wavelength · (direction · (x, z)) + phase)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    /// Height of a crest above the mean level (scene units).
    pub amplitude: f32,
    /// Distance between crests (> 0).
    pub wavelength: f32,
    /// Unit direction of travel in the (x, z) plane.
    pub direction: Vec2,
    /// Phase in radians.
    pub phase: f32,
}

/// A rectangular water surface, `size.x × size.y` centred on `center` in the
/// (x, z) plane, with mean level `center.y`, sampled on a
/// `resolution.0 × resolution.1` grid of quads.
#[derive(Clone, Debug, PartialEq)]
pub struct WaterSurface {
    /// Centre; `center.y` is the mean water level.
    pub center: Vec3A,
    /// Extent along x and z.
    pub size: Vec2,
    /// Grid cells along x and z (each ≥ 1).
    pub resolution: (u32, u32),
    /// The waves summed into the height field.
    pub waves: Vec<Wave>,
}

/// Largest grid side of a water surface (cells).
pub const MAX_WATER_RESOLUTION: u32 = 4096;

impl WaterSurface {
    /// Height above the mean level at `(x, z)`: `Σ a sin(k d·(x, z) + φ)`.
    pub fn height(&self, x: f32, z: f32) -> f32 {
        self.waves
            .iter()
            .map(|w| {
                let k = TAU / w.wavelength;
                w.amplitude * (k * (w.direction.x * x + w.direction.y * z) + w.phase).sin()
            })
            .sum()
    }

    /// Analytic gradient `(∂h/∂x, ∂h/∂z) = Σ a k cos(k d·(x, z) + φ) d`.
    pub fn gradient(&self, x: f32, z: f32) -> Vec2 {
        self.waves
            .iter()
            .map(|w| {
                let k = TAU / w.wavelength;
                w.direction * (w.amplitude * k * (k * (w.direction.x * x + w.direction.y * z) + w.phase).cos())
            })
            .sum()
    }

    /// Unit normal of the surface `y = h(x, z)` facing up: `(−∂h/∂x, 1, −∂h/∂z)`.
    pub fn normal(&self, x: f32, z: f32) -> Vec3A {
        let g = self.gradient(x, z);
        Vec3A::new(-g.x, 1.0, -g.y).normalize()
    }

    /// Highest crest above the mean level (sum of the amplitudes).
    pub fn max_amplitude(&self) -> f32 {
        self.waves.iter().map(|w| w.amplitude.abs()).sum()
    }

    /// The height field as a world-space triangle mesh. Triangles are wound
    /// counter-clockwise seen from above, so geometric normals face up (out
    /// of the water): a ray going down enters the dielectric. Vertex normals
    /// come from the analytic gradient, not from the facets.
    pub fn mesh(&self, name: &str) -> Result<Mesh, MeshDataError> {
        let (nx, nz) = self.resolution;
        let (vx, vz) = (nx as usize + 1, nz as usize + 1);
        let x0 = self.center.x - self.size.x * 0.5;
        let z0 = self.center.z - self.size.y * 0.5;
        let (dx, dz) = (self.size.x / nx as f32, self.size.y / nz as f32);
        let mut positions = Vec::with_capacity(vx * vz);
        let mut normals = Vec::with_capacity(vx * vz);
        let mut uvs = Vec::with_capacity(vx * vz);
        for i in 0..vx {
            for j in 0..vz {
                let (x, z) = (x0 + i as f32 * dx, z0 + j as f32 * dz);
                positions.push(Vec3::new(x, self.center.y + self.height(x, z), z));
                normals.push(Vec3::from(self.normal(x, z)));
                // u along +x, v along +z over the surface's extent.
                uvs.push(Vec2::new(i as f32 / nx as f32, j as f32 / nz as f32));
            }
        }
        let index = |i: usize, j: usize| (i * vz + j) as u32;
        let mut triangles = Vec::with_capacity(nx as usize * nz as usize * 2);
        for i in 0..nx as usize {
            for j in 0..nz as usize {
                // (0,0,dz) × (dx,0,dz) = (0, dx·dz, 0): facing +y.
                let (a, b, c, d) = (index(i, j), index(i, j + 1), index(i + 1, j + 1), index(i + 1, j));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Mesh::new(name, positions, triangles, Some(normals))?.with_uvs(uvs)
    }

    /// The region filled by the water for the fog: the surface's (x, z)
    /// extent, from `bottom` up to the mean level `center.y`.
    pub fn volume(&self, bottom: f32) -> Aabb {
        let half = Vec3A::new(self.size.x * 0.5, 0.0, self.size.y * 0.5);
        let lo = self.center - half;
        let hi = self.center + half;
        Aabb::new(
            Vec3A::new(lo.x, bottom.min(self.center.y), lo.z),
            Vec3A::new(hi.x, self.center.y, hi.z),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface() -> WaterSurface {
        WaterSurface {
            center: Vec3A::new(1.0, 2.0, -1.0),
            size: Vec2::new(4.0, 6.0),
            resolution: (16, 24),
            waves: vec![
                Wave {
                    amplitude: 0.1,
                    wavelength: 1.5,
                    direction: Vec2::new(0.6, 0.8),
                    phase: 0.3,
                },
                Wave {
                    amplitude: 0.05,
                    wavelength: 0.7,
                    direction: Vec2::new(-1.0, 0.0),
                    phase: 1.0,
                },
            ],
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let s = surface();
        for (x, z) in [(0.0f32, 0.0f32), (1.3, -0.7), (-2.0, 2.5)] {
            let h = 1e-3;
            let fd = Vec2::new(
                (s.height(x + h, z) - s.height(x - h, z)) / (2.0 * h),
                (s.height(x, z + h) - s.height(x, z - h)) / (2.0 * h),
            );
            assert!((fd - s.gradient(x, z)).length() < 2e-3, "{fd} {}", s.gradient(x, z));
            assert!(s.height(x, z).abs() <= s.max_amplitude() + 1e-6);
        }
    }

    #[test]
    fn mesh_faces_up_and_follows_the_height_field() {
        let s = surface();
        let m = s.mesh("water").unwrap();
        assert_eq!(m.positions.len(), 17 * 25);
        assert_eq!(m.triangles.len(), 16 * 24 * 2);
        for t in 0..m.triangles.len() {
            let [a, b, c] = m.corners(t);
            let n = (b - a).cross(c - a);
            assert!(n.y > 0.0, "triangle {t} faces down");
        }
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!((p.y - 2.0 - s.height(p.x, p.z)).abs() < 1e-5);
            assert!((Vec3A::from(*n) - s.normal(p.x, p.z)).length() < 1e-5);
        }
        let b = m.bounds();
        assert!((b.min.x + 1.0).abs() < 1e-5 && (b.max.z - 2.0).abs() < 1e-5);
        let v = s.volume(-3.0);
        assert_eq!(v.max.y, 2.0);
        assert_eq!(v.min.y, -3.0);
    }
}
