//! What `raybench verify` prints: per structure and reference, every class and the agreement
//! sentence; how much brute force checked; replay commands for the first mismatches.

use super::agreement::class_counts;
use crate::report::verify::VerifyReport;
use raybench_accel::classify::VerdictCounts;
use std::fmt::Write;

/// Replay commands printed for the first mismatches.
pub const REPLAY_COMMANDS: usize = 5;

/// A `raybench replay` command line for each of the first `n` mismatches.
pub fn replay_commands(report: &VerifyReport, n: usize) -> Vec<String> {
    let mut out = Vec::new();
    for r in &report.results {
        let Some(scene) = report.scenes.iter().find(|s| s.name == r.scene) else {
            continue;
        };
        for v in &r.agreements {
            for d in &v.first_point_mismatches {
                out.push(format!(
                        "# {} / {} point {}: {} vs {}: {} (point bits {}; `raybench replay` takes rays only)",
                        r.scene,
                        r.workload,
                        d.index,
                        r.structure,
                        v.reference,
                        d.verdict,
                        d.point_bits.join(",")
                    ));
                if out.len() == n {
                    return out;
                }
            }
            for d in &v.first_mismatches {
                let structures = [r.structure.as_str(), v.reference.as_str()];
                out.push(format!(
                    "# {} / {} ray {}: {} vs {}: {}\n{}",
                    r.scene,
                    r.workload,
                    d.index,
                    r.structure,
                    v.reference,
                    d.verdict,
                    replay_command(&scene.spec, report.settings.seed, &structures, &d.ray_bits)
                ));
                if out.len() == n {
                    return out;
                }
            }
        }
    }
    out
}

/// A ready-to-paste `raybench replay` command line.
pub fn replay_command(
    scene_spec: &str,
    seed: u64,
    structures: &[&str],
    ray_bits: &[String],
) -> String {
    let mut names: Vec<&str> = Vec::new();
    for s in structures {
        if !names.contains(s) {
            names.push(s);
        }
    }
    format!(
        "raybench replay --scene {} --seed {seed} --structure {} --ray {}",
        shell_quote(scene_spec),
        names.join(","),
        ray_bits.join(",")
    )
}

/// Quotes `s` for a POSIX shell unless it is made of characters that need none.
fn shell_quote(s: &str) -> String {
    let plain = !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./:=,+@%".contains(c));
    if plain {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// The table `raybench verify` prints: per structure and reference, every class and the
/// agreement sentence; how much brute force checked; replay commands for the first mismatches.
pub fn verify_table(report: &VerifyReport) -> String {
    let mut out = String::new();
    let s = &report.settings;
    let _ = writeln!(
        out,
        "Verified {} structures on {} scenes ({} workloads, seed {}, {} threads) against {}.",
        s.structures.len(),
        report.scenes.len(),
        s.workloads.len(),
        s.seed,
        s.threads,
        s.references.join(", ")
    );
    let _ = writeln!(out, "{}", brute_force_coverage(report));
    let _ = writeln!(
        out,
        "\n{:<22} {:<14} {:>9} {:>9} {:>9} {:>10} {:>6} {:>8} {:>8} {:>8} {:>8}  agreement",
        "structure",
        "reference",
        "rays",
        "both_miss",
        "exact",
        "within_tol",
        "tie",
        "boundary",
        "edge_amb",
        "mismatch",
        "cnt≠timed"
    );
    // cnt≠timed: counted-path answers that differ from the timed path's with no explanation
    // (explained differences are listed in the notes below).
    for row in &report.totals {
        let c = &row.counts;
        let _ = writeln!(
            out,
            "{:<22} {:<14} {:>9} {:>9} {:>9} {:>10} {:>6} {:>8} {:>8} {:>8} {:>8}  {}",
            row.structure,
            row.reference,
            row.queries,
            c.both_miss,
            c.exact,
            c.within_tolerance,
            c.tie,
            c.boundary,
            c.edge_ambiguous,
            c.mismatch,
            row.counted_path_differs,
            row.agreement
        );
    }
    let mut all = VerdictCounts::default();
    report.totals.iter().for_each(|r| all += r.counts);
    // The same ray appears once per structure × reference here, so these comparisons are not
    // independent and no bound is given for their sum; each row's bound stands on its own.
    let _ = writeln!(
        out,
        "\nAll rows: {} mismatches in {} comparisons ({}).",
        all.mismatch,
        all.total(),
        class_counts(&all)
    );
    write_mismatch_replays(&mut out, report);
    for n in &report.notes {
        let _ = writeln!(out, "note: {n}");
    }
    for e in &report.errors {
        let _ = writeln!(out, "error: {e}");
    }
    out
}

fn write_mismatch_replays(out: &mut String, report: &VerifyReport) {
    let commands = replay_commands(report, REPLAY_COMMANDS);
    if commands.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "\n{} mismatches (and counted-path differences); replay the first {} with:",
        report.mismatches(),
        commands.len()
    );
    for c in commands {
        let _ = writeln!(out, "{c}");
    }
}

/// "bruteforce checked 54,000 of 60,000 rays; subsampled: bunny (2,879 of 5,000 per workload)".
fn brute_force_coverage(report: &VerifyReport) -> String {
    let (mut checked, mut total) = (0, 0);
    let mut subsampled = Vec::new();
    for scene in &report.scenes {
        let c: usize = scene.workloads.iter().map(|w| w.brute_force_queries).sum();
        let t: usize = scene.workloads.iter().map(|w| w.queries).sum();
        checked += c;
        total += t;
        if c < t {
            subsampled.push(format!("{} ({c} of {t})", scene.name));
        }
    }
    let budget = report.settings.brute_force_budget;
    let mut line = format!(
        "Brute force checked {checked} of {total} rays (budget {budget:.1e} ray–triangle tests per scene × workload)"
    );
    if subsampled.is_empty() {
        line.push_str(": every ray.");
    } else {
        let _ = write!(
            line,
            "; evenly spaced subsamples on {}.",
            subsampled.join(", ")
        );
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replay_commands_quote_what_the_shell_would_split() {
        let bits = ["0x3f800000".to_string(), "0x00000000".to_string()];
        assert_eq!(
            replay_command(
                "sphere:triangles=800,radius=2",
                7,
                &["grid", "bruteforce"],
                &bits
            ),
            "raybench replay --scene sphere:triangles=800,radius=2 --seed 7 \
             --structure grid,bruteforce --ray 0x3f800000,0x00000000"
        );
        assert_eq!(
            replay_command("my scenes/it's.obj", 1, &["grid", "grid"], &bits),
            "raybench replay --scene 'my scenes/it'\\''s.obj' --seed 1 --structure grid \
             --ray 0x3f800000,0x00000000"
        );
    }
}
