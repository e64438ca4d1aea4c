//! The photon map: photon positions in kiddo's immutable k-d tree (built
//! once, balanced, leaf buckets of [`BUCKET`] points), and per photon a
//! compact record of its power and incoming direction.
//!
//! Memory per photon (the record layout of Jensen, *Realistic Image
//! Synthesis Using Photon Mapping*, §6.3, which packs power as Ward's RGBE
//! and the direction in two bytes; here the direction gets 4 bytes):
//!
//! | what | bytes |
//! |---|---|
//! | position, in the tree's leaves (3 × f32) | 12 |
//! | photon index, in the tree's leaves (u32) | 4 |
//! | power, RGBE shared exponent (Ward 1991) | 4 |
//! | incoming direction, octahedral 2 × u16 (Cigolle et al. 2014) | 4 |
//! | tree stems and leaf extents (≈ 12 bytes per 64-photon leaf) | ≈ 0.2 |
//!
//! about 24.2 bytes per stored photon ([`BYTES_PER_PHOTON`]). Only for the
//! debug overlay (`--debug photons`), the map also keeps a coarse position
//! per photon (3 × u16 over the map's bounds, 6 bytes). While the map
//! is built, kiddo also holds the source positions (12 B) and a sort index
//! (8 B, `usize`): the peak is [`PEAK_BYTES_PER_PHOTON`].
//!
//! A map built for progressive photon mapping's fixed-radius gathers
//! ([`PhotonMap::build_with_grid`]) holds a hashed grid instead of the
//! tree: positions (12 B), records (8 B) and a hash table of the occupied
//! cells (16 B per slot, at most three quarters full), about 22–24 bytes
//! per photon on the Cornell box.

use super::chunked::{chunk_depth, ChunkedTree};
use super::grid::PhotonGrid;
use crate::math::{Aabb, Mat3A, Vec3A};
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use rayon::prelude::*;

/// The tree stores positions rotated by this fixed rotation (queries are
/// rotated alike; distances, hence the k nearest, are unchanged). Why:
/// kiddo's immutable tree splits on x, y, z in turn at the median and moves
/// the split off runs of equal values, so photons on an axis-aligned floor
/// (all `y = 0`) would make every `y` split degenerate: a lopsided tree,
/// minutes to build and slow to query. No scene plane is aligned with the
/// rotated axes in practice.
pub fn tree_rotation() -> Mat3A {
    Mat3A::from_quat(glam::Quat::from_xyzw(0.31, 0.52, 0.17, 0.78).normalize())
}

/// `p` in the tree's (rotated) coordinates.
#[inline]
pub fn to_tree(rotation: &Mat3A, p: Vec3A) -> [f32; 3] {
    (*rotation * p).to_array()
}

/// Points per leaf of the k-d tree: with the 64-nearest gathers of the
/// irradiance precompute, leaves of 64 mean fewer leaves visited and one
/// build level fewer than 32, while 128 costs more per leaf than it saves
/// (docs/benchmarks-history.md, "The photon pass").
pub const BUCKET: usize = 64;

/// Bytes held per stored photon once the map is built (see the module docs).
pub const BYTES_PER_PHOTON: f64 = 12.0 + 4.0 + 4.0 + 4.0 + 12.0 / BUCKET as f64;

pub use crate::limits::PEAK_BYTES_PER_PHOTON;

/// The k-d tree type: f32 coordinates, u32 photon indices, 3-D.
pub type PhotonTree = ImmutableKdTree<f32, u32, 3, BUCKET>;

/// A photon as traced: full precision, before packing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub position: Vec3A,
    /// Unit direction toward where it came from (`−` its travel direction).
    pub incoming: Vec3A,
    /// Geometric normal of the surface it landed on, turned toward the
    /// side it arrived from (for the precomputed irradiance sites).
    pub normal: Vec3A,
    /// Flux it carries (W per channel).
    pub power: Vec3A,
}

/// A packed photon record: RGBE power and octahedral incoming direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C)]
pub struct PhotonRecord {
    /// Red, green, blue mantissas and the shared exponent (+128).
    pub rgbe: [u8; 4],
    /// Octahedral coordinates of the incoming direction.
    pub dir: [u16; 2],
}

