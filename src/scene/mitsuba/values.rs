//! The text of Mitsuba property values: numbers separated by commas or
//! spaces, vectors, colours and spectra.

use super::spectrum::{spectrum_to_srgb, uniform_to_srgb, SpectrumUse};
use crate::math::{Vec3, Vec3A};

/// Most wavelength:value pairs a spectrum may list.
pub const MAX_SPECTRUM_SAMPLES: usize = 10_000;

/// Finite numbers separated by commas and/or whitespace.
pub fn numbers(text: &str) -> Result<Vec<f32>, String> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| match t.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(format!("`{t}` is not finite")),
            Err(_) => Err(format!("`{t}` is not a number")),
        })
        .collect()
}

/// Exactly three numbers.
pub fn vector3(text: &str) -> Result<Vec3, String> {
    match numbers(text)?.as_slice() {
        [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
        n => Err(format!("`{text}` has {} numbers; expected three", n.len())),
    }
}

/// An `<rgb value>`: three numbers, or one for a grey.
pub fn rgb(text: &str) -> Result<Vec3A, String> {
    match numbers(text)?.as_slice() {
        [v] => Ok(Vec3A::splat(*v)),
        [r, g, b] => Ok(Vec3A::new(*r, *g, *b)),
        n => Err(format!(
            "`{text}` has {} numbers; an rgb value takes three (or one)",
            n.len()
        )),
    }
}

/// A `<spectrum value>`: one number (uniform) or `λ:value` pairs in nm, in
/// increasing wavelength.
pub fn spectrum(text: &str, usage: SpectrumUse) -> Result<Vec3A, String> {
    if !text.contains(':') {
        return match numbers(text)?.as_slice() {
            [v] => Ok(uniform_to_srgb(*v, usage)),
            _ => Err(format!("`{text}`: a spectrum is one value or `wavelength:value` pairs")),
        };
    }
    let mut wavelengths = Vec::new();
    let mut values = Vec::new();
    for pair in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (w, v) = pair
            .split_once(':')
            .ok_or_else(|| format!("`{pair}` is not a `wavelength:value` pair"))?;
        let parse = |t: &str| match t.trim().parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(format!("`{pair}`: `{}` is not a finite number", t.trim())),
        };
        wavelengths.push(parse(w)?);
        values.push(parse(v)?);
        if wavelengths.len() > MAX_SPECTRUM_SAMPLES {
            return Err(format!("more than {MAX_SPECTRUM_SAMPLES} wavelengths"));
        }
    }
    pairs_to_srgb(&wavelengths, &values, usage)
}

/// Separate `wavelengths` and `values` lists.
pub fn pairs_to_srgb(wavelengths: &[f32], values: &[f32], usage: SpectrumUse) -> Result<Vec3A, String> {
    if wavelengths.len() != values.len() {
        return Err(format!("{} wavelengths for {} values", wavelengths.len(), values.len()));
    }
    if wavelengths.len() < 2 {
        return Err("a sampled spectrum needs at least two wavelengths".into());
    }
    if let Some(w) = wavelengths.windows(2).find(|w| w[1] <= w[0]) {
        return Err(format!("wavelengths must increase, but {} follows {}", w[1], w[0]));
    }
    Ok(spectrum_to_srgb(wavelengths, values, usage))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_take_commas_and_spaces() {
        assert_eq!(numbers("1, 2 3,4").unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
        assert!(numbers("1, x").unwrap_err().contains("`x`"));
        assert!(numbers("inf").is_err());
        assert_eq!(rgb("0.5").unwrap(), Vec3A::splat(0.5));
        assert!(rgb("1 2").is_err());
    }

    #[test]
    fn spectra_are_checked() {
        assert!(spectrum("500:1, 400:1", SpectrumUse::Emission)
            .unwrap_err()
            .contains("increase"));
        assert!(spectrum("500:1", SpectrumUse::Emission).unwrap_err().contains("two"));
        assert!(spectrum("400:a, 500:1", SpectrumUse::Emission).is_err());
        assert!(spectrum("1 2", SpectrumUse::Emission).is_err());
        assert_eq!(spectrum("0.25", SpectrumUse::Reflectance).unwrap(), Vec3A::splat(0.25));
    }
}
