//! The `[[objects]]`: spheres, quads, disks, cylinders, mesh instances
//! (their files resolved and loaded once each), water surfaces, and the
//! `[medium]` that fills the water.

use super::ctx::Ctx;
use super::error::SceneError;
use crate::geometry::water::{WaterSurface, Wave, MAX_WATER_RESOLUTION};
use crate::io::MeshError;
use crate::math::{Transform, Vec3, Vec3A};
use crate::scene::desc::{MediumDesc, ObjectDesc, ScaleDesc, Spanned, Vec2Desc};
use crate::scene::medium::VolumeCoefficients;
use crate::scene::{Cylinder, Disk, Medium, Mesh, Object, Quad, Shape, Sphere};
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Default water grid resolution (cells per side).
pub const DEFAULT_WATER_RESOLUTION: u32 = 256;

impl Ctx<'_> {
    fn object_keys(o: &ObjectDesc) -> [(&'static str, Option<Range<usize>>); 19] {
        fn s<T>(x: &Option<Spanned<T>>) -> Option<Range<usize>> {
            x.as_ref().map(|x| x.span())
        }
        [
            ("center", s(&o.center)),
            ("radius", s(&o.radius)),
            ("p0", s(&o.p0)),
            ("p1", s(&o.p1)),
            ("flip_normals", s(&o.flip_normals)),
            ("corner", s(&o.corner)),
            ("u", s(&o.u)),
            ("v", s(&o.v)),
            ("size", s(&o.size)),
            ("normal", s(&o.normal)),
            ("up", s(&o.up)),
            ("rotate", s(&o.rotate)),
            ("file", s(&o.file)),
            ("translate", s(&o.translate)),
            ("matrix", s(&o.matrix)),
            ("scale", s(&o.scale)),
            ("smooth", s(&o.smooth)),
            ("waves", s(&o.waves)),
            ("resolution", s(&o.resolution)),
        ]
    }

    /// `[medium]`: fills the (first) water object's volume.
    pub(super) fn medium(
        &self,
        m: &Spanned<MediumDesc>,
        water: Option<(usize, &WaterSurface)>,
        bounds: crate::math::Aabb,
    ) -> Result<Medium, SceneError> {
        let d = m.get_ref();
        let density = self.number(&d.density, "density")?;
        if density < 0.0 {
            return Err(self.invalid(d.density.span(), format!("`density` = {density} must be ≥ 0")));
        }
        let colour = match &d.colour {
            None => Vec3A::ZERO,
            Some(c) => self.colour(c, "colour")?,
        };
        let Some((boundary, water)) = water else {
            return Err(self.invalid(
                m.span(),
                "`[medium]` fills the water: the scene needs an object of `type = \"water\"`",
            ));
        };
        let coefficient =
            |c: &Option<Spanned<crate::scene::desc::Vec3Desc>>, key: &str| -> Result<Option<Vec3A>, SceneError> {
                match c {
                    None => Ok(None),
                    Some(s) => {
                        let v = self.vec3(s, key)?;
                        if v.min_element() < 0.0 {
                            return Err(self.invalid(s.span(), format!("`{key}` must be ≥ 0 in every channel")));
                        }
                        Ok(Some(v))
                    }
                }
            };
        let absorption = coefficient(&d.absorption, "absorption")?;
        let scattering = coefficient(&d.scattering, "scattering")?;
        let g = match &d.g {
            None => 0.0,
            Some(s) => {
                let g = self.number(s, "g")?;
                if g <= -1.0 || g >= 1.0 {
                    return Err(self.invalid(s.span(), format!("`g` = {g} must be in (−1, 1)")));
                }
                g
            }
        };
        let volume = match (absorption, scattering) {
            (None, None) => {
                if let Some(s) = &d.g {
                    return Err(self.invalid(s.span(), "`g` needs `absorption` and `scattering`"));
                }
                None
            }
            (a, s) => Some(VolumeCoefficients {
                absorption: a.unwrap_or(Vec3A::ZERO),
                scattering: s.unwrap_or(Vec3A::ZERO),
                g,
            }),
        };
        Ok(Medium {
            density,
            colour,
            region: water.volume(bounds.min.y),
            volume,
            surface: water.clone(),
            boundary: boundary as u32,
        })
    }

    /// A water surface: `center`, `size`, `resolution`, `waves`.
    pub(super) fn water(&self, o: &ObjectDesc) -> Result<WaterSurface, SceneError> {
        let what = "a water surface";
        self.only_keys(what, &Self::object_keys(o), &["center", "size", "resolution", "waves"])?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let size_desc = self.required(&o.size, "size", what, o.kind.span())?;
        let (w, h) = self.finite_size(size_desc)?;
        if !(w > 0.0 && h > 0.0) {
            return Err(self.invalid(size_desc.span(), format!("water `size` = [{w}, {h}] must be positive")));
        }
        let resolution = match &o.resolution {
            None => (DEFAULT_WATER_RESOLUTION, DEFAULT_WATER_RESOLUTION),
            Some(r) => {
                let Vec2Desc([a, b]) = *r.get_ref();
                let ok = |x: f64| x.fract() == 0.0 && (1.0..=MAX_WATER_RESOLUTION as f64).contains(&x);
                if !(ok(a) && ok(b)) {
                    return Err(self.invalid(
                        r.span(),
                        format!("water `resolution` = [{a}, {b}]: both must be integers in 1..={MAX_WATER_RESOLUTION}"),
                    ));
                }
                (a as u32, b as u32)
            }
        };
        let mut waves = Vec::new();
        if let Some(list) = &o.waves {
            for wd in list.get_ref() {
                let amplitude = self.number(&wd.amplitude, "amplitude")?;
                let wavelength = self.number(&wd.wavelength, "wavelength")?;
                if wavelength <= 0.0 {
                    return Err(self.invalid(wd.wavelength.span(), format!("`wavelength` = {wavelength} must be > 0")));
                }
                let Vec2Desc([dx, dz]) = *wd.direction.get_ref();
                let dir = crate::math::Vec2::new(
                    self.check_finite(dx, wd.direction.span(), "direction")?,
                    self.check_finite(dz, wd.direction.span(), "direction")?,
                );
                let Some(direction) = dir.try_normalize() else {
                    return Err(self.invalid(
                        wd.direction.span(),
                        "wave `direction` is the zero vector: it must have a direction",
                    ));
                };
                let phase = match &wd.phase {
                    None => 0.0,
                    Some(p) => self.number(p, "phase")?.to_radians(),
                };
                waves.push(Wave {
                    amplitude,
                    wavelength,
                    direction,
                    phase,
                });
            }
        }
        Ok(WaterSurface {
            center,
            size: crate::math::Vec2::new(w, h),
            resolution,
            waves,
        })
    }

    pub(super) fn sphere(&self, o: &ObjectDesc) -> Result<Shape, SceneError> {
        let what = "a sphere";
        self.only_keys(what, &Self::object_keys(o), &["center", "radius"])?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let r = self.required(&o.radius, "radius", what, o.kind.span())?;
        let radius = self.number(r, "radius")?;
        if radius <= 0.0 {
            return Err(self.invalid(r.span(), format!("sphere `radius` = {radius} must be > 0")));
        }
        Ok(Shape::Sphere(Sphere { center, radius }))
    }

    /// A quad, either `corner` + `u` + `v`, or `center` + `size` with an
    /// orientation (`normal` + optional `up`, or `rotate`).
    pub(super) fn quad(&self, o: &ObjectDesc) -> Result<Shape, SceneError> {
        let keys = Self::object_keys(o);
        let degenerate = |span: Range<usize>, why: &str| self.invalid(span, format!("degenerate quad: {why}"));
        if let Some(corner_desc) = &o.corner {
            self.only_keys("a quad given by `corner`", &keys, &["corner", "u", "v"])?;
            let what = "a quad given by `corner`";
            let corner = self.vec3(corner_desc, "corner")?;
            let u_desc = self.required(&o.u, "u", what, corner_desc.span())?;
            let v_desc = self.required(&o.v, "v", what, corner_desc.span())?;
            let u = self.vec3(u_desc, "u")?;
            let v = self.vec3(v_desc, "v")?;
            if u.length_squared() == 0.0 {
                return Err(degenerate(u_desc.span(), "`u` is the zero vector"));
            }
            if v.length_squared() == 0.0 {
                return Err(degenerate(v_desc.span(), "`v` is the zero vector"));
            }
            return Quad::new(corner, u, v)
                .filter(|q| q.area() > 0.0 && q.area().is_finite())
                .map(Shape::Quad)
                .ok_or_else(|| degenerate(v_desc.span(), "`u` and `v` are parallel (zero area)"));
        }
        let what = "a quad given by `center` (or give `corner`, `u`, `v`)";
        self.only_keys(what, &keys, &["center", "size", "normal", "up", "rotate"])?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let size_desc = self.required(&o.size, "size", what, o.kind.span())?;
        let (w, h) = self.finite_size(size_desc)?;
        if !(w > 0.0 && h > 0.0) {
            return Err(degenerate(
                size_desc.span(),
                &format!("`size` = [{w}, {h}] must be positive"),
            ));
        }
        let (e_u, e_v) = self.orientation(o, "quad")?;
        let (u, v) = (e_u * w, e_v * h);
        Quad::new(center - (u + v) * 0.5, u, v)
            .filter(|q| q.area() > 0.0 && q.area().is_finite())
            .map(Shape::Quad)
            .ok_or_else(|| degenerate(size_desc.span(), "zero or overflowing area"))
    }

    /// Unit directions `(e_u, e_v)` with `e_u × e_v` the facing normal of a
    /// flat shape (`"quad"` or `"disk"`, named in messages): `normal` and
    /// an optional `up`, or `rotate` (the +z-facing shape rotated), or +z.
    fn orientation(&self, o: &ObjectDesc, shape: &str) -> Result<(Vec3A, Vec3A), SceneError> {
        Ok(match (&o.normal, &o.rotate) {
            (Some(_), Some(r)) => {
                return Err(self.invalid(
                    r.span(),
                    format!("give the {shape}'s orientation either as `normal` (+ `up`) or as `rotate`, not both"),
                ))
            }
            (Some(n_desc), None) => {
                let n = self.direction(n_desc, "normal")?.normalize();
                let up = match &o.up {
                    Some(u) => self.direction(u, "up")?.normalize(),
                    // +y, unless the shape faces up or down (a floor or a
                    // ceiling): then its height runs along −z, away from a
                    // camera on the +z side.
                    None if n.y.abs() > 0.999 => -Vec3A::Z,
                    None => Vec3A::Y,
                };
                let e_v = (up - n * up.dot(n))
                    .try_normalize()
                    .filter(|_| n.cross(up).length() > 1e-4);
                let Some(e_v) = e_v else {
                    let span = o.up.as_ref().map_or(n_desc.span(), |u| u.span());
                    return Err(self.invalid(span, format!("the {shape}'s `up` is parallel to its `normal`")));
                };
                // e_u × e_v = (e_v × n) × e_v = n (e_v ⟂ n, |e_v| = 1).
                (e_v.cross(n), e_v)
            }
            (None, rotate) => {
                if let Some(up) = &o.up {
                    return Err(self.invalid(
                        up.span(),
                        format!("`up` needs `normal` (it orients a {shape} given by `normal`)"),
                    ));
                }
                let deg = self.opt_vec3(rotate, "rotate", Vec3A::ZERO)?;
                let r = euler_xyz(deg);
                (r * Vec3A::X, r * Vec3A::Y)
            }
        })
    }

    /// A disk: `center`, `radius` and an orientation as a quad's (`normal`
    /// with an optional `up`, or `rotate`); its texture coordinates' `φ`
    /// runs from the quad's `u` direction toward its `v` direction.
    pub(super) fn disk(&self, o: &ObjectDesc) -> Result<Shape, SceneError> {
        let what = "a disk";
        if let Some(u_desc) = &o.u {
            // The semi-axes as given: an ellipse, or a circle in any frame.
            let what = "a disk given by `u` and `v`";
            self.only_keys(what, &Self::object_keys(o), &["center", "u", "v", "flip_normals"])?;
            let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
            let v_desc = self.required(&o.v, "v", what, u_desc.span())?;
            let (u, v) = (self.direction(u_desc, "u")?, self.direction(v_desc, "v")?);
            let reversed = o.flip_normals.as_ref().is_some_and(|f| *f.get_ref());
            return Disk::new(center, u, v, reversed)
                .filter(|d| d.area() > 0.0 && d.area().is_finite())
                .map(Shape::Disk)
                .ok_or_else(|| self.invalid(v_desc.span(), "degenerate disk: `u` and `v` are parallel"));
        }
        self.only_keys(
            what,
            &Self::object_keys(o),
            &["center", "radius", "normal", "up", "rotate"],
        )?;
        let center = self.vec3(self.required(&o.center, "center", what, o.kind.span())?, "center")?;
        let r = self.required(&o.radius, "radius", what, o.kind.span())?;
        let radius = self.number(r, "radius")?;
        if radius <= 0.0 {
            return Err(self.invalid(r.span(), format!("disk `radius` = {radius} must be > 0")));
        }
        let (e_u, e_v) = self.orientation(o, "disk")?;
        Disk::new(center, e_u * radius, e_v * radius, false)
            .filter(|d| d.area() > 0.0 && d.area().is_finite())
            .map(Shape::Disk)
            .ok_or_else(|| self.invalid(r.span(), "degenerate disk: zero or overflowing area"))
    }

    /// A cylinder: the centres `p0` and `p1` of its ends, `radius`, and
    /// `flip_normals`. The azimuth of its texture coordinates is measured
    /// in the frame Mitsuba builds about `p1 − p0` (Duff et al. 2017), so a
    /// cylinder written with the same `p0`, `p1` in either format has the
    /// same texture coordinates.
    pub(super) fn cylinder(&self, o: &ObjectDesc) -> Result<Shape, SceneError> {
        let what = "a cylinder";
        self.only_keys(what, &Self::object_keys(o), &["p0", "p1", "radius", "flip_normals"])?;
        let p0 = self.vec3(self.required(&o.p0, "p0", what, o.kind.span())?, "p0")?;
        let p1_desc = self.required(&o.p1, "p1", what, o.kind.span())?;
        let p1 = self.vec3(p1_desc, "p1")?;
        let r = self.required(&o.radius, "radius", what, o.kind.span())?;
        let radius = self.number(r, "radius")?;
        if radius <= 0.0 {
            return Err(self.invalid(r.span(), format!("cylinder `radius` = {radius} must be > 0")));
        }
        let length = (p1 - p0).length();
        if !(length > 0.0 && length.is_finite()) {
            return Err(self.invalid(p1_desc.span(), "degenerate cylinder: `p1` equals `p0`"));
        }
        let frame = crate::math::Frame::from_normal((p1 - p0) / length);
        let inward = o.flip_normals.as_ref().is_some_and(|f| *f.get_ref());
        Cylinder::new(p0, [frame.s, frame.t, frame.n], radius, length, inward)
            .map(Shape::Cylinder)
            .ok_or_else(|| self.invalid(r.span(), "degenerate cylinder"))
    }

    /// A mesh object's file reference, transform and shading flag.
    pub(super) fn mesh_instance<'d>(
        &self,
        o: &'d ObjectDesc,
    ) -> Result<(&'d Spanned<String>, Transform, bool), SceneError> {
        let what = "a mesh";
        self.only_keys(
            what,
            &Self::object_keys(o),
            &["file", "translate", "rotate", "scale", "matrix", "smooth"],
        )?;
        let file = self.required(&o.file, "file", what, o.kind.span())?;
        let smooth = o.smooth.as_ref().is_some_and(|s| *s.get_ref());
        if let Some(m) = &o.matrix {
            if let Some((key, span)) = [("translate", &o.translate), ("rotate", &o.rotate)]
                .into_iter()
                .find_map(|(k, s)| s.as_ref().map(|s| (k, s.span())))
                .or(o.scale.as_ref().map(|s| ("scale", s.span())))
            {
                return Err(self.invalid(span, format!("`{key}` with `matrix`: give the transform one way")));
            }
            let mut rows = [[0f32; 4]; 3];
            for (row, desc) in rows.iter_mut().zip(m.get_ref().0) {
                for (x, d) in row.iter_mut().zip(desc.0) {
                    *x = self.check_finite(d, m.span(), "matrix")?;
                }
            }
            let col = |j: usize| Vec3::new(rows[0][j], rows[1][j], rows[2][j]);
            let affine = crate::math::Affine3A::from_cols(col(0).into(), col(1).into(), col(2).into(), col(3).into());
            let transform = Transform::from_affine(affine)
                .ok_or_else(|| self.invalid(m.span(), "the mesh `matrix` is singular"))?;
            return Ok((file, transform, smooth));
        }
        let translate = self.opt_vec3(&o.translate, "translate", Vec3A::ZERO)?;
        let rotate = self.opt_vec3(&o.rotate, "rotate", Vec3A::ZERO)?;
        let scale = match &o.scale {
            None => Vec3A::ONE,
            Some(s) => {
                let v = match *s.get_ref() {
                    ScaleDesc::Uniform(x) => Vec3A::splat(self.check_finite(x, s.span(), "scale")?),
                    ScaleDesc::PerAxis([x, y, z]) => Vec3A::new(
                        self.check_finite(x, s.span(), "scale")?,
                        self.check_finite(y, s.span(), "scale")?,
                        self.check_finite(z, s.span(), "scale")?,
                    ),
                };
                if v.abs().min_element() == 0.0 {
                    return Err(self.invalid(s.span(), "`scale` is zero on an axis: the mesh would be flat"));
                }
                v
            }
        };
        let transform =
            Transform::from_srt(Vec3::from(scale), Vec3::from(rotate), Vec3::from(translate)).ok_or_else(|| {
                let span = o.scale.as_ref().map_or(o.kind.span(), |s| s.span());
                self.invalid(span, "the mesh transform is singular (scale too small)")
            })?;
        Ok((file, transform, smooth))
    }

    /// Resolves the mesh files, loads each distinct one once (in parallel),
    /// and points the objects at them.
    pub(super) fn load_meshes(
        &self,
        objects: &mut [Object],
        refs: &[(usize, &Spanned<String>)],
    ) -> Result<Vec<Arc<Mesh>>, SceneError> {
        let scene_dir = self.path.parent().unwrap_or(Path::new(""));
        let mesh_error = |object: usize, file: &Spanned<String>, error| SceneError::Mesh {
            path: self.path.into(),
            place: self.place(file.span()),
            object: objects[object].name.clone(),
            error: Box::new(error),
        };
        // Distinct files in order of first use; `first_user` reports errors
        // at the first object that names the file.
        let mut by_key: HashMap<PathBuf, usize> = HashMap::new();
        let mut files: Vec<(PathBuf, usize, &Spanned<String>)> = Vec::new();
        let mut mesh_of_object = Vec::with_capacity(refs.len());
        for &(object, file) in refs {
            let resolved =
                crate::io::resolve_mesh_path(scene_dir, file.get_ref()).map_err(|e| mesh_error(object, file, e))?;
            // Canonical path as the key: `a/../m.off` and `m.off` are one mesh.
            // A file that does not exist keeps its resolved path and is
            // reported by the loader.
            let key = std::fs::canonicalize(&resolved).unwrap_or_else(|_| resolved.clone());
            let index = *by_key.entry(key).or_insert_with(|| {
                files.push((resolved, object, file));
                files.len() - 1
            });
            mesh_of_object.push((object, index));
        }
        let loaded: Vec<Result<Mesh, MeshError>> = files
            .par_iter()
            .map(|(path, _, _)| crate::io::load_mesh(path))
            .collect();
        let mut meshes = Vec::with_capacity(loaded.len());
        for (result, (_, object, file)) in loaded.into_iter().zip(&files) {
            meshes.push(Arc::new(result.map_err(|e| mesh_error(*object, file, e))?));
        }
        for (object, index) in mesh_of_object {
            if let Shape::Mesh { mesh, .. } = &mut objects[object].shape {
                *mesh = index as u32;
            }
        }
        Ok(meshes)
    }
}

/// Rotation by `deg` degrees about x, then y, then z (the convention of
/// [`Transform::from_srt`], so quads and meshes rotate alike).
fn euler_xyz(deg: Vec3A) -> glam::Mat3A {
    glam::Mat3A::from_quat(glam::Quat::from_euler(
        glam::EulerRot::ZYX,
        deg.z.to_radians(),
        deg.y.to_radians(),
        deg.x.to_radians(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_matches_the_mesh_transform() {
        let deg = Vec3A::new(30.0, -45.0, 60.0);
        let t = Transform::from_srt(Vec3::ONE, Vec3::from(deg), Vec3::ZERO).unwrap();
        let r = euler_xyz(deg);
        for v in [Vec3A::X, Vec3A::Y, Vec3A::Z] {
            assert!((t.point(v) - r * v).length() < 1e-6);
        }
    }
}
