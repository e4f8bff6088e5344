//! Stamps the binary with the git revision and the compiler version, for report fingerprints.
use std::process::Command;

fn output(cmd: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(cmd).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn main() {
    let rev = output("git", &["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    // `--no-optional-locks`: a plain `git status` rewrites .git/index to refresh its file
    // times, and .git/index is one of the files below that rerun this script, so a build beside
    // another (CI's test and release builds) would make the other's harness stale.
    let dirty = output(
        "git",
        &[
            "--no-optional-locks",
            "status",
            "--porcelain",
            "--untracked-files=no",
        ],
    )
    .map(|s| !s.is_empty())
    .unwrap_or(false);
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let rustc_version = output(&rustc, &["-V"]).unwrap_or_else(|| "unknown".into());
    println!(
        "cargo:rustc-env=RAYBENCH_GIT_REV={rev}{}",
        if dirty { "-dirty" } else { "" }
    );
    println!("cargo:rustc-env=RAYBENCH_RUSTC={rustc_version}");
    println!(
        "cargo:rustc-env=RAYBENCH_PROFILE={}",
        std::env::var("PROFILE").unwrap_or_default()
    );
    for f in [
        "../../.git/HEAD",
        "../../.git/index",
        "../../.git/refs/heads",
    ] {
        println!("cargo:rerun-if-changed={f}");
    }
}
