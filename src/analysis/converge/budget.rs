//! The budgets of a convergence run (`--budgets`): samples per pixel, with
//! or without a photon count, or seconds of wall time.

use super::ConvergeError;
use crate::limits::{check_photon_count, MAX_SPP};
use std::fmt;

/// Most budgets one run accepts.
pub const MAX_BUDGETS: usize = 64;

/// Longest accepted time budget, in seconds (a day).
pub const MAX_SECONDS_BUDGET: f64 = 86_400.0;

/// One budget of a convergence run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// A fixed number of samples per pixel, with a photon count (`None`: the
    /// default rule, see the `converge` module documentation).
    Samples {
        /// Samples per pixel.
        spp: u32,
        /// Photons emitted.
        photons: Option<u64>,
    },
    /// A wall-time budget in seconds, resolved by the doubling search.
    Seconds(f64),
    /// An adaptive render stopped at this noise threshold (`--adaptive`).
    Threshold(f32),
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Budget::Samples { spp, photons: None } => write!(f, "{spp}"),
            Budget::Samples { spp, photons: Some(p) } => write!(f, "{spp}:{p}"),
            Budget::Seconds(s) => write!(f, "{s}s"),
            Budget::Threshold(e) => write!(f, "noise<{e}"),
        }
    }
}

/// Parses a comma-separated budget list: `1:10000,2:30000`, `1,2,4`,
/// `0.5s,1s,2s` (kinds may be mixed). Every spp must be in `1..=MAX_SPP`, every
/// photon count pass [`check_photon_count`], every time be in
/// `(0, MAX_SECONDS_BUDGET]`.
pub fn parse_budgets(text: &str) -> Result<Vec<Budget>, ConvergeError> {
    let fail = |reason: String| ConvergeError::Budget {
        text: text.to_string(),
        reason,
    };
    let items: Vec<&str> = text.split(',').map(str::trim).collect();
    if items.len() > MAX_BUDGETS {
        return Err(fail(format!("{} budgets: at most {MAX_BUDGETS}", items.len())));
    }
    let mut budgets = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let place = |what: String| fail(format!("budget {} ({item:?}): {what}", i + 1));
        if item.is_empty() {
            return Err(place("empty".into()));
        }
        if let Some(secs) = item.strip_suffix('s') {
            let s: f64 = secs
                .trim()
                .parse()
                .map_err(|_| place("expected seconds such as 2s or 0.5s".into()))?;
            if !(s.is_finite() && s > 0.0 && s <= MAX_SECONDS_BUDGET) {
                return Err(place(format!("seconds must be in (0, {MAX_SECONDS_BUDGET}]")));
            }
            budgets.push(Budget::Seconds(s));
            continue;
        }
        let (spp_text, photons_text) = match item.split_once(':') {
            Some((a, b)) => (a.trim(), Some(b.trim())),
            None => (*item, None),
        };
        let spp: u32 = spp_text
            .parse()
            .map_err(|_| place("expected SPP, SPP:PHOTONS or SECONDSs".into()))?;
        if spp == 0 || spp > MAX_SPP {
            return Err(place(format!("spp must be in 1..={MAX_SPP}")));
        }
        let photons = match photons_text {
            None => None,
            Some(t) => {
                let n: u64 = t.parse().map_err(|_| place(format!("{t:?} is not a photon count")))?;
                check_photon_count(n).map_err(place)?;
                Some(n)
            }
        };
        budgets.push(Budget::Samples { spp, photons });
    }
    Ok(budgets)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_parse_and_reject() {
        assert_eq!(
            parse_budgets("1:10000, 2:30000,4").unwrap(),
            vec![
                Budget::Samples {
                    spp: 1,
                    photons: Some(10000)
                },
                Budget::Samples {
                    spp: 2,
                    photons: Some(30000)
                },
                Budget::Samples { spp: 4, photons: None },
            ]
        );
        assert_eq!(
            parse_budgets("0.5s,2s").unwrap(),
            vec![Budget::Seconds(0.5), Budget::Seconds(2.0)]
        );
        for bad in [
            "",
            "0",
            "1,,2",
            "x",
            "1:y",
            "-1s",
            "0s",
            "nans",
            "infs",
            "1:99999999999",
            "2000000",
            "1e9s",
        ] {
            let e = parse_budgets(bad).unwrap_err().to_string();
            assert!(e.starts_with("--budgets"), "{bad}: {e}");
        }
        let many = vec!["1"; MAX_BUDGETS + 1].join(",");
        assert!(parse_budgets(&many).is_err());
        for b in parse_budgets("1:5,3,0.25s").unwrap() {
            assert_eq!(parse_budgets(&b.to_string()).unwrap(), vec![b]);
        }
    }
}
