//! Named metals: complex indices of refraction `eta + i k` per RGB channel,
//! from measured spectral data (Palik, "Handbook of Optical Constants of
//! Solids", 1985) reduced to the sRGB primaries; the values are those of
//! Mitsuba 3's RGB variants, so that both renderers see the same metals.

use crate::math::Vec3A;

/// A named metal's `(eta, k)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metal {
    /// Name in scene files.
    pub name: &'static str,
    /// Real part of the index.
    pub eta: [f32; 3],
    /// Extinction coefficient.
    pub k: [f32; 3],
}

/// The presets, by name.
pub const METALS: [Metal; 4] = [
    Metal {
        name: "gold",
        eta: [0.143036, 0.375307, 1.44205],
        k: [3.983, 2.38556, 1.60336],
    },
    Metal {
        name: "silver",
        eta: [0.155276, 0.116728, 0.138388],
        k: [4.82835, 3.12222, 2.1469],
    },
    Metal {
        name: "copper",
        eta: [0.201005, 0.92375, 1.10222],
        k: [3.91326, 2.45305, 2.14209],
    },
    Metal {
        name: "aluminium",
        eta: [1.6575, 0.880405, 0.521244],
        k: [9.22381, 6.2695, 4.837],
    },
];

/// The metal named `name` (as `(eta, k)`), if it is a preset.
pub fn metal(name: &str) -> Option<(Vec3A, Vec3A)> {
    METALS
        .iter()
        .find(|m| m.name == name)
        .map(|m| (Vec3A::from_array(m.eta), Vec3A::from_array(m.k)))
}
