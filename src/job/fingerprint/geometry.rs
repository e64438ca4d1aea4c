//! Objects' and meshes' encoding: shapes by their parameters, meshes by
//! content (positions, normals, texture coordinates, tangents and
//! triangles, hashed in bulk), never by file name.

use super::encoder::{Encoder, Fingerprint};
use crate::geometry::{Cylinder, Disk, Mesh, Quad, Sphere};
use crate::math::Transform;
use crate::scene::{Object, Shape};

impl Fingerprint for Object {
    fn encode(&self, e: &mut Encoder) {
        // The name only labels messages.
        let Object {
            name: _,
            shape,
            material,
        } = self;
        e.tag("object");
        e.put(shape);
        e.u32(*material);
    }
}

impl Fingerprint for Shape {
    fn encode(&self, e: &mut Encoder) {
        e.tag("shape");
        match self {
            Shape::Sphere(s) => {
                e.u8(0);
                let Sphere { center, radius } = s;
                e.put(center);
                e.f32(*radius);
            }
            Shape::Quad(q) => {
                e.u8(1);
                // The private rest is computed from these.
                let Quad {
                    corner, u, v, normal, ..
                } = q;
                e.put(corner);
                e.put(u);
                e.put(v);
                e.put(normal);
            }
            Shape::Disk(d) => {
                e.u8(2);
                // The private rest is computed from these.
                let Disk {
                    center, a, b, normal, ..
                } = d;
                e.put(center);
                e.put(a);
                e.put(b);
                e.put(normal);
            }
            Shape::Cylinder(c) => {
                e.u8(3);
                let Cylinder {
                    base,
                    s,
                    t,
                    axis,
                    radius,
                    length,
                    inward,
                } = c;
                e.put(base);
                e.put(s);
                e.put(t);
                e.put(axis);
                e.f32(*radius);
                e.f32(*length);
                e.bool(*inward);
            }
            Shape::Mesh {
                mesh,
                transform,
                smooth,
            } => {
                e.u8(4);
                e.u32(*mesh);
                e.put(transform);
                e.bool(*smooth);
            }
        }
    }
}

impl Fingerprint for Transform {
    fn encode(&self, e: &mut Encoder) {
        // Each matrix is its own value (the inverses are computed once,
        // and rays use them as stored).
        let Transform {
            to_world,
            to_object,
            normal_to_world,
        } = self;
        e.floats(&to_world.to_cols_array());
        e.floats(&to_object.to_cols_array());
        e.floats(&normal_to_world.to_cols_array());
    }
}

impl Fingerprint for Mesh {
    fn encode(&self, e: &mut Encoder) {
        let Mesh {
            name: _,
            positions,
            normals,
            triangles,
            uvs,
            tangents,
        } = self;
        e.tag("mesh");
        e.float_records(positions.iter().map(|p| p.to_array()));
        e.float_records(normals.iter().map(|n| n.to_array()));
        e.float_records(uvs.iter().map(|t| t.to_array()));
        e.float_records(tangents.iter().map(|t| t.to_array()));
        e.u32_records(triangles.iter().copied());
    }
}
