//! `<shape>`: obj, ply, serialized, rectangle, cube, sphere, disk and
//! cylinder, each with its BSDF (Mitsuba's default: a one-sided diffuse of
//! reflectance 0.5, black on an emitting shape) and a nested `area`
//! emitter, which makes the shape emit and still reflect; and `shapegroup`
//! with `instance`: each instance adds the group's shapes as objects with the
//! composed `to_world`, sharing the group's meshes and materials (one mesh
//! in memory however many instances).

use super::emitters::affine;
use super::props::Plugin;
use super::spectrum::SpectrumUse;
use super::xml::resolve;
use super::{Builder, MeshSource};
use crate::geometry::Mesh;
use crate::math::Frame;
use crate::math::{Transform, Vec2, Vec3, Vec3A};
use crate::scene::load::SceneError;
use crate::scene::{Cylinder, Disk, Material, MediumInterface, Object, Quad, Shape, Sphere};
use glam::{Affine3A, Mat4};

/// Mitsuba's `cube`: 24 vertices (4 per face, with the face's normal and
/// UVs) and 12 triangles over [−1, 1]³, as `mi.traverse` lists them.
const CUBE_POSITIONS: [[f32; 3]; 24] = [
    [1., -1., -1.],
    [1., -1., 1.],
    [-1., -1., 1.],
    [-1., -1., -1.],
    [1., 1., -1.],
    [-1., 1., -1.],
    [-1., 1., 1.],
    [1., 1., 1.],
    [1., -1., -1.],
    [1., 1., -1.],
    [1., 1., 1.],
    [1., -1., 1.],
    [1., -1., 1.],
    [1., 1., 1.],
    [-1., 1., 1.],
    [-1., -1., 1.],
    [-1., -1., 1.],
    [-1., 1., 1.],
    [-1., 1., -1.],
    [-1., -1., -1.],
    [1., 1., -1.],
    [1., -1., -1.],
    [-1., -1., -1.],
    [-1., 1., -1.],
];
const CUBE_NORMALS: [[f32; 3]; 6] = [
    [0., -1., 0.],
    [0., 1., 0.],
    [1., 0., 0.],
    [0., 0., 1.],
    [-1., 0., 0.],
    [0., 0., -1.],
];
const CUBE_UVS: [[f32; 2]; 4] = [[0., 1.], [1., 1.], [1., 0.], [0., 0.]];

