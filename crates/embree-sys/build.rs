//! Generates bindings to `<embree3/rtcore.h>` with bindgen and tells Cargo how to link
//! `libembree3`.
//!
//! Where Embree is looked for, first match wins:
//! 1. `EMBREE_DIR`: headers in `$EMBREE_DIR/include`, library in `$EMBREE_DIR/lib`.
//! 2. `pkg-config embree3`, if the command exists and knows the package. Debian's
//!    `libembree-dev` ships no `.pc` file, so on Debian this step finds nothing.
//! 3. The system's default search paths (Debian: `/usr/include`, `/usr/lib/x86_64-linux-gnu`).
//!
//! A missing header or an unloadable libclang stops the build with a message naming the Debian
//! packages, instead of bindgen's bare panic.

use std::env;
use std::path::{Path, PathBuf};
use std::process::Command;

const INSTALL_HINT: &str = "Embree 3 headers and libclang are needed to build raybench-embree-sys; \
     install them with: apt-get install -y libembree-dev libclang-dev (or set EMBREE_DIR)";

/// Where the headers and the library were found, and by which rule.
struct Location {
    rule: &'static str,
    include_dirs: Vec<PathBuf>,
    lib_dirs: Vec<PathBuf>,
}

fn main() {
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-changed=wrapper.h");
    println!("cargo::rerun-if-env-changed=EMBREE_DIR");
    println!("cargo::rerun-if-env-changed=PKG_CONFIG_PATH");

    let location = locate_embree();
    let header = find_header(&location);
    for dir in &location.lib_dirs {
        println!("cargo::rustc-link-search=native={}", dir.display());
    }
    println!("cargo::rustc-link-lib=dylib=embree3");
    // Dependents with `links` metadata can read this as DEP_EMBREE3_INCLUDE.
    if let Some(root) = header.parent().and_then(Path::parent) {
        println!("cargo::metadata=include={}", root.display());
    }

    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let bindings = generate_bindings(&location, &out_dir).unwrap_or_else(|why| fail(&why));
    announce_optional_context_fields(&bindings.to_string());
    bindings
        .write_to_file(out_dir.join("bindings.rs"))
        .unwrap_or_else(|e| fail(&format!("could not write the generated bindings: {e}")));
}

/// `RTCIntersectContext` has `instStackSize` only when `RTC_MAX_INSTANCE_LEVEL_COUNT > 1` and
/// `minWidthDistanceFactor` only when `RTC_MIN_WIDTH` is on (both off on Debian). The port of
/// `rtcInitIntersectContext` in lib.rs sets them under these cfgs, read from what bindgen
/// actually generated.
fn announce_optional_context_fields(generated: &str) {
    let start = generated
        .find("pub struct RTCIntersectContext {")
        .unwrap_or_else(|| fail("bindgen generated no RTCIntersectContext"));
    let body = &generated[start..];
    let body = &body[..body.find('}').unwrap_or(body.len())];
    for (field, cfg) in [
        ("instStackSize", "embree_inst_stack_size"),
        ("minWidthDistanceFactor", "embree_min_width"),
    ] {
        println!("cargo::rustc-check-cfg=cfg({cfg})");
        if body.contains(&format!("pub {field}:")) {
            println!("cargo::rustc-cfg={cfg}");
        }
    }
}

/// Stops the build script with `message` and the install hint; Cargo shows stderr on failure.
fn fail(message: &str) -> ! {
    eprintln!("\nerror: {message}\n{INSTALL_HINT}\n");
    std::process::exit(1);
}

fn locate_embree() -> Location {
    if let Some(dir) = env::var_os("EMBREE_DIR") {
        let dir = PathBuf::from(dir);
        return Location {
            rule: "EMBREE_DIR",
            include_dirs: vec![dir.join("include")],
            lib_dirs: vec![dir.join("lib")],
        };
    }
    pkg_config_location().unwrap_or(Location {
        rule: "the system default paths",
        include_dirs: Vec::new(),
        lib_dirs: Vec::new(),
    })
}

