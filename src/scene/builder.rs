//! The format-neutral scene builder.
//!
//! Every front end (TOML, Mitsuba XML, glTF) reads its own syntax and checks
//! each value where it is written; it then hands the parts of the scene
//! (camera, materials, meshes, objects, lights, media, settings) to a
//! [`SceneBuilder`], each part with the [`Origin`] it was read from.
//! [`SceneBuilder::build`] checks once, for every format, how the parts fit
//! together (references, a normal map's need for texture coordinates, media
//! interfaces) and names the origin of the part at fault. The builder never
//! looks inside an origin: a TOML or XML place and a glTF JSON pointer read
//! the same to it.

use crate::geometry::Mesh;
use crate::math::Vec3A;
use crate::scene::load::{Place, SceneError};
use crate::scene::{Camera, Light, LoadedScene, Material, Media, Object, RenderSettings, Scene, Shape};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a part of a scene was read from, as the front end that read it
/// names places. Errors about the part are reported there.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// A line and column of a text file (TOML, XML).
    Text {
        /// The file.
        path: PathBuf,
        /// The line and column.
        place: Place,
    },
    /// A JSON pointer (RFC 6901) into a glTF file; empty for the whole file.
    Json {
        /// The `.gltf` or `.glb` file.
        path: PathBuf,
        /// The pointer.
        pointer: String,
    },
    /// The file as a whole.
    File {
        /// The file.
        path: PathBuf,
    },
}

impl Origin {
    /// An error about the part read here.
    pub fn error(&self, message: impl Into<String>) -> SceneError {
        let message = message.into();
        match self {
            Origin::Text { path, place } => SceneError::Invalid {
                path: path.clone(),
                place: *place,
                message,
            },
            Origin::Json { path, pointer } => SceneError::Gltf {
                path: path.clone(),
                pointer: pointer.clone(),
                message,
            },
            Origin::File { path } => SceneError::Scene {
                path: path.clone(),
                message,
            },
        }
    }
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Origin::Text { path, place } => write!(f, "{}:{place}", path.display()),
            Origin::Json { path, pointer } if !pointer.is_empty() => write!(f, "{}: {pointer}", path.display()),
            Origin::Json { path, .. } | Origin::File { path } => write!(f, "{}", path.display()),
        }
    }
}

/// The parts of a scene as a front end reads them, checked together by
/// [`build`](SceneBuilder::build).
#[derive(Debug)]
pub struct SceneBuilder {
    file: Origin,
    settings: RenderSettings,
    ambient: Vec3A,
    camera: Option<Camera>,
    materials: Vec<(Material, Origin)>,
    meshes: Vec<Arc<Mesh>>,
    objects: Vec<(Object, Origin)>,
    lights: Vec<(Light, Origin)>,
    media: Media,
}

impl SceneBuilder {
    /// An empty scene read from `file` (where errors about the scene as a
    /// whole are reported).
    pub fn new(file: &Path) -> SceneBuilder {
        SceneBuilder {
            file: Origin::File { path: file.into() },
            settings: RenderSettings::default(),
            ambient: Vec3A::ZERO,
            camera: None,
            materials: Vec::new(),
            meshes: Vec::new(),
            objects: Vec::new(),
            lights: Vec::new(),
            media: Media::default(),
        }
    }

    /// The render settings the file asks for.
    pub fn set_settings(&mut self, settings: RenderSettings) {
        self.settings = settings;
    }

    /// The ambient light (the Whitted integrator's term).
    pub fn set_ambient(&mut self, ambient: Vec3A) {
        self.ambient = ambient;
    }