impl Builder<'_> {
    /// Adds a `<shape>`'s objects: one, or an instance's group members.
    pub(super) fn shape(&mut self, p: &Plugin) -> Result<(), SceneError> {
        match p.kind {
            "instance" => self.instance(p),
            "shapegroup" => {
                // Not referenced by any instance: Mitsuba renders nothing of
                // it; its members are still read, so mistakes are reported.
                let objects = self.objects.len();
                self.group_members(p, &Mat4::IDENTITY, "")?;
                self.objects.truncate(objects);
                self.interfaces.truncate(objects);
                Ok(())
            }
            _ => {
                let (object, interface) = self.object(p, &Mat4::IDENTITY, None)?;
                self.objects.push((object, p.origin().part()));
                self.interfaces.push(interface);
                Ok(())
            }
        }
    }

    /// `<shape type="instance">`: a `<ref>` to a shapegroup and a
    /// `to_world`; adds the group's shapes with `to_world` composed.
    fn instance(&mut self, p: &Plugin) -> Result<(), SceneError> {
        let groups = p.children_of("shape")?;
        let (group, at) = match groups.as_slice() {
            [one] => one,
            [] => return Err(p.error("an instance needs a <ref id=\"…\"/> to a shapegroup")),
            [_, second, ..] => return Err(second.1.origin.error("an instance takes one shapegroup, not several")),
        };
        if group.kind != "shapegroup" {
            return Err(at.origin.error(format!(
                "an instance refers to a <shape type=\"shapegroup\">, not to a <shape type=\"{}\">",
                group.kind
            )));
        }
        let to_world = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        p.finish()?;
        let name = p
            .element
            .attr("id")
            .map_or_else(|| format!("instance@{}", p.origin().place), str::to_string);
        self.group_members(group, &to_world, &name)
    }

    /// Adds the members of shapegroup `group` placed by `to_world`, named
    /// `{instance}/{member}`. Refused as Mitsuba refuses them: nested groups
    /// and instances, emitters (and media, which caustic does not render).
    fn group_members(&mut self, group: &Plugin, to_world: &Mat4, instance: &str) -> Result<(), SceneError> {
        let members = group.children_of("shape")?;
        group.finish()?;
        for (member, at) in &members {
            match member.kind {
                "shapegroup" => {
                    return Err(at.origin.error(
                        "a shapegroup inside a shapegroup: nested instancing is not permitted (nor in Mitsuba)",
                    ))
                }
                "instance" => {
                    return Err(at
                        .origin
                        .error("an instance inside a shapegroup: nested instancing is not permitted (nor in Mitsuba)"))
                }
                _ => {}
            }
            if let Some((e, _)) = member.children_of("emitter")?.first() {
                return Err(e.error(
                    "an emitter on a shape of a shapegroup: instancing of emitters is not supported (nor in Mitsuba)",
                ));
            }
            // `children_of` marked the emitters read: read the member afresh.
            let member = member.fresh()?;
            let (object, interface) = self.object(&member, to_world, Some(instance))?;
            self.objects.push((object, member.origin().part()));
            self.interfaces.push(interface);
        }
        Ok(())
    }

    /// The object of a `<shape>` and the media on its sides, its `to_world`
    /// preceded by `parent` (an instance's), its name prefixed by the
    /// instance's.
    fn object(
        &mut self,
        p: &Plugin,
        parent: &Mat4,
        instance: Option<&str>,
    ) -> Result<(Object, MediumInterface), SceneError> {
        let interface = MediumInterface {
            interior: self.shape_medium(p, "interior")?,
            exterior: self.shape_medium(p, "exterior")?,
        };
        let material = self.shape_material(p)?;
        let name = p
            .element
            .attr("id")
            .map_or_else(|| format!("{}@{}", p.kind, p.origin().place), str::to_string);
        let name = match instance {
            Some(i) => format!("{i}/{name}"),
            None => name,
        };
        let flip_normals = p.boolean("flip_normals")?.unwrap_or(false);
        let own_to_world = p.transform("to_world")?.unwrap_or(Mat4::IDENTITY);
        let to_world = *parent * own_to_world;
        let shape = match p.kind {
            "obj" | "ply" | "serialized" => {
                let file = p.string("filename")?.ok_or_else(|| p.error("`filename` is required"))?;
                let at = p.take("filename").map_or(p.origin(), |e| &e.origin).clone();
                let face_normals = p.boolean("face_normals")?.unwrap_or(false);
                // Mitsuba orients face normals by the winding of the mesh as
                // its own `to_world` places it, which a mirroring one
                // reverses; caustic transforms the object's. An instance's
                // transform moves the normals as normals (its mirror keeps
                // their side), so only the shape's own counts.
                let mirrored = own_to_world.determinant() < 0.0;
                let flip_normals = flip_normals != (face_normals && mirrored);
                let shape_index = match p.kind {
                    "serialized" => {
                        let i = p.int("shape_index")?.unwrap_or(0);
                        u32::try_from(i).map_err(|_| p.error(format!("`shape_index` = {i} must be ≥ 0")))?
                    }
                    _ => 0,
                };
                let flip_v = match p.kind {
                    // caustic's OBJ reader already flips v, as Mitsuba does by default.
                    "obj" => !p.boolean("flip_tex_coords")?.unwrap_or(true),
                    _ => false,
                };
                if p.kind == "ply" && p.has("flip_tex_coords") {
                    return Err(p.error("`flip_tex_coords` is an OBJ parameter"));
                }
                let path = resolve(file, at.dir(), &self.doc.search_path);
                let mesh = self.mesh_file(MeshSource::File {
                    path,
                    serialized: (p.kind == "serialized").then_some(shape_index),
                    flip_normals,
                    flip_v,
                    origin: at,
                    object: name.clone(),
                });
                Shape::Mesh {
                    mesh,
                    transform: self.transform(p, &to_world)?,
                    smooth: !face_normals,
                }
            }
            "rectangle" => {
                let m = affine(p, &to_world)?;
                let corner = m.transform_point3(Vec3::new(-1.0, -1.0, 0.0));
                let (u, v) = (m.transform_vector3(Vec3::X * 2.0), m.transform_vector3(Vec3::Y * 2.0));
                // Mitsuba's front is the transformed +z normal: u × v unless
                // the transform mirrors or the normals are flipped.
                let mirrored = m.matrix3.determinant() < 0.0;
                if mirrored != flip_normals {
                    Shape::Mesh {
                        mesh: self.mesh_generated(p, flip_normals, || quad_mesh(flip_normals)),
                        transform: self.transform(p, &to_world)?,
                        smooth: false,
                    }
                } else {
                    Shape::Quad(
                        Quad::new(corner.into(), u.into(), v.into())
                            .ok_or_else(|| p.error("`to_world` flattens the rectangle to a line"))?,
                    )
                }
            }
            "cube" => {
                let mesh = self.mesh_generated(p, flip_normals, || {
                    let positions = CUBE_POSITIONS.iter().map(|p| Vec3::from_array(*p)).collect();
                    let normals = (0..24).map(|i| Vec3::from_array(CUBE_NORMALS[i / 4])).collect();
                    let triangles = (0..6u32)
                        .flat_map(|f| [[4 * f, 4 * f + 1, 4 * f + 2], [4 * f + 3, 4 * f, 4 * f + 2]])
                        .collect();
                    let uvs = (0..24).map(|i| Vec2::from_array(CUBE_UVS[i % 4])).collect();
                    let mesh = Mesh::new("cube", positions, triangles, Some(normals))
                        .and_then(|m| m.with_uvs(uvs))
                        .expect("the cube is a valid mesh");
                    if flip_normals {
                        flipped(mesh)
                    } else {
                        mesh
                    }
                });
                Shape::Mesh {
                    mesh,
                    transform: self.transform(p, &to_world)?,
                    smooth: false,
                }
            }
            "sphere" => {
                if flip_normals {
                    return Err(p.error("`flip_normals` on a sphere is not supported"));
                }
                let center = p.vector("center")?.unwrap_or(Vec3::ZERO);
                let radius = p.float_checked("radius", 1.0, "> 0", |r| r > 0.0)?;
                let m = affine(p, &to_world)?
                    * Affine3A::from_translation(center)
                    * Affine3A::from_scale(Vec3::splat(radius));
                let axes = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
                let r = axes[0].length();
                let round = axes.iter().all(|a| (a.length() - r).abs() <= 1e-4 * r)
                    && axes[0].dot(axes[1]).abs() <= 1e-4 * r * r
                    && axes[1].dot(axes[2]).abs() <= 1e-4 * r * r
                    && axes[0].dot(axes[2]).abs() <= 1e-4 * r * r;
                if !round || r <= 0.0 {
                    return Err(p.error("`to_world` scales the sphere unevenly (an ellipsoid is not supported)"));
                }
                let rotated = (axes[0] / r - Vec3A::X).length() > 1e-5 || (axes[2] / r - Vec3A::Z).length() > 1e-5;
                if rotated
                    && self.materials[material as usize]
                        .textures
                        .as_ref()
                        .is_some_and(|t| t.uses_uv())
                {
                    return Err(p.error(
                        "a textured sphere whose `to_world` rotates it is not supported (caustic's sphere UVs follow the world axes)",
                    ));
                }
                Shape::Sphere(Sphere {
                    center: m.translation,
                    radius: r,
                })
            }
            "disk" => {
                let m = affine(p, &to_world)?;
                let (a, b) = (m.transform_vector3a(Vec3A::X), m.transform_vector3a(Vec3A::Y));
                let det = m.matrix3.determinant();
                if !(det != 0.0 && det.is_finite()) {
                    return Err(p.error("`to_world` is singular (the disk's normal is undefined)"));
                }
                // Mitsuba's front is M⁻ᵀ·ẑ = (a × b) / det M: −(a × b)
                // when M mirrors; `flip_normals` turns it over.
                Shape::Disk(
                    Disk::new(m.translation, a, b, (det < 0.0) != flip_normals)
                        .ok_or_else(|| p.error("`to_world` flattens the disk to a line"))?,
                )
            }
            "cylinder" => Shape::Cylinder(cylinder(p, &to_world, flip_normals, instance.is_some())?),
            "shapegroup" | "instance" => return Err(p.error("nested instancing is not permitted (nor in Mitsuba)")),
            "bsplinecurve" | "linearcurve" | "sdfgrid" => {
                return Err(p.error(format!("the shape `{}` is not supported yet", p.kind)))
            }
            other => return Err(p.error(format!("the shape `{other}` is unknown"))),
        };
        p.finish()?;
        Ok((Object { name, shape, material }, interface))
    }

    /// The index of a mesh the front end builds (cube, flipped rectangle):
    /// built once per shape element and flip, so the instances of a
    /// shapegroup share it.
    fn mesh_generated(&mut self, p: &Plugin, flip: bool, build: impl FnOnce() -> Mesh) -> u32 {
        let key = (p.element as *const _ as usize, flip);
        if let Some(&index) = self.generated_index.get(&key) {
            return index;
        }
        let index = self.mesh_ready(build());
        self.generated_index.insert(key, index);
        index
    }

    /// The medium a shape names `side` (`interior` or `exterior`), nested
    /// or referenced.
    fn shape_medium(&mut self, p: &Plugin, side: &str) -> Result<Option<u32>, SceneError> {
        match p.child_named(side)? {
            None => Ok(None),
            Some(m) if m.element.tag != "medium" => Err(m.error(format!(
                "`{side}` of {} must be a <medium>, not a <{}>",
                p.what(),
                m.element.tag
            ))),
            Some(m) => self.medium(&m).map(Some),
        }
    }

    /// The material of a shape: its BSDF (or Mitsuba's default) and the
    /// emission of a nested `area` emitter, one material per combination.
    fn shape_material(&mut self, p: &Plugin) -> Result<u32, SceneError> {
        let bsdf = p.single_child("bsdf")?;
        let emitters = p.children_of("emitter")?;
        if emitters.len() > 1 {
            return Err(emitters[1].1.origin.error("a shape takes at most one emitter"));
        }
        let key = (
            bsdf.as_ref().map_or(0, |b| b.element as *const _ as usize),
            emitters.first().map_or(0, |(e, _)| e.element as *const _ as usize),
        );
        if let Some(&index) = self.material_index.get(&key) {
            // The same definitions give the same material (read and checked once).
            return Ok(index);
        }
        self.bsdfs_read.set(0);
        let mut material = match &bsdf {
            Some(b) => self.bsdf(b)?,
            None => {
                // Mitsuba's `Shape` gives a shape without a BSDF a diffuse
                // one of reflectance 0.5, or 0 when it emits.
                let reflectance = if emitters.is_empty() { 0.5 } else { 0.0 };
                let mut m = Material::diffuse("default", Vec3A::splat(reflectance));
                m.ambient = Vec3A::ZERO;
                m.one_sided = true;
                m
            }
        };
        if let Some((e, _)) = emitters.first() {
            if e.kind != "area" {
                return Err(e.error("only an `area` emitter can be attached to a shape"));
            }
            let (radiance, texture) = self.colour(e, "radiance", Vec3A::ONE, SpectrumUse::Emission)?;
            e.finish()?;
            if texture.is_some() {
                material.emission = Vec3A::ONE;
                material.textures.get_or_insert_with(Default::default).emission = texture;
            } else {
                material.emission = radiance;
            }
            // Each emitter its own name: two lamps sharing one BSDF are
            // two materials (`caustic convert` writes each by name).
            let emitter = e
                .element
                .attr("id")
                .map_or_else(|| format!("area@{}", e.origin().place), str::to_string);
            material.name = format!("{}+{emitter}", material.name);
        }
        let index = self.materials.len() as u32;
        self.materials.push(material);
        self.material_index.insert(key, index);
        Ok(index)
    }

    fn transform(&self, p: &Plugin, m: &Mat4) -> Result<Transform, SceneError> {
        Transform::from_affine(affine(p, m)?).ok_or_else(|| p.error("`to_world` is singular"))
    }
}

