//! The example's binary as its user runs it: the whole raybench CLI with `toy-bvh` registered,
//! `verify` holding the toy against Embree and brute force on two scenes and five workloads.

use std::process::Command;

#[test]
fn the_binary_verifies_the_toy_with_no_mismatch() {
    let dir = std::env::temp_dir().join(format!("custom-structure-verify-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_custom-structure"))
        .args([
            "verify",
            "--structures",
            "toy-bvh,bvh8-binned",
            "--scenes",
            "teapot,sphere:triangles=20000",
            "--workloads",
            "primary,random,shadow,diffuse,points-near",
            "--rays",
            "10000",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    // Exit 2 is a mismatch, 1 an error: either names what went wrong on stderr.
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let toy_rows: Vec<&str> = stdout
        .lines()
        .filter(|l| l.starts_with("toy-bvh "))
        .collect();
    // One row per reference: embree-medium, embree-robust and brute force.
    assert!(toy_rows.len() >= 3, "{stdout}");
    for row in &toy_rows {
        assert!(row.contains(" 0 mismatches in "), "{row}\n{stdout}");
    }
    std::fs::remove_dir_all(dir).ok();
}
