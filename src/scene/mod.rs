//! The scene: what the TOML file describes, validated and immutable
//! (`Send + Sync`), plus the surface query that turns an accelerator's `Hit`
//! into shading data.

pub mod builder;
pub mod camera;
pub mod compare;
pub mod conductors;
pub mod cutout;
pub mod desc;
pub mod gltf;
pub mod ior;
pub mod light;
pub mod load;
pub mod material;
pub mod media;
pub mod medium;
pub mod metals;
pub mod mitsuba;
pub mod settings;
pub mod write;

pub use crate::film::{OutputSettings, ToneMap};
use crate::geometry::Hit;
use crate::math::{Aabb, Ray, Transform, Vec2, Vec3A, Vec4};
use std::sync::Arc;

pub use crate::geometry::{Cylinder, Disk, Mesh, Quad, Sphere};
pub use crate::geometry::{WaterSurface, Wave};
pub use builder::{Origin, SceneBuilder};
pub use camera::{Camera, FovAxis, ImageRays, Projection};
pub use cutout::Cutouts;
pub use light::{AreaLight, Light};
pub use load::{load_toml_scene, parse_scene, SceneError};
pub use material::{
    AlphaMask, Blend, BumpMap, Coating, CoatingTable, CoatingTableCell, Conductor, Dielectric, Disney, FresnelModel,
    Material, MaterialTextures, MicrofacetDistribution, Mirror, NormalMap, Principled, ShadingModel,
    COATING_TABLE_SIZE,
};
pub use media::{HomogeneousMedium, Media, MediumInterface, PassThrough, PhaseFunction};
pub use medium::Medium;
pub use settings::{
    AdaptiveGoal, CausticsMode, GatherMode, IntegratorKind, PhotonSettings, RenderSettings, SampleSharing,
    DEFAULT_MIN_SPP, DEFAULT_PPM_ALPHA, DEFAULT_WHITTED_DEPTH,
};

/// What a scene file holds: the scene, and the render settings it asks for
/// (which the command line's overrides may then change).
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// What is rendered.
    pub scene: Scene,
    /// How it is rendered.
    pub settings: RenderSettings,
}

/// True when [`load_scene`] reads `path` as caustic's own TOML (the other
/// formats are chosen by extension).
pub fn is_toml_path(path: &std::path::Path) -> bool {
    !mitsuba::is_mitsuba_path(path) && !gltf::is_gltf_path(path)
}

/// Loads a scene file, choosing the format by extension: `.xml` is a
/// Mitsuba scene, `.gltf` and `.glb` a glTF 2.0 model (their warnings
/// printed to stderr), anything else caustic's TOML.
pub fn load_scene(path: &std::path::Path) -> Result<LoadedScene, SceneError> {
    load_scene_with(path, &[])
}

/// [`load_scene`] with `-D name=value` definitions for a Mitsuba scene's
/// `$name` parameters (a TOML scene takes none).
pub fn load_scene_with(path: &std::path::Path, defines: &[(String, String)]) -> Result<LoadedScene, SceneError> {
    load_scene_options(
        path,
        &LoadOptions {
            defines: defines.to_vec(),
            ..Default::default()
        },
    )
}

/// How a scene file is read: what the command line passes to the front ends.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `-D name=value` definitions for a Mitsuba scene's `$name` parameters.
    pub defines: Vec<(String, String)>,
    /// A glTF model's options (`--camera`, `--allow-outside-files`).
    pub gltf: gltf::GltfOptions,
}

/// [`load_scene`] with the command line's options.
pub fn load_scene_options(path: &std::path::Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let defines = &options.defines;
    if gltf::is_gltf_path(path) {
        if let Some((name, _)) = defines.first() {
            return Err(SceneError::Gltf {
                path: path.into(),
                pointer: String::new(),
                message: format!("-D {name}=…: only Mitsuba scenes (.xml) take parameters"),
            });
        }
        let loaded = gltf::load_gltf_scene(path, &options.gltf)?;
        for w in &loaded.warnings {
            eprintln!("warning: {w}");
        }
        return Ok(loaded.into_loaded());
    }
    if mitsuba::is_mitsuba_path(path) {
        let loaded = mitsuba::load_mitsuba_scene(path, defines)?;
        for w in &loaded.warnings {
            eprintln!("warning: {w}");
        }
        return Ok(loaded.into_loaded());
    }
    if let Some((name, _)) = defines.first() {
        return Err(SceneError::Invalid {
            path: path.into(),
            place: load::Place { line: 1, column: 1 },
            message: format!("-D {name}=…: only Mitsuba scenes (.xml) take parameters"),
        });
    }
    load_toml_scene(path)
}

