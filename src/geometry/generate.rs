//! Procedural meshes: test meshes the project always has (no download), the
//! star prism of the original report's Cornell box, and height fields.
//! Every generator produces counter-clockwise triangles seen from outside.

use crate::geometry::Mesh;
use crate::math::Vec3;
use std::collections::HashMap;
use std::f32::consts::{PI, TAU};
use std::io::Write;
use std::path::Path;

/// Most icosphere subdivisions (8 gives 1,310,720 triangles).
pub const MAX_ICOSPHERE_SUBDIVISIONS: u32 = 8;

/// The star prism shipped as `scenes/meshes/star.off`: five points, tip
/// radius 1, notch radius 0.382 (the regular pentagram's ratio), depth 0.3.
pub fn cornell_star() -> Mesh {
    star_prism(5, 1.0, 0.382, 0.3)
}

fn build(name: &str, positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, normals: Option<Vec<Vec3>>) -> Mesh {
    // The generators produce finite positions and in-range indices by construction.
    Mesh::new(name, positions, triangles, normals).expect("generated meshes are valid")
}

/// A unit sphere: an icosahedron whose faces are split in four
/// `subdivisions` times (clamped to [`MAX_ICOSPHERE_SUBDIVISIONS`]), new
/// vertices pushed onto the sphere. Normals are the exact sphere normals.
pub fn icosphere(subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| Vec3::from(p).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions.min(MAX_ICOSPHERE_SUBDIVISIONS) {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let m = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(m);
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let normals = positions.clone();
    build(
        &format!("icosphere({subdivisions})"),
        positions,
        triangles,
        Some(normals),
    )
}

/// A torus around the y axis: ring radius `major`, tube radius `minor`,
/// `nu` segments around the ring and `nv` around the tube (each at least 3).
/// Normals are the exact torus normals.
pub fn torus(major: f32, minor: f32, nu: u32, nv: u32) -> Mesh {
    let (nu, nv) = (nu.max(3), nv.max(3));
    let mut positions = Vec::with_capacity((nu * nv) as usize);
    let mut normals = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let u = TAU * i as f32 / nu as f32;
        for j in 0..nv {
            let v = TAU * j as f32 / nv as f32;
            let n = Vec3::new(v.cos() * u.cos(), v.sin(), v.cos() * u.sin());
            positions.push(Vec3::new(u.cos(), 0.0, u.sin()) * major + n * minor);
            normals.push(n);
        }
    }
    let index = |i: u32, j: u32| (i % nu) * nv + (j % nv);
    let mut triangles = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
            // u turns from +x towards +z (clockwise seen from +y) and v turns
            // outward-then-up, so (a, d, c) and (a, c, b) face outward.
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    build(
        &format!("torus({major}, {minor}, {nu}, {nv})"),
        positions,
        triangles,
        Some(normals),
    )
}

/// A closed star-shaped prism: a star with `points` tips (at least 2) of
/// radius `outer_radius` and notches of radius `inner_radius`, in the xy plane
/// with a tip on +y, extruded along z from `-height/2` to `+height/2`. Caps
/// are fans from their centres; vertices are shared between caps and sides,
/// so the mesh is closed and every edge has exactly two faces.
pub fn star_prism(points: u32, outer_radius: f32, inner_radius: f32, height: f32) -> Mesh {
    let points = points.max(2);
    let ring = 2 * points;
    let half = height / 2.0;
    let mut positions = vec![Vec3::new(0.0, 0.0, half), Vec3::new(0.0, 0.0, -half)];
    // Ring k (counter-clockwise seen from +z): front vertex 2 + 2k, back 3 + 2k.
    for k in 0..ring {
        let angle = PI / 2.0 + PI * k as f32 / points as f32;
        let r = if k % 2 == 0 { outer_radius } else { inner_radius };
        let (x, y) = (r * angle.cos(), r * angle.sin());
        positions.push(Vec3::new(x, y, half));
        positions.push(Vec3::new(x, y, -half));
    }
    let front = |k: u32| 2 + 2 * (k % ring);
    let back = |k: u32| 3 + 2 * (k % ring);
    let mut triangles = Vec::with_capacity(4 * ring as usize);
    for k in 0..ring {
        triangles.push([0, front(k), front(k + 1)]); // normal +z
        triangles.push([1, back(k + 1), back(k)]); // normal -z
                                                   // Side quad: for a counter-clockwise outline, (front_k, back_k,
                                                   // back_k+1) has normal (d.y, -d.x, 0) with d the edge: outward.
        triangles.push([front(k), back(k), back(k + 1)]);
        triangles.push([front(k), back(k + 1), front(k + 1)]);
    }
    build(
        &format!("star_prism({points}, {outer_radius}, {inner_radius}, {height})"),
        positions,
        triangles,
        None,
    )
}

