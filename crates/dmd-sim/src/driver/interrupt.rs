//! Stopping a run on SIGINT, SIGTERM or SIGHUP without losing it.
//!
//! [`install`] (called by the `dmd` command) sets a flag on the first signal; the run stops at
//! its next re-basing of the time origin (the loop pauses at every re-basing while a handler is
//! installed), where a checkpoint is exact, writes `DIR/checkpoint.dmd` and returns
//! `RunError::Interrupted`, so that `dmd resume` continues
//! it bit for bit. If the scheduled re-basing is more than [`GRACE`] away, the loop re-bases
//! early: the resumed run is then exact from its checkpoint, but differs from a run never
//! stopped by the rounding of that extra re-basing. A second signal ends the process at once
//! with [`EXIT_STATUS`].

use std::sync::Arc;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Exit status of a run stopped by a signal (128 + SIGINT, the shell's convention).
pub const EXIT_STATUS: i32 = 130;

/// How long (wall time) a stopped run waits for its scheduled re-basing before it re-bases
/// at once: well inside the half minute batch systems commonly leave between SIGTERM and
/// SIGKILL.
pub const GRACE: Duration = Duration::from_secs(5);

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Installs the handlers of SIGINT, SIGTERM and SIGHUP: the first sets the flag, a second
/// exits at once with [`EXIT_STATUS`].
///
/// # Errors
/// The system's error if a handler cannot be installed.
pub fn install() -> std::io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let flag = FLAG.get_or_init(|| Arc::new(AtomicBool::new(false)));
    for sig in [SIGINT, SIGTERM, SIGHUP] {
        // In this order: the shutdown acts only if the flag was already set by an earlier
        // signal.
        signal_hook::flag::register_conditional_shutdown(sig, EXIT_STATUS, Arc::clone(flag))?;
        signal_hook::flag::register(sig, Arc::clone(flag))?;
    }
    Ok(())
}

/// Whether handlers are installed (runs then pause at every re-basing to look at the flag).
pub fn installed() -> bool {
    FLAG.get().is_some()
}

/// The flag the handlers set, once they are installed.
pub fn flag() -> Option<Arc<AtomicBool>> {
    FLAG.get().cloned()
}

/// Whether a signal asked the run to stop.
pub fn requested() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::Relaxed))
}