/// The geometry of an object.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Analytic sphere (world space).
    Sphere(Sphere),
    /// Analytic quad (world space).
    Quad(Quad),
    /// Analytic disk, circular or elliptic (world space).
    Disk(Disk),
    /// Analytic open cylinder (world space).
    Cylinder(Cylinder),
    /// An instance of `Scene::meshes[mesh]`.
    Mesh {
        /// Index into `Scene::meshes`.
        mesh: u32,
        /// Object to world.
        transform: Transform,
        /// Interpolate vertex normals (else flat facets).
        smooth: bool,
    },
}

/// One object of the scene: an instance in the top level of the accelerators.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Name (from the file, or generated) for messages.
    pub name: String,
    /// Geometry.
    pub shape: Shape,
    /// Index into `Scene::materials`.
    pub material: u32,
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Camera.
    pub camera: Camera,
    /// Materials, referenced by index.
    pub materials: Vec<Material>,
    /// Lights.
    pub lights: Vec<Light>,
    /// Distinct meshes (a file used by several objects is loaded once).
    pub meshes: Vec<Arc<Mesh>>,
    /// Objects (the top-level instances).
    pub objects: Vec<Object>,
    /// Participating media bounded by the objects (Mitsuba's `<medium>`);
    /// empty: the scene is in vacuum (the TOML water's medium is
    /// [`water_medium`](Self::water_medium)).
    pub media: Media,
    /// Ambient light (multiplied by each material's ambient colour; the
    /// Whitted integrator's term).
    pub ambient: Vec3A,
    /// The TOML `[medium]`: exponential fog and a scattering volume inside
    /// the water region.
    pub water_medium: Option<Medium>,
}

/// Shading data at a hit, in world space.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    /// Hit point.
    pub p: Vec3A,
    /// Absolute error bound of `p` (for `offset_ray_origin`).
    pub p_error: Vec3A,
    /// Unit geometric normal (outward for closed shapes; not flipped toward the ray).
    pub ng: Vec3A,
    /// Unit shading normal, on the same side as `ng` (normal-mapped where
    /// the material has a normal map).
    pub ns: Vec3A,
    /// Texture coordinates. Like `dpdu` and `dpdv`, computed only where the
    /// material reads them ([`MaterialTextures::uses_uv`]); zero elsewhere.
    pub uv: Vec2,
    /// `∂p/∂u` (world space; the tangent that normal maps follow).
    pub dpdu: Vec3A,
    /// `∂p/∂v` (world space).
    pub dpdv: Vec3A,
    /// Ray parameter of the hit.
    pub t: f32,
    /// Object index.
    pub object: u32,
    /// Material index.
    pub material: u32,
}

impl Scene {
    /// Bounds of object `i` in world space.
    pub fn object_bounds(&self, i: usize) -> Aabb {
        match &self.objects[i].shape {
            Shape::Sphere(s) => s.bounds(),
            Shape::Quad(q) => q.bounds(),
            Shape::Disk(d) => d.bounds(),
            Shape::Cylinder(c) => c.bounds(),
            Shape::Mesh { mesh, transform, .. } => transform.bounds(&self.meshes[*mesh as usize].bounds()),
        }
    }

    /// True when the scene needs `integrator::volpath`: it has media, or
    /// surfaces rays pass straight through (`null`, thin dielectrics, the
    /// holes of blends) that shadow rays cross too ([`PassThrough::Volumetric`],
    /// Mitsuba's `volpath`). Elsewhere such surfaces are delta bounces,
    /// which every integrator handles.
    pub fn is_volumetric(&self) -> bool {
        !self.media.is_empty()
            || (self.media.pass_through == PassThrough::Volumetric
                && self
                    .materials
                    .iter()
                    .any(|m| m.null || m.is_thin_sheet() || m.has_holes()))
    }

    /// Bounds of the whole scene.
    pub fn bounds(&self) -> Aabb {
        (0..self.objects.len()).fold(Aabb::EMPTY, |b, i| b.union(self.object_bounds(i)))
    }

    /// The distinct images the materials' textures read.
    pub fn texture_images(&self) -> Vec<Arc<crate::texture::Image>> {
        let mut out: Vec<Arc<crate::texture::Image>> = Vec::new();
        for m in &self.materials {
            for (_, t) in m.textures.iter().flat_map(|t| t.all()) {
                if let Some(image) = t.image() {
                    if !out.iter().any(|o| Arc::ptr_eq(o, image)) {
                        out.push(image.clone());
                    }
                }
            }
        }
        out
    }

