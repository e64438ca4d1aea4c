//! `<transform>`: `translate`, `rotate`, `scale`, `matrix` and `lookat`
//! composed as Mitsuba composes them, each operation applied after the ones
//! before it (`M = op · M`).

use super::values::{numbers, vector3};
use super::xml::Element;
use crate::math::{Vec3, Vec4};
use crate::scene::load::SceneError;
use glam::{Mat3, Mat4};

/// The matrix of a `<transform>` element.
pub fn parse_transform(element: &Element) -> Result<Mat4, SceneError> {
    element.only_attrs(&["name"])?;
    let mut m = Mat4::IDENTITY;
    for op in &element.children {
        let origin = &op.origin;
        let step = match op.tag.as_str() {
            "translate" => {
                op.only_attrs(&["x", "y", "z", "value"])?;
                Mat4::from_translation(components(op, 0.0)?)
            }
            "scale" => {
                op.only_attrs(&["x", "y", "z", "value"])?;
                let s = match op.attr("value") {
                    Some(v) => {
                        let n = numbers(v).map_err(|e| origin.error(format!("<scale value>: {e}")))?;
                        match n.as_slice() {
                            [s] => Vec3::splat(*s),
                            [x, y, z] => Vec3::new(*x, *y, *z),
                            _ => return Err(origin.error("<scale value> takes one or three numbers")),
                        }
                    }
                    None => components(op, 1.0)?,
                };
                Mat4::from_scale(s)
            }
            "rotate" => {
                op.only_attrs(&["x", "y", "z", "value", "angle"])?;
                let axis = components(op, 0.0)?;
                let angle = number_attr(op, "angle")?.unwrap_or(0.0);
                let axis = axis
                    .try_normalize()
                    .ok_or_else(|| origin.error("<rotate> needs a non-zero axis (x, y, z or value)"))?;
                Mat4::from_axis_angle(axis, angle.to_radians())
            }
            "matrix" => {
                op.only_attrs(&["value"])?;
                let n = numbers(op.required("value")?).map_err(|e| origin.error(format!("<matrix value>: {e}")))?;
                match n.len() {
                    16 => Mat4::from_cols_slice(&n).transpose(),
                    9 => Mat4::from_mat3(Mat3::from_cols_slice(&n).transpose()),
                    k => return Err(origin.error(format!("<matrix value> has {k} numbers; it takes 16 (or 9)"))),
                }
            }
            "lookat" => {
                op.only_attrs(&["origin", "target", "up"])?;
                let vec = |name: &str| -> Result<Option<Vec3>, SceneError> {
                    op.attr(name)
                        .map(|v| vector3(v).map_err(|e| origin.error(format!("<lookat {name}>: {e}"))))
                        .transpose()
                };
                let (Some(eye), Some(target)) = (vec("origin")?, vec("target")?) else {
                    return Err(origin.error("<lookat> needs `origin` and `target`"));
                };
                lookat(eye, target, vec("up")?).ok_or_else(|| {
                    origin.error("<lookat>: `origin` equals `target`, or `up` is parallel to the view direction")
                })?
            }
            other => {
                return Err(origin.error(format!(
                    "<{other}> inside <transform>: expected translate, rotate, scale, matrix or lookat"
                )))
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(element.origin.error("the transform is not finite"));
    }
    Ok(m)
}

/// Mitsuba's `Transform::look_at`: columns (left, up, forward, origin);
/// without `up`, any vector perpendicular to the view.
pub fn lookat(origin: Vec3, target: Vec3, up: Option<Vec3>) -> Option<Mat4> {
    let dir = (target - origin).try_normalize()?;
    let up = up.unwrap_or_else(|| dir.any_orthonormal_vector());
    let left = up.cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        Vec4::from((origin, 1.0)),
    ))
}

/// `x`, `y`, `z` attributes (each `default` when absent) or `value="x, y, z"`.
fn components(op: &Element, default: f32) -> Result<Vec3, SceneError> {
    if let Some(v) = op.attr("value") {
        if op.attr("x").or(op.attr("y")).or(op.attr("z")).is_some() {
            return Err(op.origin.error(format!("<{}> takes either `value` or x, y, z", op.tag)));
        }
        return vector3(v).map_err(|e| op.origin.error(format!("<{} value>: {e}", op.tag)));
    }
    Ok(Vec3::new(
        number_attr(op, "x")?.unwrap_or(default),
        number_attr(op, "y")?.unwrap_or(default),
        number_attr(op, "z")?.unwrap_or(default),
    ))
}

fn number_attr(op: &Element, name: &str) -> Result<Option<f32>, SceneError> {
    op.attr(name)
        .map(|v| match numbers(v) {
            Ok(n) if n.len() == 1 => Ok(n[0]),
            Ok(_) => Err(op
                .origin
                .error(format!("<{} {name}=\"{v}\">: expected one number", op.tag))),
            Err(e) => Err(op.origin.error(format!("<{} {name}>: {e}", op.tag))),
        })
        .transpose()
}
