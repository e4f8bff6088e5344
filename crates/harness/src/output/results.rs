//! `raybench results`: a report's figures as one Markdown page, the kind kept in
//! `docs/results/<date>.md` beside the report it was made from. The page is generated, never
//! typed by hand: a heading naming the run and linking its report; the headline (per structure,
//! the geometric mean over scenes of each ratio to the reference, and one sentence on
//! agreement), again against other structures of the run when asked; one table per scene; the
//! SAH cost of every structure that has one; the work per ray of every structure that counts it.

use super::agreement::class_counts;
use super::render::names::structure_names;
use super::summary::sig;
use crate::report::run::{Report, ResultEntry, is_point_workload, throughput_unit};
use raybench_accel::classify::VerdictCounts;
use std::fmt::Write;

/// The geometric mean of the positive finite values, `None` when there is none. A ratio that
/// is zero or missing (a structure skipped on a scene, a reference too fast to time) leaves
/// the scene out rather than pulling the mean to zero.
pub fn geometric_mean(values: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for v in values.into_iter().filter(|v| v.is_finite() && *v > 0.0) {
        sum += v.ln();
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).exp())
}

/// One row of the headline: a structure's geometric means over the scenes it ran on.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadlineRow {
    pub structure: String,
    /// Throughput relative to the reference (higher is faster), one per workload of the run.
    pub workloads: Vec<Option<f64>>,
    /// Build time relative to the reference (lower is faster).
    pub build: Option<f64>,
    /// Bytes held relative to the reference (lower is smaller).
    pub memory: Option<f64>,
    /// Scenes the structure has a result on.
    pub scenes: usize,
}

/// One structure's ratios to the reference, scene by scene: `(ratio, scene)` for each scene
/// that has the ratio. The headline takes their geometric means; the page adds their spread.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRatios {
    pub structure: String,
    /// Throughput relative to the reference, one list per workload of the run.
    pub workloads: Vec<Vec<(f64, String)>>,
    pub build: Vec<(f64, String)>,
    /// Bytes held relative to the reference's on the same scene.
    pub memory: Vec<(f64, String)>,
    /// Scenes the structure has a result on.
    pub scenes: usize,
}

/// Every structure of the run but the reference, in the run's order, with its ratios.
pub fn scene_ratios(report: &Report) -> Vec<SceneRatios> {
    scene_ratios_to(report, &[&report.run.reference])
}

/// Every structure of the run but those of `group`, with its ratios, on each scene, to the
/// best of `group` there: per workload the highest median throughput among them, the shortest
/// median build and the smallest memory. A group of one is one structure's medians: the run's
/// reference, or another structure of the same run such as embree-high (as fair, from the same
/// run). A larger group races an entry, scene by scene, against whichever of several ways of
/// calling one library is faster there, as Embree's stream and 16-ray packet calls are for
/// coherent rays.
pub fn scene_ratios_to(report: &Report, group: &[&str]) -> Vec<SceneRatios> {
    let group_on = |scene: &str| -> Vec<&ResultEntry> {
        report
            .results
            .iter()
            .filter(|r| r.scene == scene && group.contains(&r.structure.as_str()))
            .collect()
    };
    let ratio = |x: f64, base: f64| (base > 0.0).then(|| x / base);
    let best = |values: Vec<f64>, higher: bool| {
        values
            .into_iter()
            .filter(|v| *v > 0.0)
            .reduce(|a, b| if (b > a) == higher { b } else { a })
    };
    structure_names(report)
        .into_iter()
        .filter(|s| !group.contains(&s.as_str()))
        .map(|structure| {
            let entries: Vec<&ResultEntry> = report
                .results
                .iter()
                .filter(|r| r.structure == structure)
                .collect();
            let per_scene = |f: &dyn Fn(&ResultEntry, &[&ResultEntry]) -> Option<f64>| {
                entries
                    .iter()
                    .filter_map(|r| Some((f(r, &group_on(&r.scene))?, r.scene.clone())))
                    .collect::<Vec<(f64, String)>>()
            };
            let workloads = report
                .run
                .workloads
                .iter()
                .map(|wl| {
                    let of = |e: &ResultEntry| {
                        Some(
                            e.workloads
                                .iter()
                                .find(|w| &w.workload == wl)?
                                .mqueries_per_s
                                .median,
                        )
                    };
                    per_scene(&|r: &ResultEntry, bases: &[&ResultEntry]| {
                        let base = best(bases.iter().filter_map(|b| of(b)).collect(), true)?;
                        ratio(of(r)?, base)
                    })
                })
                .collect();
            let build = per_scene(&|r: &ResultEntry, bases: &[&ResultEntry]| {
                let base = best(bases.iter().map(|b| b.build.median_ms).collect(), false)?;
                ratio(r.build.median_ms, base)
            });
            let memory = per_scene(&|r: &ResultEntry, bases: &[&ResultEntry]| {
                let base = best(bases.iter().map(|b| b.memory_bytes as f64).collect(), false)?;
                ratio(r.memory_bytes as f64, base)
            });
            SceneRatios {
                structure,
                workloads,
                build,
                memory,
                scenes: entries.len(),
            }
        })
        .collect()
}