    /// Number of triangles the objects reference, counting every instance.
    pub fn instanced_triangles(&self) -> u64 {
        self.objects
            .iter()
            .map(|o| match &o.shape {
                Shape::Mesh { mesh, .. } => self.meshes[*mesh as usize].triangles.len() as u64,
                _ => 0,
            })
            .sum()
    }

    /// Turns an accelerator hit into shading data (pbrt's `Intersect` /
    /// Mitsuba's `compute_surface_interaction`): both backends report only
    /// `(t, instance, prim, u, v)`, and this is the one place that interprets it.
    pub fn surface_interaction(&self, ray: &Ray, hit: &Hit) -> SurfaceInteraction {
        let object = &self.objects[hit.instance as usize];
        let material = &self.materials[object.material as usize];
        let textures = material.textures.as_deref();
        let normal_map = textures.and_then(|t| t.normal_map.as_ref());
        let bump_map = textures.and_then(|t| t.bump_map.as_ref());
        // The parametrisation costs trigonometry on spheres: only when read.
        let wants_uv = material.uses_uv();
        // The mesh's interpolated tangent, when it has tangents and a normal map reads them.
        let mut tangent: Option<Vec4> = None;
        let (p, p_error, ng, ns, uv, dpdu, dpdv) = match &object.shape {
            Shape::Sphere(s) => {
                let (p, n, err) = s.surface(ray, hit.t);
                let (uv, dpdu, dpdv) = if wants_uv {
                    s.uv(p)
                } else {
                    (Vec2::ZERO, Vec3A::ZERO, Vec3A::ZERO)
                };
                (p, err, n, n, uv, dpdu, dpdv)
            }
            Shape::Quad(q) => {
                let (p, err) = q.surface(hit.u, hit.v);
                (p, err, q.normal, q.normal, Vec2::new(hit.u, hit.v), q.u, q.v)
            }
            Shape::Disk(d) => {
                // The hit's (u, v) are the local coordinates (x, y).
                let (p, err) = d.surface(hit.u, hit.v);
                let (uv, dpdu, dpdv) = if wants_uv {
                    d.uv(hit.u, hit.v)
                } else {
                    (Vec2::ZERO, Vec3A::ZERO, Vec3A::ZERO)
                };
                (p, err, d.normal, d.normal, uv, dpdu, dpdv)
            }
            Shape::Cylinder(c) => {
                let (p, n, err) = c.surface(ray, hit.t);
                let (uv, dpdu, dpdv) = if wants_uv {
                    c.uv(p)
                } else {
                    (Vec2::ZERO, Vec3A::ZERO, Vec3A::ZERO)
                };
                (p, err, n, n, uv, dpdu, dpdv)
            }
            Shape::Mesh {
                mesh,
                transform,
                smooth,
            } => {
                let mesh = &self.meshes[*mesh as usize];
                let prim = hit.prim as usize;
                let tri = mesh.triangles[prim];
                let [p0, p1, p2] = mesh.corners(prim);
                let (b1, b2) = (hit.u, hit.v);
                let b0 = 1.0 - b1 - b2;
                // Barycentric reconstruction: error γ(7)Σ|bᵢpᵢ| (pbrt-v4 §6.8.5).
                let p_obj = p0 * b0 + p1 * b1 + p2 * b2;
                let err_obj = ((p0 * b0).abs() + (p1 * b1).abs() + (p2 * b2).abs()) * crate::math::gamma(7);
                let ng_obj = (p1 - p0).cross(p2 - p0);
                let ng = transform.normal(ng_obj).normalize_or(Vec3A::Z);
                let ns = if *smooth {
                    let n = |i: u32| Vec3A::from(mesh.normals[i as usize]);
                    let ns_obj = n(tri[0]) * b0 + n(tri[1]) * b1 + n(tri[2]) * b2;
                    let ns = transform.normal(ns_obj).normalize_or(ng);
                    if ns.dot(ng) < 0.0 {
                        -ns
                    } else {
                        ns
                    }
                } else {
                    ng
                };
                // As on spheres: the parametrisation only when read (a
                // frame and two transformed vectors per hit otherwise).
                let (uv, dpdu, dpdv) = if wants_uv {
                    let [t0, t1, t2] = mesh.corner_uvs(prim);
                    let uv = t0 * b0 + t1 * b1 + t2 * b2;
                    // ∂p/∂u and ∂p/∂v from the triangle's edges and UV
                    // differences (pbrt-v4 §6.5.3), any frame when degenerate.
                    let (duv02, duv12) = (t0 - t2, t1 - t2);
                    let (dp02, dp12) = (p0 - p2, p1 - p2);
                    let det = duv02.x * duv12.y - duv02.y * duv12.x;
                    let (dpdu, dpdv) = if det.abs() < 1e-12 {
                        let f = crate::math::Frame::from_normal(ng_obj.normalize_or(Vec3A::Z));
                        (f.to_world(Vec3A::X), f.to_world(Vec3A::Y))
                    } else {
                        let inv = 1.0 / det;
                        (
                            (dp02 * duv12.y - dp12 * duv02.y) * inv,
                            (dp12 * duv02.x - dp02 * duv12.x) * inv,
                        )
                    };
                    (uv, transform.vector(dpdu), transform.vector(dpdv))
                } else {
                    (Vec2::ZERO, Vec3A::ZERO, Vec3A::ZERO)
                };
                if normal_map.is_some() && !mesh.tangents.is_empty() {
                    let t = |i: u32| mesh.tangents[i as usize];
                    let sign = t(tri[0]).w;
                    let xyz = t(tri[0]).truncate() * b0 + t(tri[1]).truncate() * b1 + t(tri[2]).truncate() * b2;
                    tangent = Some(Vec4::from((transform.vector(Vec3A::from(xyz)), sign)));
                }
                (
                    transform.point(p_obj),
                    transform.point_error(p_obj, err_obj),
                    ng,
                    ns,
                    uv,
                    dpdu,
                    dpdv,
                )
            }
        };
        let ns = match normal_map {
            None => ns,
            Some(map) => {
                let (t, sign) = match tangent {
                    Some(t) => (Vec3A::from(t.truncate()), t.w),
                    None => (dpdu, 1.0),
                };
                perturbed_normal(ns, ng, t, sign, map, uv)
            }
        };
        let ns = match bump_map {
            None => ns,
            Some(bump) => bumped_normal(ns, ng, dpdu, dpdv, bump, uv),
        };
        SurfaceInteraction {
            p,
            p_error,
            ng,
            ns,
            uv,
            dpdu,
            dpdv,
            t: hit.t,
            object: hit.instance,
            material: object.material,
        }
    }
}