/// A height field over the xz plane: `nx` × `nz` cells (each at least 1)
/// covering `[-size_x/2, size_x/2] × [-size_z/2, size_z/2]`, vertex heights
/// `y = height(x, z)`; triangles face +y. Normals are computed (angle-weighted).
/// Non-finite heights are replaced by 0.
pub fn heightfield(nx: u32, nz: u32, size_x: f32, size_z: f32, height: impl Fn(f32, f32) -> f32) -> Mesh {
    let (nx, nz) = (nx.max(1), nz.max(1));
    let mut positions = Vec::with_capacity(((nx + 1) * (nz + 1)) as usize);
    for j in 0..=nz {
        let z = size_z * (j as f32 / nz as f32 - 0.5);
        for i in 0..=nx {
            let x = size_x * (i as f32 / nx as f32 - 0.5);
            let y = height(x, z);
            positions.push(Vec3::new(x, if y.is_finite() { y } else { 0.0 }, z));
        }
    }
    let index = |i: u32, j: u32| j * (nx + 1) + i;
    let mut triangles = Vec::with_capacity((2 * nx * nz) as usize);
    for j in 0..nz {
        for i in 0..nx {
            let (a, b, c, d) = (index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
            // x to the right, z towards the viewer below: (a, d, c) turns
            // counter-clockwise seen from +y.
            triangles.push([a, d, c]);
            triangles.push([a, c, b]);
        }
    }
    build(&format!("heightfield({nx}x{nz})"), positions, triangles, None)
}

/// A flat grid: [`heightfield`] at `y = 0`.
pub fn grid(nx: u32, nz: u32, size_x: f32, size_z: f32) -> Mesh {
    heightfield(nx, nz, size_x, size_z, |_, _| 0.0)
}

/// Writes a mesh as OFF (positions in shortest round-trip notation, so
/// reading it back gives the same bits), atomically: temp file, then rename.
pub fn write_off(mesh: &Mesh, path: &Path) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mut file = tempfile::NamedTempFile::new_in(dir)?;
    {
        let mut out = std::io::BufWriter::new(file.as_file_mut());
        writeln!(out, "OFF")?;
        writeln!(out, "# {} (generated by caustic::geometry::generate)", mesh.name)?;
        writeln!(out, "{} {} 0", mesh.positions.len(), mesh.triangles.len())?;
        for p in &mesh.positions {
            writeln!(out, "{} {} {}", p.x, p.y, p.z)?;
        }
        for [a, b, c] in &mesh.triangles {
            writeln!(out, "3 {a} {b} {c}")?;
        }
        out.flush()?;
    }
    file.as_file().sync_all()?;
    file.persist(path).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    /// Signed volume (divergence theorem): positive iff the winding faces out.
    fn signed_volume(m: &Mesh) -> f32 {
        (0..m.triangles.len())
            .map(|i| {
                let [a, b, c] = m.corners(i).map(Vec3::from);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// Every directed edge once, and its reverse once: closed and consistently wound.
    fn assert_closed(m: &Mesh) {
        let mut edges = HashSet::new();
        for t in &m.triangles {
            for k in 0..3 {
                assert!(edges.insert((t[k], t[(k + 1) % 3])), "edge used twice in one direction");
            }
        }
        for &(a, b) in &edges {
            assert!(edges.contains(&(b, a)), "open edge {a}-{b}");
        }
    }

    fn assert_faces_agree_with_normals(m: &Mesh) {
        for (i, t) in m.triangles.iter().enumerate() {
            let [a, b, c] = m.corners(i).map(Vec3::from);
            let n = (b - a).cross(c - a);
            let avg: Vec3 = t.iter().map(|&v| m.normals[v as usize]).sum();
            assert!(n.dot(avg) > 0.0, "triangle {i} is wound against its normals");
        }
    }

    #[test]
    fn icosphere_is_closed_outward_and_converges() {
        for s in 0..4 {
            let m = icosphere(s);
            assert_eq!(m.triangles.len(), 20 * 4usize.pow(s));
            assert_eq!(m.positions.len(), 10 * 4usize.pow(s) + 2);
            assert_closed(&m);
            assert_faces_agree_with_normals(&m);
            assert!(m.positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-6));
        }
        let v = signed_volume(&icosphere(4));
        assert!((v - 4.0 / 3.0 * PI).abs() < 0.02, "{v}");
    }

    #[test]
    fn torus_is_closed_outward_with_the_right_volume() {
        let m = torus(2.0, 0.5, 64, 32);
        assert_closed(&m);
        assert_faces_agree_with_normals(&m);
        let v = signed_volume(&m);
        let exact = 2.0 * PI * PI * 2.0 * 0.25;
        assert!((v - exact).abs() / exact < 0.01, "{v} vs {exact}");
    }

    #[test]
    fn star_prism_is_closed_outward_with_the_right_volume() {
        let (p, r_out, r_in, h) = (5, 1.0, 0.4, 0.3);
        let m = star_prism(p, r_out, r_in, h);
        assert_eq!(m.triangles.len(), 8 * p as usize);
        assert_closed(&m);
        // The star is 2p triangles (centre, tip, notch) of area ½·R·r·sin(π/p).
        let exact = p as f32 * r_out * r_in * (PI / p as f32).sin() * h;
        let v = signed_volume(&m);
        assert!((v - exact).abs() < 1e-5, "{v} vs {exact}");
        // Each side face's normal points away from the axis.
        for (i, t) in m.triangles.iter().enumerate() {
            let [a, b, c] = m.corners(i).map(Vec3::from);
            let n = (b - a).cross(c - a);
            if n.z.abs() < 1e-6 {
                let centre = (a + b + c) / 3.0;
                assert!(n.x * centre.x + n.y * centre.y > 0.0, "side {i} {t:?} faces in");
            } else {
                assert!(n.z * a.z > 0.0, "cap {i} faces in");
            }
        }
    }

    #[test]
    fn heightfield_faces_up() {
        let m = heightfield(4, 3, 2.0, 1.0, |x, z| 0.1 * (x + z).sin());
        assert_eq!(m.positions.len(), 20);
        assert_eq!(m.triangles.len(), 24);
        assert!(m.normals.iter().all(|n| n.y > 0.9));
        assert!(grid(2, 2, 1.0, 1.0).normals.iter().all(|n| *n == Vec3::Y));
    }

    #[test]
    fn write_off_round_trips_exactly() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.off");
        let m = torus(1.0, 0.3, 7, 5);
        write_off(&m, &path).unwrap();
        let back = crate::io::load_mesh(&path).unwrap();
        assert_eq!(back.positions, m.positions);
        assert_eq!(back.triangles, m.triangles);
    }
}
