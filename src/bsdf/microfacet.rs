//! Microfacet distributions, isotropic, in the local shading frame (+z is
//! the macro normal): GGX (Trowbridge–Reitz) and Beckmann (Walter et al.
//! 2007, "Microfacet Models for Refraction through Rough Surfaces"). Each
//! gives the distribution of normals `D`, Smith's masking `G1`
//! (shadowing–masking taken separable, `G = G1(wi) G1(wo)`, as in Mitsuba
//! 3), and a sampling of normals: for GGX the normals visible from a
//! direction (Heitz 2018, "Sampling the GGX Distribution of Visible
//! Normals", JCGT 7(4)), for Beckmann `D(m) cos θm` (Walter et al. 2007,
//! eq. 28).

use crate::math::{Vec2, Vec3A};
pub use crate::scene::MicrofacetDistribution;
use std::f32::consts::PI;

/// Roughnesses below this are treated as smooth (a delta lobe).
pub const SMOOTH_ALPHA: f32 = 1.0e-4;

/// A distribution with roughness `alpha` (the slope's standard deviation
/// scale; the `alpha` of Mitsuba and pbrt, not a "perceptual" roughness),
/// possibly anisotropic: `alpha` along the frame's x axis (the surface's
/// `∂p/∂u`), `alpha_y` along its y axis (Mitsuba's `alpha_u`, `alpha_v`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    /// GGX or Beckmann.
    pub distribution: MicrofacetDistribution,
    /// Roughness along x.
    pub alpha: f32,
    /// Roughness along y (`alpha` when isotropic).
    pub alpha_y: f32,
}

impl Microfacet {
    /// An isotropic `distribution` of roughness `alpha`.
    pub fn isotropic(distribution: MicrofacetDistribution, alpha: f32) -> Self {
        Self {
            distribution,
            alpha,
            alpha_y: alpha,
        }
    }

    /// GGX of roughness `alpha`.
    pub fn ggx(alpha: f32) -> Self {
        Self::isotropic(MicrofacetDistribution::Ggx, alpha)
    }

    /// Roughness differs along x and y.
    #[inline]
    pub fn is_anisotropic(&self) -> bool {
        self.alpha != self.alpha_y
    }

