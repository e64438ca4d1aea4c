//! `[media.NAME]` (homogeneous media bounded by objects), and the water's
//! `[medium]` with the water object it fills.

use super::{degrees_for, int, num, string, unsupported, vec3, WriteError};
use crate::geometry::WaterSurface;
use crate::scene::{Medium, PhaseFunction, Scene};
use toml::{Table, Value};

/// `[media]`: every medium by its name; `sigma_t` is written with its
/// scale applied (`scale` is then 1).
pub(super) fn media(scene: &Scene) -> Result<Table, WriteError> {
    let mut t = Table::new();
    for m in &scene.media.list {
        let mut s = Table::new();
        s.insert("sigma_t".into(), vec3(m.sigma_t));
        s.insert("albedo".into(), vec3(m.albedo));
        let phase = match m.phase {
            PhaseFunction::Isotropic => string("isotropic"),
            PhaseFunction::HenyeyGreenstein { g } => {
                let mut hg = Table::new();
                hg.insert("hg".into(), num(g));
                Value::Table(hg)
            }
        };
        s.insert("phase".into(), phase);
        s.insert("sample_emitters".into(), Value::Boolean(m.sample_emitters));
        if t.insert(m.name.clone(), Value::Table(s)).is_some() {
            return Err(unsupported(format!("medium `{}`", m.name), "two media have this name"));
        }
    }
    Ok(t)
}

/// The water's `[medium]`.
pub(super) fn water_medium(m: &Medium) -> Table {
    let mut t = Table::new();
    t.insert("density".into(), num(m.density));
    t.insert("colour".into(), vec3(m.colour));
    if let Some(v) = &m.volume {
        t.insert("absorption".into(), vec3(v.absorption));
        t.insert("scattering".into(), vec3(v.scattering));
        t.insert("g".into(), num(v.g));
    }
    // The region follows from the water and the scene's bounds; the
    // comparison of the scene read back checks it.
    t
}

/// The keys of the `type = "water"` object the medium fills.
pub(super) fn water_object(w: &WaterSurface, t: &mut Table) {
    t.insert("type".into(), string("water"));
    t.insert("center".into(), vec3(w.center));
    t.insert("size".into(), Value::Array(vec![num(w.size.x), num(w.size.y)]));
    t.insert(
        "resolution".into(),
        Value::Array(vec![int(w.resolution.0), int(w.resolution.1)]),
    );
    let waves = w
        .waves
        .iter()
        .map(|wave| {
            let mut s = Table::new();
            s.insert("amplitude".into(), num(wave.amplitude));
            s.insert("wavelength".into(), num(wave.wavelength));
            // The loader normalises the direction: one it turns into this.
            let d = super::normalizes_to_2d(wave.direction).unwrap_or(wave.direction);
            s.insert("direction".into(), Value::Array(vec![num(d.x), num(d.y)]));
            // The nearest degrees that read back as the same phase; the
            // comparison of the scene read back checks any other rounding.
            s.insert(
                "phase".into(),
                num(degrees_for(wave.phase).unwrap_or(wave.phase.to_degrees())),
            );
            Value::Table(s)
        })
        .collect();
    t.insert("waves".into(), Value::Array(waves));
}
