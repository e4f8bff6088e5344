//! `raybench list`: the structures, scene generators, real scenes, workloads and suites.

use super::scene::{write_generators, write_real_scenes};
use crate::registry::Registry;
use anyhow::Result;
use raybench_scenes::Workload;
use std::io::Write;
use std::process::ExitCode;

pub fn run(registry: &Registry) -> Result<ExitCode> {
    let mut out = std::io::stdout().lock();
    write_structures(registry, &mut out)?;
    writeln!(out)?;
    write_generators(&mut out, false)?;
    writeln!(out)?;
    write_real_scenes(&mut out)?;
    drop(out);
    println!("\nWorkloads:");
    for w in Workload::ALL {
        println!("  {:<24} {}", w.name(), w.description());
    }
    println!("\nSuites ({}):", raybench_scenes::suites_dir().display());
    for (path, suite) in raybench_scenes::list_suites()? {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().to_string())
            .unwrap_or_default();
        println!(
            "  {stem:<24} {} ({} scenes, {} rays{})",
            suite.description,
            suite.scenes.len(),
            suite.rays,
            suite
                .points
                .map(|p| format!(", {p} points"))
                .unwrap_or_default()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The structures of `registry` under three headings: raybench's own, the peers (other crates'
/// structures) and those the running program registered; an empty group has no heading.
pub fn write_structures(registry: &Registry, out: &mut impl Write) -> std::io::Result<()> {
    let all = registry.entries();
    let own = all.iter().filter(|e| !e.peer && !e.registered).collect();
    let peers = all.iter().filter(|e| e.peer).collect();
    let registered: Vec<_> = all.iter().filter(|e| e.registered).collect();
    for (heading, entries) in [
        ("Structures:", own),
        ("\nPeers (other crates' structures):", peers),
        ("\nRegistered by this program:", registered),
    ] {
        if entries.is_empty() {
            continue;
        }
        writeln!(out, "{heading}")?;
        for e in entries {
            let limit = e
                .suite_triangle_limit
                .map(|l| format!(" (suites: up to {l} triangles)"))
                .unwrap_or_default();
            writeln!(out, "  {:<24} {}{limit}", e.name, e.description)?;
        }
        // Peers this build could not compile in, named with the reason, after the others.
        #[cfg(feature = "peers")]
        if heading.contains("Peers") {
            for (name, why) in crate::peers::unavailable() {
                writeln!(out, "  {name:<24} unavailable in this build: {why}")?;
            }
        }
    }
    Ok(())
}
