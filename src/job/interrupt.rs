//! Stopping a render on Ctrl-C: [`Interrupt`] turns SIGINT / SIGTERM into a
//! cancel flag the render loop polls before each pixel
//! (`RenderControl::cancel`); a second signal ends the process at once
//! (exit 128 + signal number), for when the clean stop itself hangs (a full
//! disk, a photon pass that is not interruptible).

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// The signals that stop a render cleanly.
#[cfg(unix)]
const STOP_SIGNALS: [i32; 2] = [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM];
#[cfg(not(unix))]
const STOP_SIGNALS: [i32; 1] = [signal_hook::consts::SIGINT];

/// A process-wide stop request from SIGINT (Ctrl-C) or SIGTERM.
#[derive(Clone, Debug)]
pub struct Interrupt {
    stop: Arc<AtomicBool>,
    signal: Arc<AtomicUsize>,
}

impl Interrupt {
    /// Installs the handlers. The first signal sets the flag (and records
    /// which signal it was); a second one, with the flag already set, exits
    /// the process immediately with status 128 + signal number.
    pub fn install() -> std::io::Result<Self> {
        let stop = Arc::new(AtomicBool::new(false));
        let signal = Arc::new(AtomicUsize::new(0));
        for sig in STOP_SIGNALS {
            // Order matters (signal-hook's documented double Ctrl-C pattern):
            // the conditional exit must run before the flag is set, so the
            // first signal only arms it.
            signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&stop))?;
            signal_hook::flag::register_usize(sig, Arc::clone(&signal), sig as usize)?;
            signal_hook::flag::register(sig, Arc::clone(&stop))?;
        }
        Ok(Self { stop, signal })
    }

    /// The cancel flag to hand to `RenderControl::cancel`.
    pub fn flag(&self) -> &AtomicBool {
        &self.stop
    }

    /// Whether a stop was requested.
    pub fn requested(&self) -> bool {
        self.stop.load(Ordering::SeqCst)
    }

    /// Name of the signal received, if any.
    pub fn signal_name(&self) -> Option<&'static str> {
        match self.signal.load(Ordering::SeqCst) {
            0 => None,
            s => Some(signal_hook::low_level::signal_name(s as i32).unwrap_or("a signal")),
        }
    }

    /// Conventional exit status after a stop: 128 + signal number (130 for
    /// SIGINT).
    pub fn exit_code(&self) -> u8 {
        match self.signal.load(Ordering::SeqCst) {
            0 => 130,
            s => (128 + s).min(255) as u8,
        }
    }
}