/// Asks `pkg-config` for the include and library directories; `None` when the command is
/// missing or does not know `embree3`.
fn pkg_config_location() -> Option<Location> {
    let query = |flag: &str| -> Option<String> {
        let out = Command::new("pkg-config")
            .args([flag, "embree3"])
            .output()
            .ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
    };
    let dirs_after = |text: &str, prefix: &str| -> Vec<PathBuf> {
        text.split_whitespace()
            .filter_map(|token| token.strip_prefix(prefix))
            .map(PathBuf::from)
            .collect()
    };
    let cflags = query("--cflags-only-I")?;
    let libs = query("--libs-only-L")?;
    Some(Location {
        rule: "pkg-config embree3",
        include_dirs: dirs_after(&cflags, "-I"),
        lib_dirs: dirs_after(&libs, "-L"),
    })
}

/// Finds `embree3/rtcore.h` ourselves, so a missing header is reported clearly instead of as a
/// clang diagnostic. With `EMBREE_DIR` only that directory counts; otherwise the usual system
/// include directories are searched as the C compiler would.
fn find_header(location: &Location) -> PathBuf {
    let mut candidates = location.include_dirs.clone();
    if location.rule != "EMBREE_DIR" {
        candidates.extend(system_include_dirs());
    }
    candidates
        .iter()
        .map(|dir| dir.join("embree3").join("rtcore.h"))
        .find(|header| header.is_file())
        .unwrap_or_else(|| {
            let searched: Vec<String> =
                candidates.iter().map(|d| d.display().to_string()).collect();
            fail(&format!(
                "<embree3/rtcore.h> not found (searched {} via {})",
                searched.join(", "),
                location.rule
            ))
        })
}

fn system_include_dirs() -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = ["CPATH", "C_INCLUDE_PATH"]
        .iter()
        .filter_map(env::var_os)
        .flat_map(|paths| env::split_paths(&paths).collect::<Vec<_>>())
        .collect();
    dirs.push(PathBuf::from("/usr/local/include"));
    dirs.push(PathBuf::from("/usr/include"));
    dirs
}

/// Runs bindgen. It panics (rather than erring) when libclang cannot be loaded, so the call
/// is wrapped in `catch_unwind` to turn that into the install hint.
fn generate_bindings(location: &Location, out_dir: &Path) -> Result<bindgen::Bindings, String> {
    let manifest_dir = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let mut builder = bindgen::Builder::default()
        .header(manifest_dir.join("wrapper.h").display().to_string())
        .allowlist_function("rtc.*")
        .allowlist_type("RTC.*")
        .allowlist_var("RTC.*")
        // Flags combine with `|`; every other enum becomes a newtype, never a Rust enum, so a
        // value Embree returns outside the declared set is not undefined behaviour.
        .bitfield_enum("RTC.*Flags")
        .newtype_enum("RTC.*")
        // No derive_default: zero-filled rays have mask 0 and miss everything.
        .derive_default(false)
        // RTC_INVALID_GEOMETRY_ID is `((unsigned int)-1)`, a cast cexpr cannot evaluate.
        .clang_macro_fallback()
        .clang_macro_fallback_build_dir(out_dir)
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()));
    for dir in &location.include_dirs {
        builder = builder.clang_arg(format!("-I{}", dir.display()));
    }
    // A silent hook while bindgen runs: the panic message is reported below, without the
    // backtrace the default hook would print in front of it.
    let default_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let outcome =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(move || builder.generate()));
    std::panic::set_hook(default_hook);
    match outcome {
        Ok(Ok(bindings)) => Ok(bindings),
        Ok(Err(e)) => Err(format!("bindgen could not process <embree3/rtcore.h>: {e}")),
        Err(panic) => Err(format!(
            "bindgen panicked ({}); libclang could probably not be loaded",
            panic_text(panic.as_ref())
        )),
    }
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".to_string())
}