/// Mitsuba 3's `cylinder`: `to_world · translate(p0) · frame(p1 − p0) ·
/// scale(r, r, |p1 − p0|)` (the frame of Duff et al. 2017 about the unit
/// axis), which must be a rotation (possibly mirroring) times a scale equal
/// across the axis: Mitsuba warns about shear and unequal scales across
/// the axis and renders them inconsistently (its area, hence an emitter's
/// power, is that of a round tube), so caustic refuses them. The normals
/// point outward whether or not the map mirrors (Mitsuba flips them back),
/// inward with `flip_normals`.
fn cylinder(p: &Plugin, to_world: &Mat4, flip_normals: bool, in_instance: bool) -> Result<Cylinder, SceneError> {
    let radius = p.float_checked("radius", 1.0, "> 0", |r| r > 0.0)?;
    let p0 = p.vector("p0")?.unwrap_or(Vec3::ZERO);
    let p1 = p.vector("p1")?.unwrap_or(Vec3::Z);
    let length = (p1 - p0).length();
    if !(length > 0.0 && length.is_finite()) {
        return Err(p.error("`p0` and `p1` coincide: the cylinder has no axis"));
    }
    let frame = Frame::from_normal(Vec3A::from((p1 - p0) / length));
    let object = Affine3A::from_translation(p0)
        * Affine3A::from_mat3(glam::Mat3::from_cols(frame.s.into(), frame.t.into(), frame.n.into()))
        * Affine3A::from_scale(Vec3::new(radius, radius, length));
    let m = affine(p, to_world)? * object;
    let [x, y, z] = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let (r, length) = (x.length(), z.length());
    let tol = 1e-4 * r.max(length);
    let round = (y.length() - r).abs() <= 1e-4 * r
        && x.dot(y).abs() <= tol * r
        && x.dot(z).abs() <= tol * length
        && y.dot(z).abs() <= tol * length;
    if !(round && r > 0.0 && length > 0.0) {
        return Err(p.error(if in_instance {
            "the instance's `to_world` shears the cylinder or scales it unevenly across its axis: an elliptic tube is not supported"
        } else {
            "`to_world` shears the cylinder or scales it unevenly across its axis (Mitsuba warns and renders it inconsistently): not supported"
        }));
    }
    let axis = z / length;
    let s = (x - axis * axis.dot(x)).normalize();
    let t = axis.cross(s);
    // The object's y axis may be −(axis × s) when the map mirrors.
    let t = if t.dot(y) < 0.0 { -t } else { t };
    Cylinder::new(m.translation, [s, t, axis], r, length, flip_normals)
        .ok_or_else(|| p.error("`to_world` makes the cylinder degenerate"))
}

/// The rectangle [−1, 1]² as two triangles with Mitsuba's UVs, facing −z
/// in object space when `flip`, else +z.
fn quad_mesh(flip: bool) -> Mesh {
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uvs = vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    let mesh = Mesh::new(
        "rectangle",
        positions,
        vec![[0, 1, 2], [0, 2, 3]],
        Some(vec![Vec3::Z; 4]),
    )
    .and_then(|m| m.with_uvs(uvs))
    .expect("the rectangle is a valid mesh");
    if flip {
        flipped(mesh)
    } else {
        mesh
    }
}

/// `mesh` turned inside out: triangles wound the other way, normals negated
/// (Mitsuba's `flip_normals`).
pub(super) fn flipped(mut mesh: Mesh) -> Mesh {
    for t in &mut mesh.triangles {
        t.swap(1, 2);
    }
    for n in &mut mesh.normals {
        *n = -*n;
    }
    mesh
}