/// The shading normal `ns` tilted by a bump map, as Mitsuba 3's `bumpmap`:
/// the height gradient `g = scale · ∇h(u, v)` replaces the normal
/// component of the surface's derivatives, `∂p/∂u' = ∂p/∂u + ns (g_u −
/// ns·∂p/∂u)` (likewise for `v`; the texture-space derivative of the
/// normal itself is neglected), and the normal is `∂p/∂u' × ∂p/∂v'`,
/// normalised and turned to `ng`'s side.
fn bumped_normal(ns: Vec3A, ng: Vec3A, dpdu: Vec3A, dpdv: Vec3A, bump: &material::BumpMap, uv: Vec2) -> Vec3A {
    let g = bump.texture.eval_scalar_grad(uv) * bump.scale;
    let du = dpdu + ns * (g.x - ns.dot(dpdu));
    let dv = dpdv + ns * (g.y - ns.dot(dpdv));
    match du.cross(dv).try_normalize() {
        Some(n) if n.dot(ng) < 0.0 => -n,
        Some(n) => n,
        None => ns,
    }
}

/// The shading normal `ns` bent by a tangent-space normal map: the map's
/// `n = 2·rgb − 1` (x, y scaled) on the frame `(t, b, ns)`, `t` the tangent
/// made orthogonal to `ns` (Gram–Schmidt) and `b = sign · ns × t`, as
/// Mitsuba's `normalmap` and glTF's tangent space. The result is kept on
/// `ng`'s side.
fn perturbed_normal(ns: Vec3A, ng: Vec3A, tangent: Vec3A, sign: f32, map: &material::NormalMap, uv: Vec2) -> Vec3A {
    let t = (tangent - ns * ns.dot(tangent)).try_normalize();
    let Some(t) = t else { return ns };
    let b = ns.cross(t) * sign;
    let m = map.texture.eval(uv) * 2.0 - Vec3A::ONE;
    let n = (t * (m.x * map.scale) + b * (m.y * map.scale) + ns * m.z).normalize_or(ns);
    if n.dot(ng) * ns.dot(ng) < 0.0 {
        // A map bending the normal past the surface: keep the surface's side.
        (n - ng * (2.0 * n.dot(ng))).normalize_or(ns)
    } else {
        n
    }
}
