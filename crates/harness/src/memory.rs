//! The machine's memory as `/proc/meminfo` gives it: the total, which bounds the counts a user
//! may ask for ([`crate::cli::bounds`]), and what is available now, which decides whether a run
//! may time one more build of a structure beside the copy it traces (`pipeline/rounds.rs`).
//! Both are capped by the process's control group, as in a container or a CI runner with a
//! memory limit, where the kernel kills the process at the group's limit however much the
//! machine has.

use std::path::{Path, PathBuf};

/// Memory the process may use, in bytes: the machine's, or its control group's limit where
/// that is less; 8 GiB when neither can be read.
pub fn physical() -> u64 {
    let machine = meminfo("MemTotal:");
    let group = this_group().map(|g| g.limit);
    least(machine, group).unwrap_or(8 << 30)
}

/// Memory available for new allocations without swapping, in bytes: the kernel's own
/// estimate, or the room left under the control group's limit where that is less. `None` when
/// neither can be read.
pub fn available() -> Option<u64> {
    least(meminfo("MemAvailable:"), this_group().map(|g| g.room))
}

/// An amount of memory for a message, in GiB with one decimal (in e-notation past a million).
pub fn gib(bytes: f64) -> String {
    let g = bytes / (1u64 << 30) as f64;
    if g < 1e6 {
        format!("{g:.1} GiB")
    } else {
        format!("{g:.1e} GiB")
    }
}

fn least(a: Option<u64>, b: Option<u64>) -> Option<u64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// The process's control group, from `/proc/self/cgroup` and `/sys/fs/cgroup`.
fn this_group() -> Option<Group> {
    let text = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    group(&text, Path::new("/sys/fs/cgroup"))
}

/// The value of one `/proc/meminfo` line, given in KiB there, in bytes.
fn meminfo(key: &str) -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse(&text, key)
}

fn parse(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The tightest memory limit over a control group and its ancestors (a parent's limit binds
/// its children), and the least room left under any of them.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Group {
    limit: u64,
    room: u64,
}

/// The process's [`Group`], from `/proc/self/cgroup`'s text and the cgroup file system mounted
/// at `root`; `None` where no group on the path has a limit. Version 2 groups keep
/// `memory.max` and `memory.current`, version 1 groups `memory.limit_in_bytes` and
/// `memory.usage_in_bytes` under the `memory` hierarchy.
fn group(proc_self_cgroup: &str, root: &Path) -> Option<Group> {
    let mut tightest: Option<Group> = None;
    for line in proc_self_cgroup.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) =
            (fields.next(), fields.next(), fields.next())
        else {
            continue;
        };
        let (base, files) = if id == "0" && controllers.is_empty() {
            (root.to_path_buf(), V2)
        } else if controllers.split(',').any(|c| c == "memory") {
            (root.join("memory"), V1)
        } else {
            continue;
        };
        for dir in ancestors(&base, path) {
            let read = |name: &str| std::fs::read_to_string(dir.join(name)).ok();
            let (Some(limit), Some(usage)) = (read(files.limit), read(files.usage)) else {
                continue;
            };
            let stat = read("memory.stat").unwrap_or_default();
            let Some(g) = limited(&limit, &usage, stat_value(&stat, files.inactive_file)) else {
                continue;
            };
            tightest = Some(match tightest {
                None => g,
                Some(t) => Group {
                    limit: t.limit.min(g.limit),
                    room: t.room.min(g.room),
                },
            });
        }
    }
    tightest
}

/// The files of one cgroup version: the limit, the usage, and the `memory.stat` key of the file
/// cache the kernel would drop before it kills (the usage counts it).
struct Files {
    limit: &'static str,
    usage: &'static str,
    inactive_file: &'static str,
}

const V2: Files = Files {
    limit: "memory.max",
    usage: "memory.current",
    inactive_file: "inactive_file",
};

const V1: Files = Files {
    limit: "memory.limit_in_bytes",
    usage: "memory.usage_in_bytes",
    inactive_file: "total_inactive_file",
};

/// One `memory.stat` value (`key value` lines), 0 when absent.
fn stat_value(stat: &str, key: &str) -> u64 {
    stat.lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(' ')?.trim().parse().ok())
        .unwrap_or(0)
}

/// The group's directory under `base` and each of its parents up to `base` itself.
fn ancestors(base: &Path, path: &str) -> Vec<PathBuf> {
    let mut dir = base.to_path_buf();
    let mut dirs = vec![dir.clone()];
    for part in path
        .split('/')
        .filter(|p| !p.is_empty() && *p != "." && *p != "..")
    {
        dir.push(part);
        dirs.push(dir.clone());
    }
    dirs
}

