//! Warps from the unit square (pbrt-v4 ch. A.5).

use super::{Vec2, Vec3A};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric map of the square onto the unit disk (Shirley & Chiu 1997).
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction about +z (Malley's method); pdf = cos θ / π.
pub fn cosine_hemisphere(u: Vec2) -> Vec3A {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3A::new(d.x, d.y, z)
}

/// Uniform direction on the unit sphere; pdf = 1 / (4π).
pub fn uniform_sphere(u: Vec2) -> Vec3A {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Uniform direction in the cone of half-angle `acos(cos_max)` about +z;
/// pdf = 1 / (2π (1 − cos_max)).
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3A {
    let cos_t = (1.0 - u.x) + u.x * cos_max;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3A::new(phi.cos() * sin_t, phi.sin() * sin_t, cos_t)
}

/// Jittered point of stratum `index` in an `nx × ny` grid over the unit square.
pub fn stratified(index: u32, nx: u32, ny: u32, jitter: Vec2) -> Vec2 {
    let (ix, iy) = (index % nx, (index / nx) % ny);
    Vec2::new((ix as f32 + jitter.x) / nx as f32, (iy as f32 + jitter.y) / ny as f32)
}

/// A pseudo-random permutation of `0..len` keyed by `seed`: the image of
/// `index` (Kensler 2013, "Correlated Multi-Jittered Sampling", `permute`;
/// a cycle-walking hash, bijective on `0..len`). Visiting strata in this
/// order makes any prefix of a pixel's samples a uniformly random subset of
/// its strata, so a pixel that stops early (adaptive sampling, a time
/// limit) is still unbiased.
pub fn permute(index: u32, len: u32, seed: u32) -> u32 {
    let l = len.max(1);
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    let p = seed;
    let mut i = index;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dcb303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e501cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860a3df);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    ((i as u64 + p as u64) % l as u64) as u32
}

/// Sample `index` of `count` of a stratified sample of the unit cube laid
/// along the Morton (Z-order) curve: `t = (index + ξ) / count`, with `ξ` the
/// 64-bit fraction `xi / 2⁶⁴`, is uniform in the sample's stratum of
/// [0, 1); the curve maps uniform `t` to the uniform cube (de-interleaving
/// the bits of `t` gives each axis independent uniform bits), so the
/// `count` samples together stratify the cube and every point of it has
/// the uniform density: estimators stay unbiased. Consecutive indices land
/// in neighbouring cells, which is the point: the rays built from them are
/// coherent (caches, traversal). `t` gives 21 bits per axis; `jitter`
/// places the point uniformly inside that finest cell.
pub fn morton_stratified(index: u64, count: u64, xi: u64, jitter: [f32; 3]) -> [f32; 3] {
    debug_assert!(index < count);
    let count = count.max(1) as u128;
    let t = ((((index as u128) << 64) | xi as u128) / count).min(u64::MAX as u128) as u64;
    // Bit 63 − 3l − a of t is bit 20 − l of axis a: axis a takes every
    // third bit of t >> (1 + (2 − a)), gathered by `compact_every_third`.
    let cell = [
        compact_every_third(t >> 3),
        compact_every_third(t >> 2),
        compact_every_third(t >> 1),
    ];
    let scale = 1.0 / (1u32 << 21) as f32;
    let mut out = [0.0f32; 3];
    for a in 0..3 {
        // Below 1 even when rounding would reach it.
        out[a] = ((cell[a] as f32 + jitter[a]) * scale).min(1.0 - f32::EPSILON / 2.0);
    }
    out
}

/// Bits 0, 3, 6, …, 60 of `x` packed into the low 21 bits (the inverse of
/// a 3-D Morton interleave; the magic-mask sequence of Baert's "Morton
/// encoding/decoding through bit interleaving").
#[inline]
fn compact_every_third(x: u64) -> u32 {
    let mut x = x & 0x1249_2492_4924_9249;
    x = (x ^ (x >> 2)) & 0x10c3_0c30_c30c_30c3;
    x = (x ^ (x >> 4)) & 0x100f_00f0_0f00_f00f;
    x = (x ^ (x >> 8)) & 0x001f_0000_ff00_00ff;
    x = (x ^ (x >> 16)) & 0x001f_0000_0000_ffff;
    x = (x ^ (x >> 32)) & 0x1f_ffff;
    x as u32
}

/// The 3-D Morton code of `cell` (21 bits per axis): bit `l` of axis `a`
/// goes to bit `3l + 2 − a`, so sorting by the code orders cells along a
/// Z-order curve (axis 0 the most significant of each triple, as in
/// [`morton_stratified`]).
pub fn morton_code(cell: [u32; 3]) -> u64 {
    (spread_every_third(cell[0]) << 2) | (spread_every_third(cell[1]) << 1) | spread_every_third(cell[2])
}

/// The low 21 bits of `x` moved to bits 0, 3, 6, …, 60 (the inverse of
/// [`compact_every_third`]).
#[inline]
fn spread_every_third(x: u32) -> u64 {
    let mut x = (x & 0x1f_ffff) as u64;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// A near-square grid `nx × ny` with `nx·ny = n` exactly when n has such a
/// factorisation, else the closest from below (nx = ⌊√n⌋, ny = ⌈n/nx⌉).
pub fn grid_for(n: u32) -> (u32, u32) {
    let n = n.max(1);
    let mut nx = (n as f32).sqrt() as u32;
    while nx > 1 && !n.is_multiple_of(nx) {
        nx -= 1;
    }
    (nx.max(1), n / nx.max(1))
}

/// The cell of an `nx × ny` grid that position `s` of a per-`seed` visiting
/// order takes (row-major index). Every full cycle of `nx·ny` positions
/// visits each cell once, in any case. When both sides are powers of two,
/// the order is the Owen-scrambled Sobol (0,2)-sequence's (points `s` of
/// dimensions 0 and 1, `sobol_burley`): its first `2^k` points form a
/// (0,k,2)-net, so every power-of-two prefix is itself stratified over the
/// whole grid (Owen 1997; Kollig & Keller 2002). A pixel that stops after
/// a few samples (adaptive sampling, a time limit) then has its light
/// samples spread over the light, not bunched in one row of strata.
/// Otherwise it is a random permutation ([`permute`]): prefixes are
/// uniformly random subsets.
pub fn stratum_order(s: u32, nx: u32, ny: u32, seed: u32) -> u32 {
    let (nx, ny) = (nx.max(1), ny.max(1));
    let n = nx * ny;
    let s = s % n;
    if nx.is_power_of_two() && ny.is_power_of_two() && n <= 1 << 16 {
        let x = (sobol_burley::sample(s, 0, seed) * nx as f32) as u32;
        let y = (sobol_burley::sample(s, 1, seed) * ny as f32) as u32;
        y.min(ny - 1) * nx + x.min(nx - 1)
    } else {
        permute(s, n, seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};

    #[test]
    fn stratum_order_visits_every_cell_once_and_prefixes_spread() {
        for &(nx, ny) in &[(1, 1), (2, 1), (4, 4), (8, 4), (16, 16), (5, 4), (3, 7), (64, 64)] {
            for seed in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; (nx * ny) as usize];
                for s in 0..nx * ny {
                    let c = stratum_order(s, nx, ny, seed) as usize;
                    assert!(!seen[c], "{nx}×{ny} seed {seed}: cell {c} twice");
                    seen[c] = true;
                }
            }
        }
        // Power-of-two grids: the first 4 positions of a 16 × 16 grid fall
        // in the 4 quadrants, the first 16 in the 16 blocks of 4 × 4 cells.
        for seed in 0..20u32 {
            for (count, side) in [(4u32, 2u32), (16, 4)] {
                let mut blocks = vec![false; count as usize];
                for s in 0..count {
                    let c = stratum_order(s, 16, 16, seed);
                    let (x, y) = (c % 16, c / 16);
                    let b = ((y * side / 16) * side + x * side / 16) as usize;
                    assert!(!blocks[b], "seed {seed}: prefix {count} has two cells in block {b}");
                    blocks[b] = true;
                }
            }
        }
    }

    #[test]
    fn permute_is_a_bijection_for_every_length() {
        for len in [1u32, 2, 3, 7, 16, 20, 33, 1000] {
            for seed in [0u32, 1, 0xdead_beef] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute(i, len, seed);
                    assert!(j < len && !seen[j as usize], "len {len} seed {seed}: {i} -> {j}");
                    seen[j as usize] = true;
                }
            }
        }
        // Different seeds give different orders.
        let order = |seed| (0..16).map(|i| permute(i, 16, seed)).collect::<Vec<_>>();
        assert_ne!(order(1), order(2));
    }

    #[test]
    fn compact_every_third_gathers_every_third_bit() {
        let mut r = Rng::new(5, Domain::Analysis, 0, 0);
        for _ in 0..1000 {
            let x = r.u64();
            let want = (0..21).fold(0u32, |acc, i| acc | ((((x >> (3 * i)) & 1) as u32) << i));
            assert_eq!(compact_every_third(x), want, "{x:#x}");
        }
    }

    #[test]
    fn morton_code_interleaves_and_round_trips() {
        let mut r = Rng::new(6, Domain::Analysis, 0, 0);
        for _ in 0..1000 {
            let cell = [r.u32() & 0x1f_ffff, r.u32() & 0x1f_ffff, r.u32() & 0x1f_ffff];
            let code = morton_code(cell);
            assert_eq!(
                [
                    compact_every_third(code >> 2),
                    compact_every_third(code >> 1),
                    compact_every_third(code)
                ],
                cell
            );
        }
        assert_eq!(morton_code([1, 0, 0]), 4);
        assert_eq!(morton_code([0, 1, 1]), 3);
        assert_eq!(morton_code([2, 0, 0]), 32);
    }

    #[test]
    fn morton_stratified_samples_are_uniform_stratified_and_coherent() {
        let mut r = Rng::new(4, Domain::Analysis, 0, 0);
        let n = 1u64 << 12;
        let mut counts = [0u32; 64];
        let mut max_step = 0.0f32;
        let mut prev: Option<[f32; 3]> = None;
        for i in 0..n {
            let p = morton_stratified(i, n, r.u64(), [r.f32(), r.f32(), r.f32()]);
            assert!(p.iter().all(|&c| (0.0..1.0).contains(&c)), "{p:?}");
            // 4 × 4 × 4 cells: stratified, every cell gets exactly n / 64.
            let cell = |c: f32| (c * 4.0) as usize;
            counts[cell(p[0]) * 16 + cell(p[1]) * 4 + cell(p[2])] += 1;
            if let Some(q) = prev {
                if i % 64 != 0 {
                    let d = (0..3).map(|a| (p[a] - q[a]).abs()).fold(0.0, f32::max);
                    max_step = max_step.max(d);
                }
            }
            prev = Some(p);
        }
        assert!(counts.iter().all(|&c| c == (n / 64) as u32), "{counts:?}");
        // An aligned run of 64 consecutive samples shares the top 6 bits of
        // t, hence one cell of side 1/4: consecutive samples are near.
        assert!(max_step <= 0.25, "{max_step}");
        // Odd counts: still all in [0, 1) and the mean is 1/2.
        let m = 1001u64;
        let mean: f64 = (0..m)
            .map(|i| morton_stratified(i, m, r.u64(), [r.f32(), r.f32(), r.f32()])[1] as f64)
            .sum::<f64>()
            / m as f64;
        assert!((mean - 0.5).abs() < 0.01, "{mean}");
    }

    #[test]
    fn cosine_hemisphere_mean_cos_is_two_thirds() {
        let mut r = Rng::new(3, Domain::Analysis, 0, 0);
        let n = 200_000;
        let mean: f64 = (0..n)
            .map(|_| {
                let (a, b) = r.f32x2();
                cosine_hemisphere(Vec2::new(a, b)).z as f64
            })
            .sum::<f64>()
            / n as f64;
        // E[cos θ] under pdf cos θ/π is 2/3.
        assert!((mean - 2.0 / 3.0).abs() < 0.005, "{mean}");
    }

    #[test]
    fn warps_give_unit_vectors() {
        for (a, b) in [(0.1, 0.9), (0.5, 0.5), (0.0, 0.0), (0.99, 0.01)] {
            let u = Vec2::new(a, b);
            assert!((uniform_sphere(u).length() - 1.0).abs() < 1e-5);
            assert!((cosine_hemisphere(u).length() - 1.0).abs() < 1e-5);
            assert!((uniform_cone(u, 0.5).length() - 1.0).abs() < 1e-5);
            assert!(uniform_cone(u, 0.5).z >= 0.5 - 1e-6);
        }
    }

    #[test]
    fn grids_cover_n() {
        assert_eq!(grid_for(32), (4, 8));
        assert_eq!(grid_for(16), (4, 4));
        assert_eq!(grid_for(7), (1, 7));
        assert_eq!(grid_for(1), (1, 1));
    }
}
