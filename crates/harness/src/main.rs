//! `raybench`: list what can be measured, run measurements into a checked JSON report, and
//! look at scenes (`raybench scene list|export|preview`). The command line lives in
//! [`raybench_harness::cli::main_with`]; this binary runs it with the built-in structures.

use raybench_harness::Registry;
use std::process::ExitCode;

fn main() -> ExitCode {
    raybench_harness::cli::main_with(Registry::builtin())
}
