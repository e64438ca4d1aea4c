//! Process memory figures for reports (Linux `/proc`; `None` elsewhere).

/// Peak resident set size of this process in bytes (`VmHWM`).
pub fn peak_rss_bytes() -> Option<u64> {
    status_kib("VmHWM:").map(|k| k * 1024)
}

/// Current resident set size of this process in bytes (`VmRSS`).
pub fn current_rss_bytes() -> Option<u64> {
    status_kib("VmRSS:").map(|k| k * 1024)
}

/// Resets the kernel's peak-RSS counter of this process to the current
/// resident set (writes `5` to `/proc/self/clear_refs`, Linux ≥ 4.0), so that
/// [`peak_rss_bytes`] measures one phase of a run (the benchmarks measure
/// each accelerator apart). False when the reset is not possible.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Memory the kernel reports as available to new allocations (`MemAvailable`).
pub fn available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_kib(&text, "MemAvailable:").map(|k| k * 1024)
}

/// Environment variable that overrides [`available_bytes`] for the checks made
/// before large allocations (mesh loading, film, photon map): a byte count with
/// an optional `K`, `M`, `G` or `T` suffix (powers of 1024), e.g. `512M`.
pub const MEMORY_LIMIT_ENV: &str = "CAUSTIC_MEMORY_LIMIT";

/// The memory that large allocations are checked against, and where the figure comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    /// Bytes that may be allocated.
    pub bytes: u64,
    /// `"available"` (the kernel's `MemAvailable`) or the environment variable's name.
    pub source: &'static str,
}

impl std::fmt::Display for MemoryBudget {
    /// `"1.5 GiB available"` or `"0.1 GiB allowed by CAUSTIC_MEMORY_LIMIT"`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.source == MEMORY_LIMIT_ENV {
            write!(f, "{} allowed by {MEMORY_LIMIT_ENV}", format_bytes(self.bytes))
        } else {
            write!(f, "{} available", format_bytes(self.bytes))
        }
    }
}

/// Formats a byte count for messages: GiB from 1 GiB up, MiB from 1 MiB up,
/// bytes below (so that small test limits still read sensibly).
pub fn format_bytes(bytes: u64) -> String {
    const MIB: u64 = 1 << 20;
    const GIB: u64 = 1 << 30;
    if bytes >= GIB {
        format!("{:.3} GiB", bytes as f64 / GIB as f64)
    } else if bytes >= MIB {
        format!("{:.1} MiB", bytes as f64 / MIB as f64)
    } else {
        format!("{bytes} bytes")
    }
}

/// The memory budget: [`MEMORY_LIMIT_ENV`] when set, else [`available_bytes`];
/// `Ok(None)` when neither is known (no check is then possible). An
/// unparsable [`MEMORY_LIMIT_ENV`] is an error, not silently ignored.
pub fn budget() -> Result<Option<MemoryBudget>, String> {
    match std::env::var(MEMORY_LIMIT_ENV) {
        Ok(text) => parse_size(&text)
            .map(|bytes| {
                Some(MemoryBudget {
                    bytes,
                    source: MEMORY_LIMIT_ENV,
                })
            })
            .ok_or_else(|| format!("{MEMORY_LIMIT_ENV}={text:?} is not a byte count (examples: 1000000, 512M, 4G)")),
        Err(_) => Ok(available_bytes().map(|bytes| MemoryBudget {
            bytes,
            source: "available",
        })),
    }
}

/// Parses `123`, `64K`, `512M`, `4G`, `1T` (suffixes are powers of 1024, an
/// optional trailing `B` or `iB` is accepted).
pub fn parse_size(text: &str) -> Option<u64> {
    let t = text.trim();
    let t = t.strip_suffix("iB").or_else(|| t.strip_suffix('B')).unwrap_or(t);
    let (digits, shift) = match t.chars().last()? {
        'K' | 'k' => (&t[..t.len() - 1], 10),
        'M' | 'm' => (&t[..t.len() - 1], 20),
        'G' | 'g' => (&t[..t.len() - 1], 30),
        'T' | 't' => (&t[..t.len() - 1], 40),
        _ => (t, 0),
    };
    let n: u64 = digits.trim().parse().ok()?;
    n.checked_mul(1u64 << shift)
}

fn status_kib(key: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_kib(&text, key)
}

fn parse_kib(text: &str, key: &str) -> Option<u64> {
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|rest| rest.split_whitespace().next()?.parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_kib_lines() {
        let text = "Name:\tx\nVmHWM:\t  123456 kB\nVmRSS:\t 1 kB\n";
        assert_eq!(parse_kib(text, "VmHWM:"), Some(123456));
        assert_eq!(parse_kib(text, "Missing:"), None);
    }

    #[test]
    fn sizes() {
        assert_eq!(parse_size("1000"), Some(1000));
        assert_eq!(parse_size("64K"), Some(64 << 10));
        assert_eq!(parse_size("512M"), Some(512 << 20));
        assert_eq!(parse_size("4GiB"), Some(4 << 30));
        assert_eq!(parse_size(" 2g "), Some(2 << 30));
        assert_eq!(parse_size("1T"), Some(1 << 40));
        for bad in ["", "G", "1.5G", "-1", "lots", "99999999999999999999T"] {
            assert_eq!(parse_size(bad), None, "{bad}");
        }
        assert_eq!(format_bytes(3 << 29), "1.500 GiB");
        assert_eq!(format_bytes(64 << 20), "64.0 MiB");
        assert_eq!(format_bytes(184), "184 bytes");
    }

    #[test]
    fn reads_this_process() {
        if cfg!(target_os = "linux") {
            assert!(peak_rss_bytes().unwrap() > 1 << 20);
            assert!(available_bytes().unwrap() > 0);
            let rss = current_rss_bytes().unwrap();
            assert!(rss > 1 << 20);
        }
    }
}