impl PhotonRecord {
    /// Packs power and incoming direction.
    pub fn new(power: Vec3A, incoming: Vec3A) -> Self {
        Self {
            rgbe: encode_rgbe(power),
            dir: encode_octahedral(incoming),
        }
    }

    /// Unpacked power.
    #[inline]
    pub fn power(&self) -> Vec3A {
        decode_rgbe(self.rgbe)
    }

    /// Unpacked unit incoming direction.
    #[inline]
    pub fn incoming(&self) -> Vec3A {
        decode_octahedral(self.dir)
    }

    /// True when the incoming direction is on the side of `n` (`ω·n > 0`),
    /// without normalising the decoded direction (the gather's hot path).
    #[inline]
    pub fn arrives_from_side_of(&self, n: Vec3A) -> bool {
        let x = self.dir[0] as f32 / 65535.0 * 2.0 - 1.0;
        let y = self.dir[1] as f32 / 65535.0 * 2.0 - 1.0;
        let z = 1.0 - x.abs() - y.abs();
        let (x, y) = if z < 0.0 {
            ((1.0 - y.abs()).copysign(x), (1.0 - x.abs()).copysign(y))
        } else {
            (x, y)
        };
        n.x * x + n.y * y + n.z * z > 0.0
    }
}

/// Ward's RGBE shared-exponent colour (Graphics Gems II, "Real Pixels"),
/// with rounding to the nearest mantissa so that sums of many photons are
/// unbiased: `c = m/256 · 2^(e − 128)`; error ≤ 1/256 of the largest
/// channel. Negative or non-finite components are stored as 0.
pub fn encode_rgbe(c: Vec3A) -> [u8; 4] {
    let c = Vec3A::new(clean(c.x), clean(c.y), clean(c.z));
    let max = c.max_element();
    if max < 1e-37 {
        return [0, 0, 0, 0];
    }
    // max = f · 2^e with f in [0.5, 1) (frexp, read off the exponent bits:
    // max is normal here); one more when rounding would carry the largest
    // mantissa to 256. Scaling by 2^(8 − e) is exact, and done in f64 so it
    // cannot overflow; `+ 0.5` then truncation rounds half up (x ≥ 0).
    let mut e = (((max.to_bits() >> 23) & 0xff) as i32 - 126).clamp(-126, 127);
    if (max as f64 * pow2_f64(8 - e) + 0.5) as u32 > 255 && e < 127 {
        e += 1;
    }
    let scale = pow2_f64(8 - e);
    let m = |x: f32| (x as f64 * scale + 0.5).min(255.0) as u8;
    [m(c.x), m(c.y), m(c.z), (e + 128) as u8]
}

/// `2^k` for `|k| ≤ 1022`, built from its bits.
#[inline]
fn pow2_f64(k: i32) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

fn clean(x: f32) -> f32 {
    if x.is_finite() && x > 0.0 {
        x
    } else {
        0.0
    }
}

/// Inverse of [`encode_rgbe`].
#[inline]
pub fn decode_rgbe(rgbe: [u8; 4]) -> Vec3A {
    if rgbe[3] == 0 {
        return Vec3A::ZERO;
    }
    // 2^(e − 128) / 256 = 2^(e − 136), built from its bits (exponent
    // field e − 136 + 127 ≥ 1 for every stored e ≥ 2; e = 1 underflows to
    // a subnormal scale, handled by powi).
    let f = if rgbe[3] >= 10 {
        f32::from_bits(((rgbe[3] as u32) - 9) << 23)
    } else {
        2f32.powi(rgbe[3] as i32 - 136)
    };
    Vec3A::new(rgbe[0] as f32, rgbe[1] as f32, rgbe[2] as f32) * f
}

