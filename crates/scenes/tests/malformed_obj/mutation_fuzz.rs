//! Stable-Rust fuzzing: seeded mutations of the fixtures.

use super::{big_input_name, fixtures_dir, load_catching_panics};
use crate::table::FIXTURES;
use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use raybench_geom::EMBREE_LARGE;
use raybench_scenes::{Scene, SceneError, load_obj_bytes};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Bytes that steer the parser: digits, signs, separators, line ends, escapes, binary.
const INTERESTING_BYTES: &[u8] = b"0123456789-+./ \t\n\r\\#evfnlotg\x00\xff\x80";
/// Tokens that reach the loader's rules: keywords, extreme numbers and indices, encodings.
const TOKENS: &[&str] = &[
    "v ",
    "vt ",
    "vn ",
    "f ",
    "l ",
    "p ",
    "o x\n",
    "g\n",
    "s off\n",
    "usemtl\n",
    "usemtl m\n",
    "mtllib a.mtl\n",
    "-1",
    "-9",
    "0",
    "1",
    "2",
    "3",
    "4",
    "/",
    "//",
    "1/1/1",
    "-1/-1/-1",
    "99999999999999999999",
    "-99999999999999999999",
    "9223372036854775807",
    "-9223372036854775808",
    "1e999",
    "-1e999",
    "1e-999",
    "2e18",
    "1.8e18",
    "nan",
    "inf",
    "-0",
    "0x10",
    "1.2.3",
    "\\\n",
    "\r",
    "\r\n",
    "\n",
    "\u{feff}",
    "\u{200b}",
    "\u{a0}",
    " 1 2 3",
    " 0 0 0 1 1 1",
    "\nf 1 2 3\n",
    "\nv 0 0 0\n",
];
/// Valid seeds besides the fixtures, so mutations start from files that load.
const VALID: &[&str] = &[
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\nf 1/1/1 2/2/1 3/1/1\nf -1 -2 -3\n",
    "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng b\nv 0 0 1\nf 1 2 4\nl 1 2 3\nf 1 2 3 4\n",
    "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 3 2 1\nf 1 2 3\n",
];
const MAX_INPUT: usize = 64 << 10;

fn seeds() -> Vec<Vec<u8>> {
    let mut seeds: Vec<Vec<u8>> = FIXTURES
        .iter()
        .map(|f| std::fs::read(fixtures_dir().join(f.file)).unwrap())
        .collect();
    seeds.extend(VALID.iter().map(|s| s.as_bytes().to_vec()));
    seeds
}

fn below(rng: &mut Pcg64Mcg, n: usize) -> usize {
    (rng.next_u64() % n.max(1) as u64) as usize
}

/// One random edit: flip, set, insert a token, delete, truncate, duplicate, splice, swap.
fn mutate_once(input: &mut Vec<u8>, seeds: &[Vec<u8>], rng: &mut Pcg64Mcg) {
    let len = input.len();
    let at = below(rng, len + 1);
    match below(rng, 9) {
        0 if len > 0 => input[at.min(len - 1)] ^= 1 << below(rng, 8),
        1 if len > 0 => {
            input[at.min(len - 1)] = INTERESTING_BYTES[below(rng, INTERESTING_BYTES.len())]
        }
        2 | 3 => {
            let token = TOKENS[below(rng, TOKENS.len())].as_bytes();
            input.splice(at..at, token.iter().copied());
        }
        4 => {
            let end = (at + 1 + below(rng, 16)).min(len);
            input.drain(at.min(end)..end);
        }
        5 => input.truncate(at),
        6 => {
            let end = (at + 1 + below(rng, 64)).min(len);
            let copy = input[at.min(end)..end].to_vec();
            let to = below(rng, len + 1);
            input.splice(to..to, copy);
        }
        7 => {
            let other = &seeds[below(rng, seeds.len())];
            let from = below(rng, other.len() + 1);
            input.truncate(at);
            input.extend_from_slice(&other[from..]);
        }
        _ => swap_two_lines(input, rng),
    }
    input.truncate(MAX_INPUT);
}

fn swap_two_lines(input: &mut Vec<u8>, rng: &mut Pcg64Mcg) {
    let mut lines: Vec<Vec<u8>> = input.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect();
    let (a, b) = (below(rng, lines.len()), below(rng, lines.len()));
    lines.swap(a, b);
    *input = lines.join(&b'\n');
}

