//! The machine's memory as `/proc/meminfo` gives it: the total, which bounds the counts a user
//! may ask for ([`crate::cli::bounds`]), and what is available now, which decides whether a run
//! may time one more build of a structure beside the copy it traces (`pipeline/rounds.rs`).

/// Physical memory in bytes, or 8 GiB when it cannot be read.
pub fn physical() -> u64 {
    meminfo("MemTotal:").unwrap_or(8 << 30)
}

/// Memory available for new allocations without swapping, in bytes (the kernel's own
/// estimate), or `None` when it cannot be read.
pub fn available() -> Option<u64> {
    meminfo("MemAvailable:")
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
        assert!(available <= physical(), "{available} available");
    }
}