/// The headline rows: every structure of the run but the reference, in the run's order.
pub fn headline_rows(report: &Report) -> Vec<HeadlineRow> {
    headline_rows_to(report, &[&report.run.reference])
}

/// [`headline_rows`] relative to the best of `group` on each scene ([`scene_ratios_to`]).
pub fn headline_rows_to(report: &Report, group: &[&str]) -> Vec<HeadlineRow> {
    let mean = |v: &[(f64, String)]| geometric_mean(v.iter().map(|(x, _)| *x));
    scene_ratios_to(report, group)
        .into_iter()
        .map(|r| HeadlineRow {
            workloads: r.workloads.iter().map(|w| mean(w)).collect(),
            build: mean(&r.build),
            memory: mean(&r.memory),
            structure: r.structure,
            scenes: r.scenes,
        })
        .collect()
}

/// Scenes in the order the report lists them, then any other that has results.
fn scenes(report: &Report) -> Vec<String> {
    let mut names: Vec<String> = report.scenes.iter().map(|s| s.name.clone()).collect();
    for r in &report.results {
        if !names.contains(&r.scene) {
            names.push(r.scene.clone());
        }
    }
    names
}

/// Writes a heading row once, before the first peer (`peer-*`: another crate's structure,
/// registered last), so a table shows raybench's structures and the peers apart.
#[derive(Default)]
struct PeersHeading {
    written: bool,
}

impl PeersHeading {
    fn before(&mut self, s: &mut String, structure: &str, cells: usize) {
        if !self.written && crate::registry::is_peer_name(structure) {
            self.written = true;
            let _ = writeln!(
                s,
                "| *peers: other crates' structures* |{}",
                " |".repeat(cells)
            );
        }
    }
}

/// A ratio with two decimals; one too small for two decimals to show in scientific notation
/// (brute force runs at about 1e-4 of the reference's speed).
pub fn ratio_text(x: f64) -> String {
    if x >= 0.005 {
        format!("{x:.2}")
    } else {
        format!("{x:.1e}")
    }
}

/// A ratio cell: [`ratio_text`], or "-" when there is none.
pub(crate) fn cell(x: Option<f64>) -> String {
    x.map_or("-".to_string(), ratio_text)
}

/// The headline table and the agreement sentence (what `--headline-only` prints, for pasting
/// into the README).
pub fn headline(report: &Report) -> String {
    let mut s = headline_table(report, &[&report.run.reference]);
    let _ = writeln!(s, "\n{}", agreement_line(report));
    s
}

/// The headline's table (and which structures ran on fewer scenes) relative to the best of
/// `group` on each scene (one structure, usually).
fn headline_table(report: &Report, group: &[&str]) -> String {
    let mut s = String::new();
    let workloads = &report.run.workloads;
    s.push_str("| structure |");
    for w in workloads {
        let _ = write!(s, " {w} |");
    }
    s.push_str(" build | memory |\n|---|");
    s.push_str(&"---:|".repeat(workloads.len() + 2));
    s.push('\n');
    let rows = headline_rows_to(report, group);
    let mut peers_heading = PeersHeading::default();
    for row in &rows {
        peers_heading.before(&mut s, &row.structure, workloads.len() + 2);
        let _ = write!(s, "| {} |", row.structure);
        for (w, name) in row.workloads.iter().zip(workloads) {
            // A workload the structure cannot answer on any scene: said, never a number.
            let refused = report
                .results
                .iter()
                .filter(|r| r.structure == row.structure)
                .all(|r| r.not_offered.contains(name));
            match w {
                None if refused => s.push_str(" not offered |"),
                _ => {
                    let _ = write!(s, " {} |", cell(*w));
                }
            }
        }
        let _ = writeln!(s, " {} | {} |", cell(row.build), cell(row.memory));
    }
    let all_scenes = scenes(report).len();
    let fewer: Vec<String> = rows
        .iter()
        .filter(|r| r.scenes < all_scenes)
        .map(|r| format!("{} ({} of {all_scenes})", r.structure, r.scenes))
        .collect();
    if !fewer.is_empty() {
        let _ = writeln!(
            s,
            "\nOver fewer scenes (skipped where a suite limits them, or failed): {}.",
            fewer.join(", ")
        );
    }
    s
}