/// One group's limit and the room left under it, its inactive file cache counted as free (as
/// the kubelet counts a container's working set): `None` when it has no limit (`max`, or
/// version 1's "unlimited", a number near 2^63) or a file does not parse.
fn limited(limit: &str, usage: &str, inactive_file: u64) -> Option<Group> {
    let limit: u64 = limit.trim().parse().ok()?;
    if limit >= 1 << 62 {
        return None;
    }
    let usage: u64 = usage.trim().parse().ok()?;
    let room = limit.saturating_sub(usage.saturating_sub(inactive_file));
    Some(Group { limit, room })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_named_line_in_bytes() {
        let text = "MemTotal:       24576000 kB\nMemFree:  100 kB\nMemAvailable:   12288000 kB\n";
        assert_eq!(parse(text, "MemTotal:"), Some(24_576_000 * 1024));
        assert_eq!(parse(text, "MemAvailable:"), Some(12_288_000 * 1024));
        assert_eq!(parse(text, "SwapTotal:"), None);
        assert_eq!(parse("MemAvailable: lots kB\n", "MemAvailable:"), None);
        assert_eq!(
            parse("MemAvailable: 18446744073709551615 kB\n", "MemAvailable:"),
            None
        );
    }

    #[test]
    #[cfg(target_os = "linux")]
    fn this_machine_says_how_much_is_available() {
        let available = available().expect("MemAvailable in /proc/meminfo");
        let total = meminfo("MemTotal:").expect("MemTotal in /proc/meminfo");
        assert!(
            available <= total && physical() <= total,
            "{available} available"
        );
    }

    fn room(limit: &str, usage: &str, inactive_file: u64) -> Option<u64> {
        limited(limit, usage, inactive_file).map(|g| g.room)
    }

    #[test]
    fn a_limit_leaves_its_room_and_no_limit_none() {
        assert_eq!(room("1000\n", "400\n", 0), Some(600));
        assert_eq!(room("1000\n", "400\n", 100), Some(700));
        assert_eq!(room("1000", "1200", 0), Some(0));
        assert_eq!(room("1000", "300", 500), Some(1000));
        assert_eq!(room("max\n", "400", 0), None);
        assert_eq!(room("9223372036854771712\n", "400", 0), None);
        assert_eq!(room("1000", "?", 0), None);
        let stat = "active_file 7\ninactive_file 250\ntotal_inactive_file 90\n";
        assert_eq!(stat_value(stat, "inactive_file"), 250);
        assert_eq!(stat_value(stat, "total_inactive_file"), 90);
        assert_eq!(stat_value(stat, "shmem"), 0);
    }

    /// A made-up cgroup file system in a temporary directory: the tightest limit of the group
    /// and its parents counts, in either version's files; other controllers are ignored.
    #[test]
    fn the_tightest_group_on_the_path_bounds_the_room() {
        let root = std::env::temp_dir().join(format!("raybench-cgroup-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let write = |dir: &Path, files: &[(&str, &str)]| {
            std::fs::create_dir_all(dir).unwrap();
            for (name, text) in files {
                std::fs::write(dir.join(name), text).unwrap();
            }
        };
        // Version 2: the parent allows 8,000 with 5,000 used; the group 6,000 with 1,000.
        write(
            &root,
            &[("memory.max", "max\n"), ("memory.current", "9000\n")],
        );
        write(
            &root.join("ci"),
            &[("memory.max", "8000\n"), ("memory.current", "5000\n")],
        );
        write(
            &root.join("ci/job"),
            &[("memory.max", "6000\n"), ("memory.current", "1000\n")],
        );
        assert_eq!(
            group("0::/ci/job\n", &root),
            Some(Group {
                limit: 6000,
                room: 3000
            })
        );
        // The parent's file cache, 2,000 of its usage, is room too.
        write(&root.join("ci"), &[("memory.stat", "inactive_file 2000\n")]);
        assert_eq!(
            group("0::/ci/job\n", &root),
            Some(Group {
                limit: 6000,
                room: 5000
            })
        );
        assert_eq!(group("0::/\n", &root), None);
        // Version 1: only the `memory` hierarchy counts.
        let v1 = root.join("memory/docker/abc");
        write(
            &v1,
            &[
                ("memory.limit_in_bytes", "4000\n"),
                ("memory.usage_in_bytes", "2500\n"),
            ],
        );
        let text = "12:cpu,cpuacct:/docker/abc\n4:memory:/docker/abc\n0::/ci/job\n";
        assert_eq!(
            group(text, &root),
            Some(Group {
                limit: 4000,
                room: 1500
            })
        );
        assert_eq!(group("12:cpu:/docker/abc\n", &root), None);
        assert_eq!(group("garbage\n", &root), None);
        std::fs::remove_dir_all(&root).unwrap();
    }
}