/// Octahedral encoding of a unit vector (Cigolle et al. 2014, "A Survey of
/// Efficient Representations for Independent Unit Vectors"), 16 bits per
/// coordinate: angular error below 1e-4 rad.
pub fn encode_octahedral(v: Vec3A) -> [u16; 2] {
    let l1 = v.x.abs() + v.y.abs() + v.z.abs();
    if !l1.is_finite() || l1 <= 0.0 {
        return [32768, 32768];
    }
    let (mut x, mut y) = (v.x / l1, v.y / l1);
    if v.z < 0.0 {
        let (ax, ay) = (x.abs(), y.abs());
        x = (1.0 - ay).copysign(x);
        y = (1.0 - ax).copysign(y);
    }
    // Round to nearest by `+ 0.5` and truncation (the value is ≥ 0): no libm call.
    let q = |a: f32| ((a.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0 + 0.5) as u16;
    [q(x), q(y)]
}

/// Inverse of [`encode_octahedral`].
#[inline]
pub fn decode_octahedral(e: [u16; 2]) -> Vec3A {
    let x = e[0] as f32 / 65535.0 * 2.0 - 1.0;
    let y = e[1] as f32 / 65535.0 * 2.0 - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()).copysign(x), (1.0 - x.abs()).copysign(y))
    } else {
        (x, y)
    };
    Vec3A::new(x, y, z).normalize_or(Vec3A::Z)
}

/// Builds the chunked trees over `positions` (already in tree
/// coordinates); see [`super::chunked`] for the returned order.
pub(super) fn build_tree(positions: Vec<[f32; 3]>) -> (ChunkedTree, Vec<u32>) {
    let depth = chunk_depth(positions.len());
    ChunkedTree::build(positions, depth)
}

/// `items` reordered so that `out[j] = items[order[j]]`.
pub(super) fn reorder<T: Copy + Send + Sync>(items: Vec<T>, order: &[u32]) -> Vec<T> {
    order.par_iter().map(|&i| items[i as usize]).collect()
}

/// Bytes held by a [`PhotonTree`] of `n` points: its leaves (positions and
/// indices), stems and leaf extents (kiddo's layout: one f32 stem per
/// power-of-two leaf slot, two u32 per leaf).
pub(super) fn tree_bytes(n: usize) -> usize {
    let leaves = n.div_ceil(BUCKET).max(1);
    let stems = if leaves < 2 { 0 } else { leaves.next_power_of_two() };
    n * (12 + 4) + leaves * 8 + stems * 4
}

/// The photon map.
pub struct PhotonMap {
    pub(super) tree: ChunkedTree,
    pub(super) rotation: Mat3A,
    pub(super) records: Vec<PhotonRecord>,
    /// The hashed grid that answers the gathers instead of the tree, when
    /// the map was built with one ([`PhotonMap::build_with_grid`]).
    pub(super) grid: Option<PhotonGrid>,
    coarse: Vec<[u16; 3]>,
    bounds: Aabb,
    /// Irradiance precomputed at a subset of the photons (Christensen
    /// 1999), when [`PhotonMap::precompute_irradiance`] ran.
    pub(super) precomputed: Option<super::precomputed::PrecomputedIrradiance>,
    /// The photons the path integrator's physically based pass stored where
    /// they scattered in a participating medium (light shafts), when any
    /// did: a map of its own, gathered in 3-D balls.
    pub volume: Option<Box<PhotonMap>>,
}

impl std::fmt::Debug for PhotonMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PhotonMap")
            .field("photons", &self.len())
            .field("bounds", &self.bounds)
            .finish()
    }
}

impl PhotonMap {
    /// Builds the map from positions and their records (same order; the
    /// tree's items are indices into `records`). Consumes the positions:
    /// afterwards they live only in the tree's leaves, and, with
    /// `keep_coarse`, as coarse copies for the debug overlay.
    ///
    /// # Panics
    /// If the lengths differ or there are more than `u32::MAX` photons (the
    /// photon pass never produces either).
    pub fn build(positions: Vec<[f32; 3]>, records: Vec<PhotonRecord>, keep_coarse: bool) -> Self {
        Self::build_with_grid(positions, records, keep_coarse, None)
    }