/// "Agreement with embree-medium: 0 mismatches in N comparisons (…)", or the count.
fn agreement_line(report: &Report) -> String {
    let mut counts = VerdictCounts::default();
    let mut counted_differs = 0;
    for w in report.results.iter().flat_map(|r| &r.workloads) {
        counts += w.agreement.counts;
        counted_differs += w.agreement.counted_path_differs;
    }
    let mismatches = match counts.mismatch {
        1 => "1 mismatch".to_string(),
        k => format!("{k} mismatches"),
    };
    let mut line = format!(
        "Agreement with `{}`: {mismatches} in {} comparisons, one per query of every \
         structure, scene and workload ({})",
        report.run.reference,
        counts.total(),
        class_counts(&counts)
    );
    if counted_differs > 0 {
        let _ = write!(
            line,
            "; the counted path answered differently from the timed path on {counted_differs} \
             queries"
        );
    }
    line.push('.');
    line
}

/// The whole page; `report_link` is where the heading's link to the report points, and
/// `also_against` names other structures of the run the headline is repeated against (say
/// embree-high beside the reference embree-medium), each one structure or a group joined by
/// [`GROUP_JOIN`] (the best of them on each scene: [`scene_ratios_to`]).
pub fn results_page(report: &Report, report_link: &str, also_against: &[String]) -> String {
    let env = &report.header.environment;
    let run = &report.run;
    let date = env.timestamp.get(..10).unwrap_or(&env.timestamp);
    let revision: String = env.git_revision.chars().take(10).collect();
    let mut s = String::new();
    let _ = writeln!(s, "# Results of {date} (revision {revision})\n");
    let points = if run.workloads.iter().any(|w| is_point_workload(w)) {
        format!(", {} points per closest-point workload", run.points)
    } else {
        String::new()
    };
    // One model name can cover CPUs with and without AVX-512, whose kernels differ: the
    // features say which one the figures belong to.
    let features = if env.cpu_flags.is_empty() {
        String::new()
    } else {
        format!(
            "; {}; Embree's {} kernels",
            env.cpu_flags.join(" "),
            env.embree.isa
        )
    };
    let _ = writeln!(
        s,
        "Suite `{}`, {} thread(s), {} rays per ray workload{points}, seed {}, on {} ({} \
         cores{features}); every answer checked against `{}`. Report: \
         [{report_link}]({report_link}).\n",
        run.suite.as_deref().unwrap_or("none"),
        run.threads,
        run.rays,
        run.seed,
        env.cpu_model,
        env.cores,
        run.reference
    );
    let _ = writeln!(
        s,
        "Generated by `raybench results` from the report; do not edit by hand.\n"
    );
    let _ = writeln!(
        s,
        "## Headline\n\nGeometric mean over the scenes of each structure's throughput relative \
         to `{}` in the same run (Mrays/s for ray workloads, Mqueries/s for closest-point \
         workloads; higher is faster), and of its build time and memory relative to `{}` \
         (lower is faster or smaller).\n",
        run.reference, run.reference
    );
    s.push_str(&headline(report));
    for other in also_against {
        let group = against_group(other);
        if let [one] = group[..] {
            let _ = writeln!(
                s,
                "\n## Against `{one}`\n\nThe headline's geometric means relative to `{one}` \
                 in the same run (its medians on each scene).\n"
            );
        } else {
            let names = names_text(&group);
            let _ = writeln!(
                s,
                "\n## Against the faster of {names}\n\nThe headline's geometric means \
                 relative to, on each scene and workload, the faster of {names} in the same \
                 run: the higher of their median throughputs (for build time and memory, the \
                 lower), so each entry races whichever of them does best there.\n"
            );
        }
        s.push_str(&headline_table(report, &group));
    }
    claims_table(&mut s, report);
    scene_tables(&mut s, report);
    sah_table(&mut s, report);
    super::work_per_ray::work_section(&mut s, report);
    if !report.notes.is_empty() || !report.errors.is_empty() {
        s.push_str("\n## Notes\n\n");
        for n in &report.notes {
            let _ = writeln!(s, "- {n}");
        }
        for e in &report.errors {
            let _ = writeln!(s, "- error: {e}");
        }
    }
    s
}

/// Joins the structures of an `--also-against` group: `embree-medium-stream+embree-medium-packet16`.
pub const GROUP_JOIN: char = '+';

/// The structures an `--also-against` value names: one, or a group joined by [`GROUP_JOIN`].
pub fn against_group(value: &str) -> Vec<&str> {
    value.split(GROUP_JOIN).collect()
}

/// "`a`", "`a` and `b`", "`a`, `b` and `c`".
fn names_text(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        _ => quoted.concat(),
    }
}

