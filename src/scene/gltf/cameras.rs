//! Cameras (glTF 2.0 §3.10): the perspective or orthographic camera a node
//! places (it looks down its node's −z axis, +y up), chosen by `--camera` or the first
//! in the scene, or a camera that frames the model when the file has none.

use super::nodes::Graph;
use super::Ctx;
use crate::math::Vec3A;
use crate::scene::load::SceneError;
use crate::scene::{Camera, Projection, RenderSettings, Scene};
use glam::Vec3;

/// Image height of a model's render, and its width when the camera gives
/// no aspect ratio (4:3).
pub const DEFAULT_HEIGHT: u32 = 600;
/// Image width when the camera gives no aspect ratio.
pub const DEFAULT_WIDTH: u32 = 800;
/// Vertical field of view of the camera that frames a model without one
/// (about that of a 50 mm lens on a full-frame sensor held upright).
pub const DEFAULT_FRAMING_FOV_DEG: f32 = 40.0;
/// Elevation of the framing camera above the model's front (+z), degrees.
pub const DEFAULT_FRAMING_ELEVATION_DEG: f32 = 15.0;

/// Which of the file's cameras to render (`--camera`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CameraChoice {
    /// By index in the file's `cameras`.
    Index(usize),
    /// By the camera's name or the name of the node that places it.
    Name(String),
}

impl std::str::FromStr for CameraChoice {
    type Err = std::convert::Infallible;

    /// A number is an index; anything else a name.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            Ok(i) => CameraChoice::Index(i),
            Err(_) => CameraChoice::Name(s.to_string()),
        })
    }
}

/// A camera replaced once the geometry is known.
pub(super) fn placeholder() -> Camera {
    Camera::new(Vec3A::Z, Vec3A::ZERO, Vec3A::Y, DEFAULT_FRAMING_FOV_DEG).expect("a valid camera")
}