    /// [`build`](Self::build), or with `grid_radius`, a map whose gathers
    /// a hashed grid for that radius answers instead of the tree
    /// ([`PhotonGrid`]: the same photons as the tree's), for progressive
    /// photon mapping's fixed-radius gathers. Such a map keeps no tree.
    pub fn build_with_grid(
        positions: Vec<[f32; 3]>,
        records: Vec<PhotonRecord>,
        keep_coarse: bool,
        grid_radius: Option<f32>,
    ) -> Self {
        assert_eq!(positions.len(), records.len());
        assert!(positions.len() <= u32::MAX as usize, "too many photons for u32 indices");
        let bounds = positions
            .par_iter()
            .fold(|| Aabb::EMPTY, |b, p| b.grow(Vec3A::from_array(*p)))
            .reduce(|| Aabb::EMPTY, Aabb::union);
        let coarse: Option<Vec<[u16; 3]>> = keep_coarse.then(|| {
            let extent = if bounds.is_empty() {
                Vec3A::ONE
            } else {
                bounds.extent().max(Vec3A::splat(f32::MIN_POSITIVE))
            };
            let scale = Vec3A::splat(65535.0) / extent;
            positions
                .par_iter()
                .map(|p| {
                    let q = ((Vec3A::from_array(*p) - bounds.min) * scale)
                        .round()
                        .clamp(Vec3A::ZERO, Vec3A::splat(65535.0));
                    [q.x as u16, q.y as u16, q.z as u16]
                })
                .collect()
        });
        let rotation = tree_rotation();
        let mut positions = positions;
        positions
            .par_iter_mut()
            .for_each(|p| *p = to_tree(&rotation, Vec3A::from_array(*p)));
        if let Some(r) = grid_radius {
            let (grid, order) = PhotonGrid::build(&positions, r, 0);
            return Self {
                tree: build_tree(Vec::new()).0,
                rotation,
                records: reorder(records, &order),
                grid: Some(grid),
                coarse: coarse.map_or_else(Vec::new, |c| reorder(c, &order)),
                bounds,
                precomputed: None,
                volume: None,
            };
        }
        let (tree, order) = build_tree(positions);
        let records = reorder(records, &order);
        let coarse = coarse.map_or_else(Vec::new, |c| reorder(c, &order));
        Self {
            tree,
            rotation,
            records,
            grid: None,
            coarse,
            bounds,
            precomputed: None,
            volume: None,
        }
    }

    /// Builds a map from unpacked photons (tests, tools).
    pub fn from_photons(photons: &[Photon]) -> Self {
        let positions = photons.iter().map(|p| p.position.to_array()).collect();
        let records = photons.iter().map(|p| PhotonRecord::new(p.power, p.incoming)).collect();
        Self::build(positions, records, true)
    }

    /// Number of stored photons.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// True when no photon was stored.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Bounds of the stored positions.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Bytes held by the map: the tree's leaves (positions and indices),
    /// stems and leaf extents (kiddo's layout: one f32 stem per power-of-two
    /// leaf slot, two u32 per leaf) or the grid that replaces it, the
    /// records and the coarse positions.
    pub fn memory_bytes(&self) -> usize {
        let n = self.len();
        let tree = if self.grid.is_some() { 0 } else { tree_bytes(n) };
        tree + n * std::mem::size_of::<PhotonRecord>()
            + self.coarse.len() * std::mem::size_of::<[u16; 3]>()
            + self.grid.as_ref().map_or(0, |g| g.memory_bytes())
            + self.precomputed.as_ref().map_or(0, |p| p.memory_bytes())
            + self.volume.as_ref().map_or(0, |v| v.memory_bytes())
    }

    /// Total power of all stored photons (f64 accumulation).
    pub fn total_power(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for r in &self.records {
            let p = r.power();
            s[0] += p.x as f64;
            s[1] += p.y as f64;
            s[2] += p.z as f64;
        }
        s
    }

    /// Record of photon `i`.
    pub fn record(&self, i: usize) -> PhotonRecord {
        self.records[i]
    }

