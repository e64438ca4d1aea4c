//! Where a render's caustics come from: no map, one map for every sample,
//! or progressive photon mapping's map per sample index. The render loop
//! asks the source, so it has one pass loop for all three.

use super::progressive::ProgressiveSchedule;
use super::PhotonMap;

/// The caustic maps a render gathers from.
pub enum CausticsSource<'a> {
    /// No photon map: caustics are traced as paths, or not at all.
    None,
    /// One map, gathered with the plan's settings by every sample (traced
    /// before the image, built from a photon file, or given by the caller).
    Map(&'a PhotonMap),
    /// Progressive photon mapping: every pixel's sample `s` gathers from
    /// map `s` within radius `r_{s+1}`, each map traced when its sample
    /// index is rendered ([`ProgressiveSchedule::trace`]).
    PerSample(ProgressiveSchedule),
}

impl<'a> CausticsSource<'a> {
    /// The source of a render whose plan runs progressive photon mapping
    /// with `schedule`, or else gathers from `map` (if any).
    pub fn new(schedule: Option<ProgressiveSchedule>, map: Option<&'a PhotonMap>) -> Self {
        match (schedule, map) {
            (Some(schedule), _) => CausticsSource::PerSample(schedule),
            (None, Some(map)) => CausticsSource::Map(map),
            (None, None) => CausticsSource::None,
        }
    }

    /// The one map every sample gathers from, when there is one.
    pub fn fixed_map(&self) -> Option<&'a PhotonMap> {
        match self {
            CausticsSource::Map(map) => Some(map),
            CausticsSource::None | CausticsSource::PerSample(_) => None,
        }
    }
}
