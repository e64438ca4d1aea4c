//! Warnings about parameters the scene's integrator ignores, and about
//! materials that reflect more light than they receive. Shown by `caustic
//! info` and at the start of a render; they never stop a render.

use crate::math::Vec3A;
use crate::scene::{IntegratorKind, Light, Material, RenderSettings, Scene};

/// One warning about one material.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialWarning {
    /// The material's name in the scene file.
    pub material: String,
    /// What is wrong and why.
    pub message: String,
}

impl std::fmt::Display for MaterialWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "material `{}`: {}", self.material, self.message)
    }
}

/// Every warning about `scene` rendered with `settings`, as shown to the user.
pub fn warnings(scene: &Scene, settings: &RenderSettings) -> Vec<String> {
    settings_warnings(scene, settings)
        .into_iter()
        .chain(
            material_warnings(scene, settings.integrator)
                .iter()
                .map(ToString::to_string),
        )
        .collect()
}

/// Warnings about the `[render]` settings (and the scene's terms that
/// `settings`' integrator ignores).
pub fn settings_warnings(scene: &Scene, settings: &RenderSettings) -> Vec<String> {
    let s = settings;
    let mut out = Vec::new();
    if !s.denoise && s.denoise_quality != crate::film::denoise::DenoiseQuality::default() {
        out.push(format!(
            "the denoising quality `{}` is ignored: the image is not denoised (`[render] denoise = true` or --denoise)",
            s.denoise_quality.name()
        ));
    }
    if s.integrator == IntegratorKind::Path {
        if scene.ambient.max_element() > 0.0 {
            out.push("`[render] ambient` is ignored: the path integrator computes indirect light".into());
        }
        if scene.water_medium.as_ref().is_some_and(|m| m.volume.is_none()) {
            out.push(
                "`[medium]` has no `absorption` and `scattering`: the path integrator renders no medium \
                 (the exponential fog is the Whitted integrator's model)"
                    .into(),
            );
        }
    }
    out
}

fn set(c: Vec3A) -> bool {
    c.max_element() > 0.0
}

/// The largest channel of `c` above 1 (as "1.2 in red"), if any.
fn over_one(c: Vec3A) -> Option<String> {
    let names = ["red", "green", "blue"];
    let (i, v) = c
        .to_array()
        .into_iter()
        .enumerate()
        .fold(None, |best: Option<(usize, f32)>, (i, v)| match best {
            Some((_, b)) if b >= v => best,
            _ => Some((i, v)),
        })?;
    (v > 1.0 + 1e-6).then(|| format!("{v:.3} in {}", names[i]))
}

/// Warnings for every material used by an object of `scene`, rendered by
/// `integrator`.
pub fn material_warnings(scene: &Scene, integrator: IntegratorKind) -> Vec<MaterialWarning> {
    let has_delta_light = scene.lights.iter().any(Light::is_delta);
    let mut used = vec![false; scene.materials.len()];
    for o in &scene.objects {
        used[o.material as usize] = true;
    }
    scene
        .materials
        .iter()
        .zip(used)
        .filter(|(_, used)| *used)
        .flat_map(|(m, _)| {
            warnings_of(m, integrator, has_delta_light)
                .into_iter()
                .map(|message| MaterialWarning {
                    material: m.name.clone(),
                    message,
                })
        })
        .collect()
}