/// Sets `camera` (and the image size in `settings`) from the chosen camera;
/// true when none was placed and the camera frames the model instead.
pub(super) fn choose(
    ctx: &Ctx,
    graph: &Graph,
    scene: &Scene,
    settings: &mut RenderSettings,
    camera: &mut Camera,
) -> Result<bool, SceneError> {
    let doc = ctx.doc;
    let cameras: Vec<gltf::Camera> = doc.cameras().collect();
    let node_name = |i: usize| doc.nodes().nth(i).and_then(|n| n.name().map(str::to_string));
    let placed = match &ctx.options.camera {
        None => graph.cameras.first(),
        Some(choice) => {
            let found = graph.cameras.iter().find(|p| match choice {
                CameraChoice::Index(i) => p.item == *i,
                CameraChoice::Name(n) => {
                    cameras[p.item].name() == Some(n.as_str()) || node_name(p.node).as_deref() == Some(n.as_str())
                }
            });
            if found.is_none() {
                let list: Vec<String> = graph
                    .cameras
                    .iter()
                    .map(|p| match cameras[p.item].name() {
                        Some(n) => format!("{} `{n}`", p.item),
                        None => p.item.to_string(),
                    })
                    .collect();
                return Err(ctx.error(
                    "/cameras",
                    format!(
                        "--camera {}: no such camera placed by the scene (cameras: {})",
                        match choice {
                            CameraChoice::Index(i) => i.to_string(),
                            CameraChoice::Name(n) => n.clone(),
                        },
                        if list.is_empty() {
                            "none".into()
                        } else {
                            list.join(", ")
                        }
                    ),
                ));
            }
            found
        }
    };
    let Some(placed) = placed else {
        *camera = framing(scene, settings.width as f32 / settings.height as f32).ok_or_else(|| {
            ctx.error(
                "",
                "the model's bounds are too large to frame with a camera (its positions reach single \
                 precision's limits): give the file a camera",
            )
        })?;
        return Ok(true);
    };
    let pointer = format!("/cameras/{}", placed.item);
    let w = placed.world;
    let position = Vec3A::from(w.transform_point3(Vec3::ZERO));
    let forward = Vec3A::from(w.transform_vector3(Vec3::NEG_Z));
    let up = Vec3A::from(w.transform_vector3(Vec3::Y));
    let mut c = Camera::new(position, position + forward, up, DEFAULT_FRAMING_FOV_DEG).ok_or_else(|| {
        ctx.error(
            format!("/nodes/{}", placed.node),
            "the node's transform collapses the camera's axes",
        )
    })?;
    let (aspect, znear) = match cameras[placed.item].projection() {
        gltf::camera::Projection::Perspective(perspective) => {
            let yfov = perspective.yfov().to_degrees();
            if !(yfov > 0.0 && yfov < 180.0) {
                return Err(ctx.error(
                    format!("{pointer}/perspective/yfov"),
                    format!("{yfov}°: must be in (0°, 180°)"),
                ));
            }
            c.fov_deg = yfov;
            let aspect = perspective.aspect_ratio();
            if let Some(aspect) = aspect {
                if !(aspect > 0.0 && aspect.is_finite()) {
                    return Err(ctx.error(
                        format!("{pointer}/perspective/aspectRatio"),
                        format!("{aspect}: must be > 0"),
                    ));
                }
            }
            (aspect, perspective.znear())
        }
        gltf::camera::Projection::Orthographic(o) => {
            // §3.10.3: xmag and ymag are the half width and half height of
            // the view (the projection matrix's 1/xmag, 1/ymag); zero would
            // collapse it and a negative one mirror it.
            let (xmag, ymag) = (o.xmag(), o.ymag());
            for (key, v) in [("xmag", xmag), ("ymag", ymag)] {
                if !(v > 0.0 && v.is_finite()) {
                    return Err(ctx.error(
                        format!("{pointer}/orthographic/{key}"),
                        format!("{v}: must be a finite number > 0"),
                    ));
                }
            }
            let aspect = xmag / ymag;
            if !(aspect > 0.0 && aspect.is_finite()) {
                return Err(ctx.error(
                    format!("{pointer}/orthographic"),
                    format!("xmag / ymag = {xmag} / {ymag} is not a usable aspect ratio"),
                ));
            }
            // The image shows at least the xmag × ymag rectangle: at the
            // default size exactly, and with another aspect ratio
            // (`--width`/`--height`) extended, never stretched nor cropped.
            c.projection = Projection::Orthographic {
                half_width: xmag,
                half_height: ymag,
            };
            (Some(aspect), o.znear())
        }
    };
    if let Some(aspect) = aspect {
        settings.height = DEFAULT_HEIGHT;
        settings.width = ((DEFAULT_HEIGHT as f32 * aspect).round() as u32).clamp(1, crate::limits::MAX_IMAGE_SIDE);
    }
    if znear.is_finite() && znear > 0.0 {
        c.near_clip = znear;
    }
    *camera = c;
    Ok(false)
}

/// A camera that frames the scene's bounds as model viewers do: from the
/// model's front (+z, glTF's forward) raised by
/// [`DEFAULT_FRAMING_ELEVATION_DEG`], far enough that the bounding sphere
/// fits the narrower field of view of an image of aspect `aspect`; `None`
/// when the bounds are too large for single precision to place it.
pub fn framing(scene: &Scene, aspect: f32) -> Option<Camera> {
    let b = scene.bounds();
    let (centre, radius) = if b.is_empty() {
        (Vec3A::ZERO, 1.0)
    } else {
        (b.center(), (b.extent().length() * 0.5).max(1e-3))
    };
    let half_v = (DEFAULT_FRAMING_FOV_DEG * 0.5).to_radians();
    let half_h = (half_v.tan() * aspect).atan();
    let half = half_v.min(half_h);
    let distance = radius / half.sin();
    let e = DEFAULT_FRAMING_ELEVATION_DEG.to_radians();
    let dir = Vec3A::new(0.0, e.sin(), e.cos());
    let eye = centre + dir * distance;
    if !(eye.is_finite() && centre.is_finite()) {
        return None;
    }
    Camera::new(eye, centre, Vec3A::Y, DEFAULT_FRAMING_FOV_DEG)
}