/// `Err` names the broken invariant: a panic; an error not naming the input first, or not
/// one short line; a tobj rejection the scan let through (an `Obj` error without a line);
/// a scene with no triangles or with a vertex Embree would drop.
fn check_one(input: &[u8]) -> Result<&'static str, String> {
    let name = big_input_name();
    match load_catching_panics(|| load_obj_bytes(name, input)) {
        Err(panic) => Err(format!("panic: {panic}")),
        Ok(Ok(scene)) => check_loaded(&scene).map(|()| "loaded"),
        Ok(Err(e)) => check_rejected(&e),
    }
}

fn check_loaded(scene: &Scene) -> Result<(), String> {
    if scene.mesh.is_empty() {
        return Err("a scene without triangles".into());
    }
    let bad = scene
        .mesh
        .triangles()
        .flat_map(|t| [t.v0, t.v1, t.v2])
        .find(|p| !p.is_finite() || p.abs().max_element() > EMBREE_LARGE);
    match bad {
        Some(p) => Err(format!("a kept triangle has the vertex {p}")),
        None => Ok(()),
    }
}

fn check_rejected(e: &SceneError) -> Result<&'static str, String> {
    let message = e.to_string();
    if !message.starts_with("generated.obj: ") || message.contains('\n') || message.len() > 400 {
        return Err(format!("unclear message: {message:?}"));
    }
    Ok(match e {
        SceneError::Obj { line: None, .. } => {
            return Err(format!(
                "tobj rejected what the scan accepted (no line): {message}"
            ));
        }
        SceneError::Obj { .. } => "rejected with a line",
        SceneError::NotUtf8 { .. } => "not UTF-8",
        SceneError::NoTriangles { .. } => "no triangles",
        _ => "other error",
    })
}

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Saves a failing input next to the temporary files and returns its path.
fn save_failure(input: &[u8], seed: u64, iteration: u64) -> PathBuf {
    let path = std::env::temp_dir().join(format!("raybench-fuzz-{seed:#x}-{iteration}.obj"));
    std::fs::write(&path, input).unwrap();
    path
}

/// Stable-Rust fallback for `cargo fuzz run obj_loader`. Defaults: 3 minutes, no cap on
/// inputs, seed 0x5eed_f022; override with RAYBENCH_FUZZ_SECONDS, RAYBENCH_FUZZ_ITERATIONS
/// and RAYBENCH_FUZZ_SEED. A failure names the seed and iteration and saves the input.
#[test]
#[ignore = "minutes long: run by hand (README, \"Fuzzing the OBJ loader\")"]
fn mutation_fuzz_the_loader() {
    let seed = env_u64("RAYBENCH_FUZZ_SEED", 0x5eed_f022);
    let iterations = env_u64("RAYBENCH_FUZZ_ITERATIONS", u64::MAX);
    let budget = Duration::from_secs(env_u64("RAYBENCH_FUZZ_SECONDS", 180));
    let seeds = seeds();
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut outcomes = std::collections::BTreeMap::<&str, u64>::new();
    let start = Instant::now();
    let mut ran = 0;
    while ran < iterations && start.elapsed() < budget {
        let mut input = seeds[below(&mut rng, seeds.len())].clone();
        for _ in 0..1 + below(&mut rng, 4) {
            mutate_once(&mut input, &seeds, &mut rng);
        }
        match check_one(&input) {
            Ok(outcome) => *outcomes.entry(outcome).or_default() += 1,
            Err(problem) => {
                let saved = save_failure(&input, seed, ran);
                panic!(
                    "seed {seed:#x}, input {ran} (saved as {}): {problem}",
                    saved.display()
                );
            }
        }
        ran += 1;
    }
    eprintln!(
        "mutation fuzz: {ran} inputs in {:.0} s (seed {seed:#x}), no failure; outcomes {outcomes:?}",
        start.elapsed().as_secs_f64()
    );
    assert!(ran > 0);
}

/// The fuzzer's own check: a short seeded run in every test pass, so the harness cannot rot.
#[test]
fn a_short_mutation_run_finds_nothing() {
    let seeds = seeds();
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let mut loaded = 0;
    for i in 0..3000 {
        let mut input = seeds[below(&mut rng, seeds.len())].clone();
        mutate_once(&mut input, &seeds, &mut rng);
        match check_one(&input) {
            Ok("loaded") => loaded += 1,
            Ok(_) => {}
            Err(problem) => panic!(
                "seed 7, input {i}: {problem}\n{:?}",
                String::from_utf8_lossy(&input)
            ),
        }
    }
    assert!(
        loaded > 100,
        "mutations must also produce loadable files: {loaded}"
    );
}