fn warnings_of(m: &Material, integrator: IntegratorKind, has_delta_light: bool) -> Vec<String> {
    let mut out = Vec::new();
    let whitted = integrator == IntegratorKind::Whitted;
    if m.conductor.is_some() || m.dielectric.is_some() {
        let what = if m.conductor.is_some() {
            "a conductor"
        } else {
            "a dielectric"
        };
        if set(m.diffuse) {
            out.push(format!("`diffuse` is ignored: {what} has no diffuse term"));
        } else if set(m.ambient) && whitted {
            out.push(format!("`ambient` is ignored: {what} has no ambient term"));
        }
    }
    if let Some(c) = m.conductor {
        if set(m.specular) {
            out.push("`specular` is ignored: a conductor's highlight comes from its index and roughness".into());
        }
        if c.roughness > 0.0 && whitted {
            out.push("the Whitted integrator lights a rough conductor directly but shows no reflection in it".into());
        }
        return out;
    }
    if m.disney.is_some() && whitted {
        out.push(
            "the Whitted integrator lights a Disney material (Mitsuba's `principled` or `principledthin`) directly \
             and shows no reflection or transmission in it"
                .into(),
        );
    }
    if let Some(p) = m.principled {
        if set(m.specular) {
            out.push(
                "`specular` is ignored: a principled material's highlight comes from its roughness and index".into(),
            );
        }
        if whitted && p.transmission > 0.0 {
            out.push(
                "`principled.transmission` is ignored: the Whitted integrator lights a principled material \
                 directly and shows its smooth reflection only"
                    .into(),
            );
        }
        return out;
    }
    if m.coating.is_some() && set(m.specular) {
        out.push("`specular` is ignored: a coating's highlight comes from its index".into());
    }
    if let Some(d) = m.dielectric {
        if set(m.specular) && !whitted {
            out.push("`specular` is ignored: the path integrator's dielectric has no highlight lobe".into());
        } else if set(m.specular) && !has_delta_light {
            out.push(
                "`specular` is ignored: a dielectric keeps the highlight of point lights only (point, spot, \
                 directional) and the scene has none (area lights appear in its reflection)"
                    .into(),
            );
        }
        if d.roughness > 0.0 && whitted {
            out.push("`roughness` is ignored: the Whitted integrator treats every dielectric as smooth".into());
        }
        if let Some(c) = over_one(d.tint) {
            out.push(format!("`dielectric.tint` transmits more light than it receives ({c})"));
        }
        return out;
    }
    let r = m.mirror.map_or(0.0, |mi| mi.reflectivity);
    if let Some(mi) = m.mirror {
        if r <= 0.0 {
            out.push("`mirror` has no effect: its reflectivity is 0".into());
        } else if r >= 1.0 {
            let dead: Vec<&str> = [("diffuse", m.diffuse), ("specular", m.specular), ("ambient", m.ambient)]
                .into_iter()
                .filter(|(_, c)| set(*c))
                .map(|(name, _)| name)
                .collect();
            if !dead.is_empty() {
                out.push(format!(
                    "`{}` {} ignored: a perfect mirror (reflectivity 1) shows only its reflection",
                    dead.join("`, `"),
                    if dead.len() == 1 { "is" } else { "are" }
                ));
            }
        }
        if let Some(c) = over_one(mi.tint) {
            out.push(format!("`mirror.tint` reflects more light than it receives ({c})"));
        }
    }
    // The normalised lobes reflect at most their reflectance each (module
    // docs of `integrator::whitted`), so their sum bounds the albedo.
    if r < 1.0 {
        if let Some(c) = over_one(m.diffuse + m.specular) {
            out.push(format!(
                "reflects more light than it receives: `diffuse` + `specular` = {c} (keep the sum at most 1 per channel)"
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Dielectric, Mirror};

    #[test]
    fn dead_and_energy_gaining_parameters_are_named() {
        let mut glass = Material::diffuse("glass", Vec3A::ZERO);
        glass.specular = Vec3A::splat(0.8);
        glass.dielectric = Some(Dielectric::smooth(1.5, Vec3A::ONE));
        let w = warnings_of(&glass, IntegratorKind::Whitted, false);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(w[0].contains("point lights only"));
        assert!(warnings_of(&glass, IntegratorKind::Whitted, true).is_empty());

        let mut mirror = Material::diffuse("mirror", Vec3A::ZERO);
        mirror.specular = Vec3A::splat(0.6);
        mirror.mirror = Some(Mirror {
            reflectivity: 1.0,
            tint: Vec3A::ONE,
        });
        let w = warnings_of(&mirror, IntegratorKind::Whitted, true);
        assert_eq!(
            w,
            vec!["`specular` is ignored: a perfect mirror (reflectivity 1) shows only its reflection"]
        );

        let mut bright = Material::diffuse("bright", Vec3A::new(0.8, 0.5, 0.5));
        bright.specular = Vec3A::new(0.4, 0.4, 0.4);
        let w = warnings_of(&bright, IntegratorKind::Whitted, true);
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("1.200 in red"), "{w:?}");

        assert!(warnings_of(&Material::diffuse("ok", Vec3A::splat(0.9)), IntegratorKind::Path, true).is_empty());
    }

    #[test]
    fn a_denoising_quality_without_denoising_is_named() {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell.toml"));
        let crate::scene::LoadedScene { scene, mut settings } = crate::scene::load_scene(path).unwrap();
        assert!(settings_warnings(&scene, &settings).is_empty());
        settings.denoise_quality = crate::film::denoise::DenoiseQuality::Fast;
        let w = settings_warnings(&scene, &settings);
        assert!(w.len() == 1 && w[0].contains("`fast` is ignored"), "{w:?}");
        settings.denoise = true;
        assert!(settings_warnings(&scene, &settings).is_empty());
    }

    #[test]
    fn a_medium_without_coefficients_is_named_in_path_mode() {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/underwater.toml"));
        let text = std::fs::read_to_string(path).unwrap();
        let crate::scene::LoadedScene { scene, settings } = crate::scene::load::parse_scene(&text, path).unwrap();
        assert!(scene.water_medium.as_ref().unwrap().volume.is_some());
        let mut traced = settings.clone();
        traced.integrator = IntegratorKind::Path;
        assert!(settings_warnings(&scene, &traced)
            .iter()
            .all(|w| !w.contains("[medium]")));
        let mut fog_only = scene.clone();
        fog_only.water_medium.as_mut().unwrap().volume = None;
        let w = settings_warnings(&fog_only, &traced);
        assert!(w.iter().any(|w| w.contains("renders no medium")), "{w:?}");
        // The Whitted integrator renders the fog of the same table.
        assert!(settings_warnings(&scene, &settings)
            .iter()
            .all(|w| !w.contains("[medium]")));
    }
}
