//! Stopping `track run` and `track eval otb` cleanly on Ctrl-C (SIGINT), SIGTERM and SIGHUP.
//!
//! The handlers only record the signal; `run` checks [`StopSignals::received`] between frames,
//! stops reading, and writes the outputs of the frames tracked so far (`eval otb` checks it
//! before each run, finishes the runs in progress and writes the tables of those finished), so no temporary file is
//! left and nothing computed is lost. A second signal ends the process at once (exit 128 + the
//! signal number), for a user who will not wait for the outputs.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::{AppError, Result};

/// The stop signals of one run; unregistered when dropped.
pub struct StopSignals {
    received: Arc<AtomicUsize>,
    #[cfg(unix)]
    ids: Vec<signal_hook::SigId>,
}

impl std::fmt::Debug for StopSignals {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StopSignals")
            .field("received", &self.received)
            .finish_non_exhaustive()
    }
}

/// The signals that stop a run, with their names.
#[cfg(unix)]
const SIGNALS: [(i32, &str); 3] = [
    (signal_hook::consts::SIGINT, "SIGINT"),
    (signal_hook::consts::SIGTERM, "SIGTERM"),
    (signal_hook::consts::SIGHUP, "SIGHUP"),
];

impl StopSignals {
    /// Installs the handlers.
    ///
    /// # Errors
    /// [`AppError::Computation`] when a handler cannot be installed.
    #[cfg(unix)]
    pub fn install() -> Result<Self> {
        use signal_hook::flag;
        let received = Arc::new(AtomicUsize::new(0));
        let armed = Arc::new(std::sync::atomic::AtomicBool::new(false));
        let mut ids = Vec::new();
        let wrap = |e| AppError::computation("installing the signal handlers", e);
        for (sig, _) in SIGNALS {
            // Registered first, so the first signal finds `armed` false and only arms it.
            ids.push(
                flag::register_conditional_shutdown(sig, 128 + sig, Arc::clone(&armed))
                    .map_err(wrap)?,
            );
            ids.push(flag::register(sig, Arc::clone(&armed)).map_err(wrap)?);
            ids.push(flag::register_usize(sig, Arc::clone(&received), sig as usize).map_err(wrap)?);
        }
        Ok(Self { received, ids })
    }

    /// Installs nothing: on this platform a signal ends the process as before.
    ///
    /// # Errors
    /// None.
    #[cfg(not(unix))]
    pub fn install() -> Result<Self> {
        Ok(Self {
            received: Arc::new(AtomicUsize::new(0)),
        })
    }

    /// The signal received (its name and number), if any.
    pub fn received(&self) -> Option<(&'static str, u8)> {
        let sig = self.received.load(Ordering::SeqCst);
        if sig == 0 {
            return None;
        }
        #[cfg(unix)]
        let name = SIGNALS
            .iter()
            .find(|(s, _)| *s as usize == sig)
            .map_or("a signal", |(_, n)| n);
        #[cfg(not(unix))]
        let name = "a signal";
        Some((name, u8::try_from(sig).unwrap_or(0)))
    }
}

impl StopSignals {
    /// Before tracking begins: the error that ends the command when a signal was received.
    ///
    /// # Errors
    /// [`AppError::InterruptedBeforeStart`].
    pub fn stop_if_received(&self) -> Result<()> {
        match self.received() {
            Some((signal, number)) => Err(AppError::InterruptedBeforeStart { signal, number }),
            None => Ok(()),
        }
    }
}

impl Drop for StopSignals {
    fn drop(&mut self) {
        #[cfg(unix)]
        for id in self.ids.drain(..) {
            signal_hook::low_level::unregister(id);
        }
    }
}
