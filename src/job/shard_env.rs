//! `--shard auto`: the shard index and count from a scheduler's
//! environment, so that one job script serves every task of an array.
//!
//! * Slurm job arrays: `SLURM_ARRAY_TASK_ID`, with `SLURM_ARRAY_TASK_COUNT`
//!   or `SLURM_ARRAY_TASK_MIN` / `SLURM_ARRAY_TASK_MAX` (and
//!   `SLURM_ARRAY_TASK_STEP`): the index is `(ID − MIN) / STEP`, so
//!   `--array=0-3`, `--array=1-4` and `--array=0-30:10` all give shards 0..3
//!   of 4.
//! * Kubernetes Indexed Jobs: `JOB_COMPLETION_INDEX` (0-based), with the
//!   count given on the command line (`--shard-count N`, the Job's
//!   `completions`), which Kubernetes does not put in the environment.

use crate::film::ShardId;

/// The shard of this process from the environment `var` reads (`std::env::var`
/// in the command line, a map in tests). `count` is `--shard-count`: required
/// for Kubernetes, and checked against Slurm's count when given.
pub fn shard_from_env(var: &dyn Fn(&str) -> Option<String>, count: Option<u32>) -> Result<ShardId, String> {
    let number = |name: &str| -> Result<Option<u64>, String> {
        match var(name) {
            None => Ok(None),
            Some(v) => v
                .trim()
                .parse::<u64>()
                .map(Some)
                .map_err(|_| format!("--shard auto: {name}={v:?} is not a non-negative integer")),
        }
    };
    let narrow = |what: &str, v: u64| -> Result<u32, String> {
        u32::try_from(v).map_err(|_| format!("--shard auto: {what} {v} is too large"))
    };
    if let Some(id) = number("SLURM_ARRAY_TASK_ID")? {
        let min = number("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
        let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        let slurm_count = match (number("SLURM_ARRAY_TASK_COUNT")?, number("SLURM_ARRAY_TASK_MAX")?) {
            (Some(c), _) => Some(c),
            (None, Some(max)) if max >= min => Some((max - min) / step + 1),
            (None, Some(max)) => {
                return Err(format!(
                    "--shard auto: SLURM_ARRAY_TASK_MAX={max} is below SLURM_ARRAY_TASK_MIN={min}"
                ))
            }
            (None, None) => None,
        };
        if id < min || (id - min) % step != 0 {
            return Err(format!(
                "--shard auto: SLURM_ARRAY_TASK_ID={id} is not MIN + k·STEP (MIN {min}, STEP {step}); \
                 use a contiguous array such as --array=0-3"
            ));
        }
        let index = (id - min) / step;
        let total = match (slurm_count, count) {
            (Some(s), Some(c)) if s != c as u64 => {
                return Err(format!(
                    "--shard auto: --shard-count {c}, but the Slurm array has {s} tasks"
                ))
            }
            (Some(s), _) => s,
            (None, Some(c)) => c as u64,
            (None, None) => {
                return Err(
                    "--shard auto: SLURM_ARRAY_TASK_ID is set but neither SLURM_ARRAY_TASK_COUNT \
                            nor SLURM_ARRAY_TASK_MAX is; give --shard-count N"
                        .to_string(),
                )
            }
        };
        return ShardId::new(narrow("index", index)?, narrow("count", total)?)
            .map_err(|e| format!("--shard auto (Slurm array task {id}): {e}"));
    }
    if let Some(index) = number("JOB_COMPLETION_INDEX")? {
        let Some(total) = count else {
            return Err(
                "--shard auto: JOB_COMPLETION_INDEX is set (a Kubernetes Indexed Job) but the number \
                        of shards is not in the environment; give --shard-count N (the Job's completions)"
                    .to_string(),
            );
        };
        return ShardId::new(narrow("index", index)?, total).map_err(|e| format!("--shard auto (Kubernetes): {e}"));
    }
    Err(
        "--shard auto: neither SLURM_ARRAY_TASK_ID (a Slurm job array) nor JOB_COMPLETION_INDEX \
         (a Kubernetes Indexed Job) is set; give --shard I/N"
            .to_string(),
    )
}

/// The shard of `--shard TEXT` (`I/N` or `auto`, with `--shard-count`
/// `count`), `var` reading the environment for `auto`.
pub fn parse_shard_arg(
    text: &str,
    count: Option<u32>,
    var: &dyn Fn(&str) -> Option<String>,
) -> Result<ShardId, String> {
    if text.trim() == "auto" {
        return shard_from_env(var, count);
    }
    let id = ShardId::parse(text).map_err(|e| format!("--shard: {e}"))?;
    match count {
        Some(c) if c != id.count => Err(format!("--shard {id} but --shard-count {c}")),
        _ => Ok(id),
    }
}