    /// The camera.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = Some(camera);
    }

    /// Adds a material; objects refer to it by the index returned.
    pub fn add_material(&mut self, material: Material, origin: Origin) -> u32 {
        self.materials.push((material, origin));
        self.materials.len() as u32 - 1
    }

    /// Adds a mesh; mesh shapes refer to it by the index returned.
    pub fn add_mesh(&mut self, mesh: Arc<Mesh>) -> u32 {
        self.meshes.push(mesh);
        self.meshes.len() as u32 - 1
    }

    /// Adds an object (shape and material) read at `origin`.
    pub fn add_object(&mut self, object: Object, origin: Origin) {
        self.objects.push((object, origin));
    }

    /// Adds a light read at `origin`.
    pub fn add_light(&mut self, light: Light, origin: Origin) {
        self.lights.push((light, origin));
    }

    /// The participating media and the objects' interfaces with them.
    pub fn set_media(&mut self, media: Media) {
        self.media = media;
    }

    /// The scene, once every part refers to parts that exist and what a
    /// material needs from a shape is there. Errors name the part's origin.
    pub fn build(self) -> Result<LoadedScene, SceneError> {
        let Some(camera) = self.camera.clone() else {
            return Err(self.file.error("the scene has no camera"));
        };
        for (object, origin) in &self.objects {
            let material = self.materials.get(object.material as usize).ok_or_else(|| {
                origin.error(format!(
                    "object `{}` uses material #{}, but the scene has {} material(s)",
                    object.name,
                    object.material,
                    self.materials.len()
                ))
            })?;
            if let Shape::Mesh { mesh, .. } = &object.shape {
                let mesh = self.meshes.get(*mesh as usize).ok_or_else(|| {
                    origin.error(format!(
                        "object `{}` uses mesh #{mesh}, but the scene has {} mesh(es)",
                        object.name,
                        self.meshes.len()
                    ))
                })?;
                check_map_frame(&material.0, mesh, &object.name, origin)?;
            }
        }
        self.check_media()?;
        let scene = Scene {
            camera,
            materials: self.materials.into_iter().map(|(m, _)| m).collect(),
            lights: self.lights.into_iter().map(|(l, _)| l).collect(),
            meshes: self.meshes,
            objects: self.objects.into_iter().map(|(o, _)| o).collect(),
            media: self.media,
            ambient: self.ambient,
            water_medium: None,
        };
        Ok(LoadedScene {
            scene,
            settings: self.settings,
        })
    }

    /// Every interface names a medium that exists, and there is one
    /// interface per object when there are any.
    fn check_media(&self) -> Result<(), SceneError> {
        let media = &self.media;
        let count = media.list.len();
        let exists = |m: Option<u32>| m.is_none_or(|m| (m as usize) < count);
        if !media.interfaces.is_empty() && media.interfaces.len() != self.objects.len() {
            return Err(self.file.error(format!(
                "{} medium interface(s) for {} object(s)",
                media.interfaces.len(),
                self.objects.len()
            )));
        }
        for (interface, (object, origin)) in media.interfaces.iter().zip(&self.objects) {
            if !exists(interface.interior) || !exists(interface.exterior) {
                return Err(origin.error(format!(
                    "object `{}` is bounded by a medium that does not exist (the scene has {count})",
                    object.name
                )));
            }
        }
        if !exists(media.camera) {
            return Err(self.file.error(format!(
                "the camera is in a medium that does not exist (the scene has {count})"
            )));
        }
        Ok(())
    }
}