    /// Density of microfacet normals `m` (per steradian, projected:
    /// `∫ D(m) cos θm dm = 1`).
    pub fn d(&self, m: Vec3A) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let d = if self.is_anisotropic() {
            // x²/αx² + y²/αy² is tan²θ/α(φ)² times cos²θ.
            let (ax, ay) = (self.alpha, self.alpha_y);
            let slopes = (m.x / ax) * (m.x / ax) + (m.y / ay) * (m.y / ay);
            match self.distribution {
                MicrofacetDistribution::Ggx => {
                    let s = slopes + m.z * m.z;
                    1.0 / (PI * ax * ay * s * s)
                }
                MicrofacetDistribution::Beckmann => {
                    let cos2 = m.z * m.z;
                    (-slopes / cos2).exp() / (PI * ax * ay * cos2 * cos2)
                }
            }
        } else {
            let a2 = self.alpha * self.alpha;
            match self.distribution {
                MicrofacetDistribution::Ggx => {
                    let s = (m.x * m.x + m.y * m.y) / a2 + m.z * m.z;
                    1.0 / (PI * a2 * s * s)
                }
                MicrofacetDistribution::Beckmann => {
                    let cos2 = m.z * m.z;
                    let tan2 = (m.x * m.x + m.y * m.y) / cos2;
                    (-tan2 / a2).exp() / (PI * a2 * cos2 * cos2)
                }
            }
        };
        // Far tails underflow to garbage in f32; they carry no energy.
        if d * m.z > 1.0e-20 {
            d
        } else {
            0.0
        }
    }

    /// Smith's masking of microfacet `m` seen from `v`; 0 when `v` sees the
    /// back of `m` or `m` from the other side of the macro surface.
    pub fn g1(&self, v: Vec3A, m: Vec3A) -> f32 {
        if v.dot(m) * v.z <= 0.0 {
            return 0.0;
        }
        // α(φ)² tan²θ, with α(φ)² = cos²φ αx² + sin²φ αy².
        let xy = if self.is_anisotropic() {
            self.alpha * self.alpha * v.x * v.x + self.alpha_y * self.alpha_y * v.y * v.y
        } else {
            self.alpha * self.alpha * (v.x * v.x + v.y * v.y)
        };
        if xy == 0.0 {
            return 1.0;
        }
        let tan2 = xy / (v.z * v.z);
        match self.distribution {
            MicrofacetDistribution::Ggx => 2.0 / (1.0 + (1.0 + tan2).sqrt()),
            MicrofacetDistribution::Beckmann => {
                // Walter et al. 2007, eq. 27's rational fit in a = 1/(α tan θ),
                // as Mitsuba 3 evaluates it.
                let a = 1.0 / tan2.sqrt();
                if a >= 1.6 {
                    1.0
                } else {
                    (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
                }
            }
        }
    }

    /// Shadowing–masking of `wi` and `wo` by `m`.
    pub fn g(&self, wi: Vec3A, wo: Vec3A, m: Vec3A) -> f32 {
        self.g1(wi, m) * self.g1(wo, m)
    }

    /// Height-correlated Smith masking–shadowing (Heitz 2014, eq. 99),
    /// `1 / (1 + Λ(wi) + Λ(wo))` with `G1 = 1 / (1 + Λ)`: the form glTF's
    /// `V_GGX` and Cycles use; it masks less than the separable product.
    pub fn g_correlated(&self, wi: Vec3A, wo: Vec3A, m: Vec3A) -> f32 {
        let (gi, go) = (self.g1(wi, m), self.g1(wo, m));
        if gi <= 0.0 || go <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 / gi + 1.0 / go - 1.0)
    }

    /// Density (solid angle of `m`) with which [`sample_normal`](Self::sample_normal)
    /// draws `m` seen from `v`: for GGX the visible normals,
    /// `G1(v, m) |v·m| D(m) / |cos θv|`; for Beckmann `D(m) cos θm`.
    pub fn pdf_normal(&self, v: Vec3A, m: Vec3A) -> f32 {
        match self.distribution {
            MicrofacetDistribution::Ggx => {
                if v.z == 0.0 {
                    return 0.0;
                }
                self.g1(v, m) * v.dot(m).abs() * self.d(m) / v.z.abs()
            }
            MicrofacetDistribution::Beckmann => self.d(m) * m.z.max(0.0),
        }
    }

    /// A microfacet normal for light leaving toward `v` (either hemisphere;
    /// the result is in the upper one), density [`pdf_normal`](Self::pdf_normal).
    pub fn sample_normal(&self, v: Vec3A, u: Vec2) -> Vec3A {
        match self.distribution {
            MicrofacetDistribution::Ggx => self.sample_visible_ggx(v, u),
            MicrofacetDistribution::Beckmann if self.is_anisotropic() => {
                // Slopes of the stretched Gaussian: the isotropic sample's
                // slope scaled by αx, αy (D cos θm stays the density).
                let r = (-(1.0 - u.x).max(f32::MIN_POSITIVE).ln()).sqrt();
                let phi = 2.0 * PI * u.y;
                let (sx, sy) = (self.alpha * r * phi.cos(), self.alpha_y * r * phi.sin());
                Vec3A::new(-sx, -sy, 1.0).normalize()
            }
            MicrofacetDistribution::Beckmann => {
                // tan² θm = −α² ln(1 − u) (Walter et al. 2007, eq. 28).
                let tan2 = -self.alpha * self.alpha * (1.0 - u.x).max(f32::MIN_POSITIVE).ln();
                let cos = 1.0 / (1.0 + tan2).sqrt();
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                Vec3A::new(sin * phi.cos(), sin * phi.sin(), cos.max(1.0e-6)).normalize()
            }
        }
    }

    fn sample_visible_ggx(&self, v: Vec3A, u: Vec2) -> Vec3A {
        let v = if v.z < 0.0 { -v } else { v };
        // To the hemisphere configuration (Heitz 2018, §3.2).
        let vh = Vec3A::new(self.alpha * v.x, self.alpha_y * v.y, v.z).normalize();
        let len2 = vh.x * vh.x + vh.y * vh.y;
        let t1 = if len2 > 0.0 {
            Vec3A::new(-vh.y, vh.x, 0.0) / len2.sqrt()
        } else {
            Vec3A::X
        };
        let t2 = vh.cross(t1);
        // Uniform point on the projected half disk (§4.2).
        let r = u.x.sqrt();
        let phi = 2.0 * PI * u.y;
        let p1 = r * phi.cos();
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        // Back to the ellipsoid configuration (§3.4).
        Vec3A::new(self.alpha * nh.x, self.alpha_y * nh.y, nh.z.max(1.0e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampling::uniform_sphere;
    use crate::math::{rng::Domain, Rng};

    #[test]
    fn d_is_normalised_and_visible_normals_integrate_to_one() {
        let mut rng = Rng::new(3, Domain::Analysis, 0, 0);
        for ((alpha, alpha_y), distribution) in [
            (0.05f32, 0.05f32),
            (0.2, 0.2),
            (0.6, 0.6),
            (1.0, 1.0),
            (0.2, 0.6),
            (0.7, 0.25),
        ]
        .into_iter()
        .flat_map(|a| [(a, MicrofacetDistribution::Ggx), (a, MicrofacetDistribution::Beckmann)])
        {
            let g = Microfacet {
                distribution,
                alpha,
                alpha_y,
            };
            let n = 400_000;
            // ∫ D(m) cos θm dm by uniform sphere sampling.
            let mut projected = 0.0f64;
            let mut visible = 0.0f64;
            let v = Vec3A::new(0.6, 0.0, 0.8);
            for _ in 0..n {
                let (a, b) = rng.f32x2();
                let m = uniform_sphere(Vec2::new(a, b));
                projected += (g.d(m) * m.z.max(0.0) * 4.0 * PI) as f64;
                visible += (g.pdf_normal(v, m) * 4.0 * PI) as f64;
            }
            let (p, vis) = (projected / n as f64, visible / n as f64);
            let tol = if alpha < 0.1 { 0.15 } else { 0.03 };
            assert!((p - 1.0).abs() < tol, "{distribution:?} {alpha}: ∫D cos = {p}");
            assert!((vis - 1.0).abs() < tol, "{distribution:?} {alpha}: ∫ pdf = {vis}");
        }
    }
}