    /// Position of photon `i`, quantised to 1/65535 of the map's bounds on
    /// each axis, when the map was built to keep them: for the debug
    /// overlay (the exact positions live in the tree's leaves, which kiddo
    /// does not expose).
    pub fn coarse_position(&self, i: usize) -> Option<Vec3A> {
        let q = self.coarse.get(i)?;
        let t = Vec3A::new(q[0] as f32, q[1] as f32, q[2] as f32) / 65535.0;
        Some(self.bounds.min + (self.bounds.max - self.bounds.min) * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::{Domain, Rng};
    use crate::math::sampling::uniform_sphere;
    use crate::math::Vec2;

    #[test]
    fn rgbe_round_trips_within_its_precision() {
        for c in [
            Vec3A::new(1.0, 0.5, 0.25),
            Vec3A::new(3.7e-7, 1.2e-7, 0.0),
            Vec3A::new(1234.0, 1.0, 900.0),
            Vec3A::splat(0.999),
            Vec3A::new(1e-36, 0.0, 5e-37),
        ] {
            let d = decode_rgbe(encode_rgbe(c));
            let max = c.max_element();
            assert!((d - c).abs().max_element() <= max / 256.0 * 1.001, "{c} → {d}");
        }
        assert_eq!(decode_rgbe(encode_rgbe(Vec3A::ZERO)), Vec3A::ZERO);
        assert_eq!(decode_rgbe(encode_rgbe(Vec3A::new(f32::NAN, -1.0, 0.0))), Vec3A::ZERO);
    }

    #[test]
    fn octahedral_round_trips() {
        let mut rng = Rng::new(1, Domain::Analysis, 0, 0);
        for _ in 0..10_000 {
            let (a, b) = rng.f32x2();
            let v = uniform_sphere(Vec2::new(a, b));
            let d = decode_octahedral(encode_octahedral(v));
            assert!(v.cross(d).length() < 1e-4 && v.dot(d) > 0.0, "{v} → {d}");
            let r = PhotonRecord::new(Vec3A::ONE, v);
            for n in [Vec3A::X, Vec3A::Y, -Vec3A::Z, Vec3A::new(0.6, -0.8, 0.0)] {
                if v.dot(n).abs() > 1e-3 {
                    assert_eq!(r.arrives_from_side_of(n), v.dot(n) > 0.0);
                }
            }
        }
        for v in [Vec3A::X, -Vec3A::X, Vec3A::Y, -Vec3A::Y, Vec3A::Z, -Vec3A::Z] {
            assert!(decode_octahedral(encode_octahedral(v)).dot(v) > 0.99999);
        }
    }

    #[test]
    fn records_are_eight_bytes_and_coarse_positions_are_close() {
        assert_eq!(std::mem::size_of::<PhotonRecord>(), 8);
        const { assert!(BYTES_PER_PHOTON <= 32.0) };
        let photons: Vec<Photon> = (0..1000)
            .map(|i| Photon {
                position: Vec3A::new(i as f32 * 0.01, (i % 7) as f32, -(i as f32).sqrt()),
                incoming: Vec3A::Y,
                normal: Vec3A::Y,
                power: Vec3A::ONE,
            })
            .collect();
        let map = PhotonMap::from_photons(&photons);
        assert_eq!(map.len(), 1000);
        let ext = map.bounds().extent();
        // The map orders its photons its own way: each coarse position is
        // next to exactly one input photon.
        let mut matched = vec![false; photons.len()];
        for i in 0..map.len() {
            let c = map.coarse_position(i).unwrap();
            let (j, p) = photons
                .iter()
                .enumerate()
                .min_by(|a, b| (a.1.position - c).length().total_cmp(&(b.1.position - c).length()))
                .unwrap();
            let err = (c - p.position).abs();
            assert!(err.cmple(ext / 65535.0 + Vec3A::splat(1e-6)).all());
            assert!(!std::mem::replace(&mut matched[j], true), "photon {j} twice");
        }
        assert!((map.total_power()[0] - 1000.0).abs() < 1e-3);
        assert!(map.memory_bytes() as f64 <= 1000.0 * (BYTES_PER_PHOTON + 6.0) + 512.0);
        // Without the overlay's coarse positions: none kept, none counted.
        let positions = photons.iter().map(|p| p.position.to_array()).collect();
        let records = photons.iter().map(|p| PhotonRecord::new(p.power, p.incoming)).collect();
        let lean = PhotonMap::build(positions, records, false);
        assert_eq!(lean.coarse_position(0), None);
        assert!(lean.memory_bytes() as f64 <= 1000.0 * BYTES_PER_PHOTON + 512.0);
        assert_eq!(map.memory_bytes() - lean.memory_bytes(), 6000);
    }
}