/// A normal map needs a tangent frame: texture coordinates or tangents; a
/// bump map differentiates the height along the texture coordinates.
fn check_map_frame(material: &Material, mesh: &Mesh, object: &str, origin: &Origin) -> Result<(), SceneError> {
    let Some(textures) = &material.textures else {
        return Ok(());
    };
    let bumped = textures.bump_map.is_some() && mesh.uvs.is_empty();
    let normal_mapped = textures.normal_map.is_some() && mesh.uvs.is_empty() && mesh.tangents.is_empty();
    if bumped || normal_mapped {
        return Err(origin.error(format!(
            "material `{}` has a {} map, but mesh `{}` of object `{object}` has no texture coordinates to orient it",
            material.name,
            if bumped { "bump" } else { "normal" },
            mesh.name
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{MaterialTextures, MediumInterface, NormalMap};
    use crate::texture::Texture;

    fn text(line: usize) -> Origin {
        Origin::Text {
            path: "scene.toml".into(),
            place: Place { line, column: 3 },
        }
    }

    fn builder() -> SceneBuilder {
        let mut b = SceneBuilder::new(Path::new("scene.toml"));
        b.set_camera(Camera::new(glam::Vec3A::new(0.0, 5.0, 0.0), glam::Vec3A::ZERO, glam::Vec3A::Z, 45.0).unwrap());
        b
    }

    fn square(uvs: bool) -> Arc<Mesh> {
        let mesh = crate::geometry::generate::grid(1, 1, 1.0, 1.0);
        let count = mesh.positions.len();
        Arc::new(if uvs {
            mesh.with_uvs(vec![glam::Vec2::ZERO; count]).unwrap()
        } else {
            mesh
        })
    }

    fn mesh_object(mesh: u32, material: u32) -> Object {
        Object {
            name: "thing".into(),
            shape: Shape::Mesh {
                mesh,
                transform: crate::math::Transform::IDENTITY,
                smooth: true,
            },
            material,
        }
    }

    #[test]
    fn a_consistent_scene_builds() {
        let mut b = builder();
        let m = b.add_material(Material::diffuse("white", glam::Vec3A::ONE), text(1));
        let mesh = b.add_mesh(square(true));
        b.add_object(mesh_object(mesh, m), text(2));
        let scene = b.build().unwrap();
        assert_eq!(scene.scene.objects.len(), 1);
        assert_eq!(scene.scene.materials[0].name, "white");
    }

    #[test]
    fn errors_name_the_origin_of_the_part_at_fault() {
        let mut b = builder();
        b.add_material(Material::diffuse("white", glam::Vec3A::ONE), text(1));
        let mesh = b.add_mesh(square(true));
        b.add_object(mesh_object(mesh, 7), text(9));
        let e = b.build().unwrap_err().to_string();
        assert!(e.starts_with("scene.toml:9:3: object `thing` uses material #7"), "{e}");

        let mut b = builder();
        let m = b.add_material(Material::diffuse("white", glam::Vec3A::ONE), text(1));
        b.add_object(mesh_object(3, m), text(4));
        let e = b.build().unwrap_err().to_string();
        assert!(e.starts_with("scene.toml:4:3: object `thing` uses mesh #3"), "{e}");

        let e = SceneBuilder::new(Path::new("a.xml")).build().unwrap_err().to_string();
        assert_eq!(e, "a.xml: the scene has no camera");
    }

    #[test]
    fn a_normal_map_needs_texture_coordinates() {
        for (uvs, json) in [(false, true), (false, false), (true, false)] {
            let mut b = builder();
            let mut material = Material::diffuse("bumpy", glam::Vec3A::ONE);
            material.textures = Some(Box::new(MaterialTextures {
                normal_map: Some(NormalMap {
                    texture: Texture::Constant(glam::Vec3A::new(0.5, 0.5, 1.0)),
                    scale: 1.0,
                }),
                ..Default::default()
            }));
            let m = b.add_material(material, text(1));
            let mesh = b.add_mesh(square(uvs));
            let origin = if json {
                Origin::Json {
                    path: "model.gltf".into(),
                    pointer: "/nodes/2".into(),
                }
            } else {
                text(6)
            };
            b.add_object(mesh_object(mesh, m), origin);
            match (uvs, b.build()) {
                (true, Ok(_)) => {}
                (false, Err(e)) => {
                    let e = e.to_string();
                    let at = if json {
                        "model.gltf: /nodes/2: "
                    } else {
                        "scene.toml:6:3: "
                    };
                    assert!(e.starts_with(at) && e.contains("has a normal map"), "{e}");
                }
                (uvs, r) => panic!("uvs {uvs}: {r:?}"),
            }
        }
    }

    #[test]
    fn interfaces_name_media_that_exist() {
        let mut b = builder();
        let m = b.add_material(Material::diffuse("white", glam::Vec3A::ONE), text(1));
        let mesh = b.add_mesh(square(true));
        b.add_object(mesh_object(mesh, m), text(5));
        b.set_media(Media {
            interfaces: vec![MediumInterface {
                interior: Some(0),
                exterior: None,
            }],
            ..Default::default()
        });
        let e = b.build().unwrap_err().to_string();
        assert!(
            e.starts_with("scene.toml:5:3: object `thing` is bounded by a medium"),
            "{e}"
        );
    }
}
