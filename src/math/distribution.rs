//! Piecewise-constant distributions for importance sampling (pbrt-v4
//! §A.1.2, `PiecewiseConstant1D` / `PiecewiseConstant2D`): a tabulated
//! function over `[0, 1]` or `[0, 1]²`, sampled by inverting its running sums.

use super::Vec2;

/// A piecewise-constant density over `[0, 1]` with `n` equal cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// Cell values (≥ 0).
    func: Vec<f32>,
    /// Running integral, `cdf[0] = 0`, `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// `∫ func` over `[0, 1]` (the mean of the cells).
    integral: f32,
}

impl Distribution1D {
    /// The distribution of `func` (negative or non-finite values count as
    /// 0); a function that is 0 everywhere becomes uniform.
    pub fn new(func: &[f32]) -> Self {
        let n = func.len().max(1);
        let func: Vec<f32> = (0..n)
            .map(|i| {
                func.get(i)
                    .copied()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .unwrap_or(0.0)
            })
            .collect();
        let mut cdf = vec![0.0f32; n + 1];
        // Summed in f64: millions of small cells lose bits in f32.
        let mut acc = 0.0f64;
        for i in 0..n {
            acc += f64::from(func[i]) / n as f64;
            cdf[i + 1] = acc as f32;
        }
        let integral = acc as f32;
        if integral > 0.0 {
            for c in &mut cdf[1..] {
                *c = (f64::from(*c) / acc) as f32;
            }
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f32 / n as f32;
            }
        }
        cdf[n] = 1.0;
        Self { func, cdf, integral }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// True for a distribution of no cells (never: `new` makes at least one).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// `∫ func` over `[0, 1]`.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// `(x, pdf, cell)` for `u ∈ [0, 1)`: `x` in the cell where the running
    /// integral passes `u`, linearly within it.
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        // The last cell whose cdf start is ≤ u.
        let cell = (self.cdf.partition_point(|&c| c <= u).max(1) - 1).min(n - 1);
        let (c0, c1) = (self.cdf[cell], self.cdf[cell + 1]);
        let du = if c1 > c0 { (u - c0) / (c1 - c0) } else { 0.5 };
        let x = ((cell as f32 + du.clamp(0.0, 1.0)) / n as f32).min(1.0 - f32::EPSILON / 2.0);
        (x, self.pdf_of_cell(cell), cell)
    }

    /// Density at `x ∈ [0, 1]`.
    pub fn pdf(&self, x: f32) -> f32 {
        let n = self.func.len();
        self.pdf_of_cell(((x * n as f32) as usize).min(n - 1))
    }

    fn pdf_of_cell(&self, cell: usize) -> f32 {
        if self.integral > 0.0 {
            self.func[cell] / self.integral
        } else {
            1.0
        }
    }
}

/// A piecewise-constant density over `[0, 1]²` of `nu × nv` cells: a
/// marginal over rows (`v`) and a conditional per row (`u`).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// From row-major cell values, `nu` per row.
    pub fn new(func: &[f32], nu: usize, nv: usize) -> Self {
        let rows: Vec<Distribution1D> = (0..nv)
            .map(|v| Distribution1D::new(&func[v * nu..(v + 1) * nu]))
            .collect();
        let marginal = Distribution1D::new(&rows.iter().map(Distribution1D::integral).collect::<Vec<_>>());
        Self { rows, marginal }
    }

    /// `∫∫ func` over `[0, 1]²`.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// `(uv, pdf)` for `u ∈ [0, 1)²`.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample(u.y);
        let (x, pdf_u, _) = self.rows[row].sample(u.x);
        (Vec2::new(x, v), pdf_u * pdf_v)
    }

    /// Density at `uv ∈ [0, 1]²`.
    pub fn pdf(&self, uv: Vec2) -> f32 {
        let n = self.rows.len();
        let row = ((uv.y * n as f32) as usize).min(n - 1);
        self.marginal.pdf_of_cell(row) * self.rows[row].pdf(uv.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_dimension_samples_its_cells_in_proportion() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, f32::NAN]);
        assert!((d.integral() - 1.0).abs() < 1e-6);
        // Cell 0 has a quarter of the mass, cell 2 three quarters.
        let (x, pdf, cell) = d.sample(0.1);
        assert_eq!(cell, 0);
        assert!((x - 0.1).abs() < 1e-6 && (pdf - 1.0).abs() < 1e-6);
        let (x, pdf, cell) = d.sample(0.625);
        assert_eq!(cell, 2);
        assert!((x - 0.625).abs() < 1e-6 && (pdf - 3.0).abs() < 1e-6, "{x} {pdf}");
        assert_eq!(d.pdf(0.3), 0.0);
        assert!((d.pdf(0.6) - 3.0).abs() < 1e-6);
        // All zero: uniform.
        let z = Distribution1D::new(&[0.0, 0.0]);
        assert_eq!(z.sample(0.7).0, 0.7);
        assert_eq!(z.pdf(0.2), 1.0);
    }

    /// The 2D density integrates to 1 and sampling follows it (a chi-square
    /// test over the cells, 5 % significance with 15 degrees of freedom).
    #[test]
    fn two_dimensions_pdf_integrates_to_one_and_matches_sampling() {
        let (nu, nv) = (4, 4);
        let func: Vec<f32> = (0..nu * nv).map(|i| ((i * 7) % 5) as f32 + 0.5).collect();
        let d = Distribution2D::new(&func, nu, nv);
        let mut total = 0.0;
        for v in 0..nv {
            for u in 0..nu {
                total += d.pdf(Vec2::new((u as f32 + 0.5) / 4.0, (v as f32 + 0.5) / 4.0)) / 16.0;
            }
        }
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        let n = 200_000;
        let mut counts = vec![0u32; nu * nv];
        let mut rng = crate::math::Rng::new(1, crate::math::rng::Domain::Analysis, 0, 0);
        for _ in 0..n {
            let (uv, pdf) = d.sample(Vec2::new(rng.f32(), rng.f32()));
            assert!((pdf - d.pdf(uv)).abs() < 1e-4 * pdf.max(1.0));
            let cell = (uv.y * 4.0) as usize * nu + (uv.x * 4.0) as usize;
            counts[cell] += 1;
        }
        let sum: f32 = func.iter().sum();
        let chi2: f64 = counts
            .iter()
            .zip(&func)
            .map(|(&c, &f)| {
                let expected = f64::from(f / sum) * n as f64;
                (f64::from(c) - expected).powi(2) / expected
            })
            .sum();
        assert!(chi2 < 25.0, "chi-square {chi2}");
    }
}
