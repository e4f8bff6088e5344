//! Records which ISA `-march=native` means for the C++ compiler on this build machine
//! (tinybvh-rs compiles tinybvh with it), so reports can say what the C++ side was compiled for.

use std::process::Command;

fn main() {
    let cxx = std::env::var("CXX").unwrap_or_else(|_| "c++".to_string());
    let march = Command::new(&cxx)
        .args(["-march=native", "-Q", "--help=target"])
        .output()
        .ok()
        .and_then(|o| {
            String::from_utf8_lossy(&o.stdout)
                .lines()
                .find(|l| l.trim_start().starts_with("-march="))
                .and_then(|l| l.split_whitespace().nth(1).map(str::to_string))
        })
        .unwrap_or_else(|| "unknown (the compiler did not report it)".to_string());
    println!("cargo:rustc-env=TINYBVH_CXX_MARCH={march}");
    println!("cargo:rerun-if-env-changed=CXX");
    println!("cargo:rerun-if-changed=build.rs");
}
