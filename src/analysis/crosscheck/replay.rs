//! Replay strings: a ray and its `t_max` as seven f32 values that read back
//! to the same bits.

use crate::math::{Ray, Vec3A};
use thiserror::Error;

/// The replay string of a ray: `ox,oy,oz,dx,dy,dz,t_max`, each f32 in Rust's
/// shortest round-trip `{:e}` notation (`inf` for an unbounded query).
pub fn format_ray(ray: &Ray, t_max: f32) -> String {
    let o = ray.origin;
    let d = ray.dir;
    format!(
        "{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
        o.x, o.y, o.z, d.x, d.y, d.z, t_max
    )
}

/// A replay string that cannot be read.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum ReplayParseError {
    /// Not 6 or 7 comma-separated values.
    #[error("expected \"ox,oy,oz,dx,dy,dz[,t_max]\", got {0} values")]
    Count(usize),
    /// A value is not a number.
    #[error("value {index} ('{text}') is not a number")]
    Number {
        /// 1-based position.
        index: usize,
        /// The text.
        text: String,
    },
    /// Non-finite origin or direction, zero direction, or t_max not > 0.
    #[error("{0}")]
    Invalid(&'static str),
}

/// Reads a replay string (see [`format_ray`]); `t_max` defaults to ∞.
pub fn parse_ray(text: &str) -> Result<(Ray, f32), ReplayParseError> {
    let parts: Vec<&str> = text.trim().trim_matches('"').split(',').map(str::trim).collect();
    if parts.len() != 6 && parts.len() != 7 {
        return Err(ReplayParseError::Count(parts.len()));
    }
    let mut v = [f32::INFINITY; 7];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p.parse::<f32>().map_err(|_| ReplayParseError::Number {
            index: i + 1,
            text: (*p).to_string(),
        })?;
    }
    let origin = Vec3A::new(v[0], v[1], v[2]);
    let dir = Vec3A::new(v[3], v[4], v[5]);
    if !origin.is_finite() || !dir.is_finite() {
        return Err(ReplayParseError::Invalid("origin and direction must be finite"));
    }
    if dir == Vec3A::ZERO {
        return Err(ReplayParseError::Invalid("the direction is zero"));
    }
    let positive = v[6] > 0.0; // false for NaN too
    if !positive {
        return Err(ReplayParseError::Invalid("t_max must be > 0"));
    }
    Ok((Ray::new(origin, dir), v[6]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replay_strings_round_trip_and_reject_garbage() {
        let ray = Ray::new(Vec3A::new(0.1, -1e-30, 3.4028235e38), Vec3A::new(1.0 / 3.0, 0.0, -0.7));
        for t_max in [f32::INFINITY, 1.1754944e-38, 2.5] {
            let s = format_ray(&ray, t_max);
            let (back, t) = parse_ray(&s).unwrap();
            assert_eq!(back, ray);
            assert_eq!(t.to_bits(), t_max.to_bits());
        }
        assert_eq!(parse_ray("1,2,3,0,0,1").unwrap().1, f32::INFINITY);
        assert_eq!(parse_ray("1,2,3"), Err(ReplayParseError::Count(3)));
        assert!(matches!(
            parse_ray("1,2,x,0,0,1"),
            Err(ReplayParseError::Number { index: 3, .. })
        ));
        assert!(matches!(parse_ray("1,2,3,0,0,0"), Err(ReplayParseError::Invalid(_))));
        assert!(matches!(parse_ray("1,2,NaN,0,0,1"), Err(ReplayParseError::Invalid(_))));
        assert!(matches!(parse_ray("1,2,3,0,0,1,-1"), Err(ReplayParseError::Invalid(_))));
    }
}