/// The claims this run decided (none listed when it measured none): claim, figures, verdict.
fn claims_table(s: &mut String, report: &Report) {
    use crate::report::claims::{Verdict, of_report};
    let claims = of_report(report);
    if claims.iter().all(|c| c.verdict == Verdict::NotMeasured) {
        return;
    }
    s.push_str(
        "\n## Claims\n\nEach decided on this run's data by its rule (see \
         [docs/claims.md](../claims.md)).\n\n| claim | figures | verdict |\n|---|---|---|\n",
    );
    let cell = |t: &str| t.replace('|', "\\|");
    for c in &claims {
        let _ = writeln!(
            s,
            "| {} | {} | {} |",
            cell(&c.statement),
            cell(&c.figures.join("; ")),
            c.verdict.text()
        );
    }
}

/// Per scene: build ms (ratio), memory MB, and throughput per workload with its ratio.
fn scene_tables(s: &mut String, report: &Report) {
    let workloads = &report.run.workloads;
    s.push_str("\n## Scenes\n\nBuild time (median) and throughput (median) with the ratio to the reference in parentheses.\n");
    for scene in scenes(report) {
        let entries: Vec<&ResultEntry> = structure_names(report)
            .iter()
            .filter_map(|st| {
                report
                    .results
                    .iter()
                    .find(|r| r.scene == scene && &r.structure == st)
            })
            .collect();
        let Some(first) = entries.first() else {
            continue;
        };
        let _ = writeln!(
            s,
            "\n### {scene}\n\n{} triangles.\n",
            first.triangles.traced
        );
        s.push_str("| structure | build ms | memory MB |");
        for w in workloads {
            let _ = write!(s, " {w} {} |", throughput_unit(w));
        }
        s.push_str("\n|---|");
        s.push_str(&"---:|".repeat(workloads.len() + 2));
        s.push('\n');
        let mut peers_heading = PeersHeading::default();
        for r in entries {
            peers_heading.before(s, &r.structure, workloads.len() + 2);
            let _ = write!(
                s,
                "| {} | {} ({}) | {} |",
                r.structure,
                sig(r.build.median_ms),
                cell(r.build_ratio_to_reference),
                sig(r.memory_bytes as f64 / 1e6)
            );
            for wl in workloads {
                match r.workloads.iter().find(|w| &w.workload == wl) {
                    Some(w) => {
                        let _ = write!(
                            s,
                            " {} ({}) |",
                            sig(w.mqueries_per_s.median),
                            cell(w.speedup_vs_reference)
                        );
                    }
                    None if r.not_offered.contains(wl) => s.push_str(" not offered |"),
                    None => s.push_str(" - |"),
                }
            }
            s.push('\n');
        }
    }
}

/// SAH cost per scene × structure, for the structures that have one.
fn sah_table(s: &mut String, report: &Report) {
    let with_sah: Vec<String> = structure_names(report)
        .into_iter()
        .filter(|st| {
            report
                .results
                .iter()
                .any(|r| &r.structure == st && r.build_stats.sah_cost.is_some())
        })
        .collect();
    if with_sah.is_empty() {
        return;
    }
    s.push_str(
        "\n## SAH cost\n\nThe surface area heuristic's cost of each tree (a node step and a \
         triangle test both cost 1).\n\n| scene |",
    );
    for st in &with_sah {
        let _ = write!(s, " {st} |");
    }
    s.push_str("\n|---|");
    s.push_str(&"---:|".repeat(with_sah.len()));
    s.push('\n');
    for scene in scenes(report) {
        let _ = write!(s, "| {scene} |");
        for st in &with_sah {
            let cost = report
                .results
                .iter()
                .find(|r| r.scene == scene && &r.structure == st)
                .and_then(|r| r.build_stats.sah_cost);
            let _ = write!(
                s,
                " {} |",
                cost.map_or("-".to_string(), |c| format!("{c:.2}"))
            );
        }
        s.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometric_means_skip_what_cannot_be_a_ratio() {
        let g = geometric_mean([2.0, 8.0]).unwrap();
        assert!((g - 4.0).abs() < 1e-12, "{g}");
        assert_eq!(geometric_mean([0.0, f64::NAN, -1.0]), None);
        let g = geometric_mean([3.0, 0.0]).unwrap();
        assert!((g - 3.0).abs() < 1e-12, "a zero leaves its scene out: {g}");
    }

    #[test]
    fn ratios_keep_two_decimals_unless_too_small_to_show() {
        assert_eq!(ratio_text(1.234), "1.23");
        assert_eq!(ratio_text(0.005), "0.01");
        assert_eq!(ratio_text(0.000123), "1.2e-4");
    }
}
