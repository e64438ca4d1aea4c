//! Runs the `caustic` binary the way a user does, from the crate root (so
//! that `scenes/…` paths resolve), without the shard variables of a
//! scheduler the test itself may run under.

use std::process::{Command, Output};

/// The variables `--shard auto` reads (Slurm arrays, Kubernetes Indexed
/// Jobs): never inherited, so a test run inside a Slurm job stays a
/// single render unless a test sets them.
pub const SCHEDULER_VARS: [&str; 6] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_COUNT",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_MAX",
    "SLURM_ARRAY_TASK_STEP",
    "JOB_COMPLETION_INDEX",
];

/// `caustic ARGS`, ready to spawn or to be given more arguments.
pub fn command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_caustic"));
    c.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for var in SCHEDULER_VARS {
        c.env_remove(var);
    }
    c
}

/// Runs `caustic ARGS` to the end.
pub fn caustic(args: &[&str]) -> Output {
    command(args).output().expect("the caustic binary runs")
}

/// Runs `caustic ARGS` with the variables `envs` set.
pub fn caustic_with_env(args: &[&str], envs: &[(&str, &str)]) -> Output {
    command(args)
        .envs(envs.iter().copied())
        .output()
        .expect("the caustic binary runs")
}

/// The run's standard output, as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The run's standard error, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Exit status, standard output and standard error, for a failure message.
pub fn describe(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        stdout(o),
        stderr(o)
    )
}
