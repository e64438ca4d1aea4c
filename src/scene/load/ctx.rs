//! The file being checked ([`Ctx`]): spans turned into places, and the checks
//! of single values (finite numbers, vectors, colours, reflectances, keys
//! that apply to an object's type, required keys).

use super::error::{Place, SceneError};
use crate::math::Vec3A;
use crate::scene::desc::{Spanned, TextureDesc, Vec2Desc, Vec3Desc};
use crate::texture::{ColourSpace, Image};
use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest magnitude of a coordinate, length or colour: squares of such
/// values stay finite in single precision (1e36 < 3.4e38).
pub const MAX_MAGNITUDE: f64 = 1e18;

/// The file being checked: turns spans into places.
pub(super) struct Ctx<'a> {
    pub(super) text: &'a str,
    pub(super) path: &'a Path,
    /// The `[textures]` table.
    pub(super) textures: &'a BTreeMap<String, Spanned<TextureDesc>>,
    /// Images decoded so far, by canonical path and colour space.
    pub(super) images: RefCell<HashMap<(PathBuf, ColourSpace), Arc<Image>>>,
}

impl Ctx<'_> {
    pub(super) fn place(&self, span: Range<usize>) -> Place {
        Place::of_offset(self.text, span.start)
    }

    pub(super) fn invalid(&self, span: Range<usize>, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            path: self.path.into(),
            place: self.place(span),
            message: message.into(),
        }
    }

    /// A finite number of bounded magnitude, as f32.
    pub(super) fn number(&self, s: &Spanned<f64>, key: &str) -> Result<f32, SceneError> {
        self.check_finite(*s.get_ref(), s.span(), key)
    }

    /// The two finite numbers of a `size = [w, h]` value.
    pub(super) fn finite_size(&self, size: &Spanned<Vec2Desc>) -> Result<(f32, f32), SceneError> {
        let Vec2Desc([w, h]) = *size.get_ref();
        Ok((
            self.check_finite(w, size.span(), "size")?,
            self.check_finite(h, size.span(), "size")?,
        ))
    }

    pub(super) fn check_finite(&self, x: f64, span: Range<usize>, key: &str) -> Result<f32, SceneError> {
        if x.is_nan() {
            return Err(self.invalid(span, format!("`{key}` is NaN: numbers must be finite")));
        }
        if x.is_infinite() {
            return Err(self.invalid(span, format!("`{key}` is infinite: numbers must be finite")));
        }
        if x.abs() > MAX_MAGNITUDE {
            return Err(self.invalid(
                span,
                format!("`{key}` = {x:e} is too large (limit ±{MAX_MAGNITUDE:e}, so that squares stay finite)"),
            ));
        }
        Ok(x as f32)
    }

    pub(super) fn vec3(&self, s: &Spanned<Vec3Desc>, key: &str) -> Result<Vec3A, SceneError> {
        let [x, y, z] = s.get_ref().0;
        let c = |v| self.check_finite(v, s.span(), key);
        Ok(Vec3A::new(c(x)?, c(y)?, c(z)?))
    }

    pub(super) fn opt_vec3(
        &self,
        s: &Option<Spanned<Vec3Desc>>,
        key: &str,
        default: Vec3A,
    ) -> Result<Vec3A, SceneError> {
        s.as_ref().map_or(Ok(default), |s| self.vec3(s, key))
    }

    /// A vector that must have a direction.
    pub(super) fn direction(&self, s: &Spanned<Vec3Desc>, key: &str) -> Result<Vec3A, SceneError> {
        let v = self.vec3(s, key)?;
        if v.length_squared() == 0.0 {
            return Err(self.invalid(
                s.span(),
                format!("`{key}` is the zero vector: it must have a direction"),
            ));
        }
        Ok(v)
    }

    /// A colour: finite, non-negative.
    pub(super) fn colour(&self, s: &Spanned<Vec3Desc>, key: &str) -> Result<Vec3A, SceneError> {
        let c = self.vec3(s, key)?;
        if c.min_element() < 0.0 {
            return Err(self.invalid(s.span(), format!("`{key}` has a negative component: colours are ≥ 0")));
        }
        Ok(c)
    }

    /// Rejects keys that exist for another `type` but not this one.
    pub(super) fn only_keys(
        &self,
        what: &str,
        present: &[(&str, Option<Range<usize>>)],
        allowed: &[&str],
    ) -> Result<(), SceneError> {
        for (key, span) in present {
            if let Some(span) = span {
                if !allowed.contains(key) {
                    return Err(self.invalid(
                        span.clone(),
                        format!("`{key}` does not apply to {what} (its keys: {})", allowed.join(", ")),
                    ));
                }
            }
        }
        Ok(())
    }

    pub(super) fn required<'d, T>(
        &self,
        value: &'d Option<Spanned<T>>,
        key: &str,
        what: &str,
        at: Range<usize>,
    ) -> Result<&'d Spanned<T>, SceneError> {
        value
            .as_ref()
            .ok_or_else(|| self.invalid(at, format!("{what} needs `{key}`")))
    }
}
