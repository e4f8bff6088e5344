//! Ctrl-C (SIGINT) and SIGTERM: the process exits with status 130 after removing the temporary
//! files being written ([`crate::atomic`]), so an interrupted command leaves no half-written
//! or stray file; the output directory's lock goes with the process.

/// Installs the handler; a second installation (tests) is ignored.
pub fn install() {
    let _ = ctrlc::set_handler(|| {
        crate::atomic::remove_temporaries();
        eprintln!("raybench: interrupted; no partial file was left behind");
        std::process::exit(130);
    });
}
