//! Ctrl-C (SIGINT) and SIGTERM. By default the process exits with status 130 after removing
//! the temporary files being written ([`crate::atomic`]), so an interrupted command leaves no
//! half-written or stray file; the output directory's lock goes with the process.
//!
//! A command that can stop cleanly (`run`) asks for it with [`stop_gracefully`]: the first
//! signal then only raises a flag ([`requested`]) that the command checks between steps, so
//! it can write what it finished; a second signal exits at once as above.

use std::sync::atomic::{AtomicBool, Ordering};

static GRACEFUL: AtomicBool = AtomicBool::new(false);
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Installs the handler; a second installation (tests) is ignored.
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        if GRACEFUL.load(Ordering::SeqCst) && !REQUESTED.swap(true, Ordering::SeqCst) {
            eprintln!(
                "raybench: interrupted: stopping after the current step and writing what is \
                 finished (interrupt again to stop at once)"
            );
            return;
        }
        crate::atomic::remove_temporaries();
        eprintln!("raybench: interrupted; no partial file was left behind");
        std::process::exit(130);
    });
}

/// From now on the first signal only sets [`requested`].
pub fn stop_gracefully() {
    GRACEFUL.store(true, Ordering::SeqCst);
}

/// Whether a graceful stop was asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}
