//! The fingerprint's byte encoding: every value written explicitly,
//! little-endian, so that the hash depends on what a render computes and on
//! nothing of how the Rust types spell it (field names, `Debug` text).

use sha2::{Digest, Sha256};

/// Writes values into a SHA-256 in a fixed, explicit byte form.
///
/// Scalars are little-endian; `f32` is hashed by its bits (so `-0.0` and
/// `0.0` differ, as they may in a render); strings and sequences are
/// prefixed with their length, so no two value sequences encode alike.
pub struct Encoder {
    hash: Sha256,
    buffer: Vec<u8>,
}

/// Bytes gathered before a bulk write hands them to the hash.
const BULK: usize = 1 << 16;

impl Default for Encoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Encoder {
    /// An empty encoder.
    pub fn new() -> Self {
        Self {
            hash: Sha256::new(),
            buffer: Vec::with_capacity(BULK),
        }
    }

    /// The hex SHA-256 of everything written.
    pub fn finish(self) -> String {
        self.hash.finalize().iter().map(|b| format!("{b:02x}")).collect()
    }

    /// A tag: names what follows (a kind, a section) so that values of
    /// different kinds never encode alike. Tags are the fingerprint's own
    /// words, never derived from Rust names.
    pub fn tag(&mut self, tag: &str) {
        self.bytes(tag.as_bytes());
    }

    /// Length-prefixed bytes.
    pub fn bytes(&mut self, bytes: &[u8]) {
        self.u64(bytes.len() as u64);
        self.hash.update(bytes);
    }

    /// One byte (an enum's variant number).
    pub fn u8(&mut self, v: u8) {
        self.hash.update([v]);
    }

    /// A boolean as one byte, 0 or 1.
    pub fn bool(&mut self, v: bool) {
        self.u8(v as u8);
    }

    /// Little-endian `u32`.
    pub fn u32(&mut self, v: u32) {
        self.hash.update(v.to_le_bytes());
    }

    /// Little-endian `u64`.
    pub fn u64(&mut self, v: u64) {
        self.hash.update(v.to_le_bytes());
    }

    /// An `f32` by its bits, little-endian.
    pub fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }

    /// Consecutive `f32`s (a vector, a matrix), no length prefix.
    pub fn floats(&mut self, values: &[f32]) {
        for &v in values {
            self.f32(v);
        }
    }

    /// An optional value: 0, or 1 then the value.
    pub fn option<T>(&mut self, value: Option<&T>, encode: impl FnOnce(&mut Self, &T)) {
        match value {
            None => self.u8(0),
            Some(v) => {
                self.u8(1);
                encode(self, v);
            }
        }
    }

    /// A sequence of `N`-float records in bulk (a mesh's positions, normals,
    /// texture coordinates): the count, then every float's little-endian
    /// bits, gathered in a buffer so that the hash sees large writes.
    pub fn float_records<const N: usize>(&mut self, records: impl ExactSizeIterator<Item = [f32; N]>) {
        self.u64(records.len() as u64);
        for r in records {
            for v in r {
                self.buffer.extend_from_slice(&v.to_bits().to_le_bytes());
            }
            if self.buffer.len() >= BULK {
                self.flush();
            }
        }
        self.flush();
    }

    /// A sequence of `N`-integer records in bulk (a mesh's triangles).
    pub fn u32_records<const N: usize>(&mut self, records: impl ExactSizeIterator<Item = [u32; N]>) {
        self.u64(records.len() as u64);
        for r in records {
            for v in r {
                self.buffer.extend_from_slice(&v.to_le_bytes());
            }
            if self.buffer.len() >= BULK {
                self.flush();
            }
        }
        self.flush();
    }

    fn flush(&mut self) {
        self.hash.update(&self.buffer);
        self.buffer.clear();
    }

    /// Something that encodes itself.
    pub fn put<T: Fingerprint + ?Sized>(&mut self, value: &T) {
        value.encode(self);
    }
}

/// A type's own encoding in the fingerprint: everything about it that can
/// change a render's samples, in a fixed order, each kind introduced by a
/// tag of its own. Implementations destructure their type exhaustively, so
/// that a new field does not compile until it is encoded (or said to change
/// no sample).
pub trait Fingerprint {
    /// Writes this value into `e`.
    fn encode(&self, e: &mut Encoder);
}

impl Fingerprint for crate::math::Vec3A {
    fn encode(&self, e: &mut Encoder) {
        e.floats(&self.to_array());
    }
}

impl Fingerprint for crate::math::Vec2 {
    fn encode(&self, e: &mut Encoder) {
        e.floats(&self.to_array());
    }
}
