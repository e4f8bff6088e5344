//! The built-in structures take the run's memory limit: each of our builders refuses past it
//! with "scene too large" instead of planning on memory the machine may not have, Embree's
//! entries hand it to their device's memory monitor, and the report's parameters record the
//! limit each build had.

use raybench_accel::BuildError;
use raybench_harness::Registry;
use raybench_harness::memory;
use raybench_harness::registry::BuildContext;

#[test]
fn the_limit_is_half_of_this_machines_memory_at_most_8_gib() {
    let limit = BuildContext::new(1).memory_limit_bytes;
    assert!(limit > 0);
    assert!(limit <= 8 << 30, "{limit}");
    assert!(limit <= memory::physical() / 2, "{limit}");
    assert_eq!(limit, (memory::physical() / 2).min(8 << 30));
}

#[test]
fn every_one_of_our_structures_refuses_past_the_limit_and_records_the_limit_it_had() {
    let mesh = raybench_scenes::resolve("sphere:triangles=2000", 1)
        .unwrap()
        .mesh;
    let tight = BuildContext {
        memory_limit_bytes: 4096,
        ..BuildContext::new(1)
    };
    let roomy = BuildContext {
        memory_limit_bytes: 3 << 30,
        ..BuildContext::new(1)
    };
    let (mut ours, mut embree) = (0, 0);
    for entry in Registry::builtin().entries() {
        // Brute force allocates nothing.
        if entry.name.starts_with("bruteforce") || entry.peer {
            continue;
        }
        let limit = format!("\"memory_limit_bytes\":{}", 3u64 << 30);
        if entry.name.starts_with("embree") {
            // Embree's limit is its device's, shared by every Embree build in this process: a
            // 4 KiB limit here would refuse the builds of tests running beside this one. The
            // embree crate's device tests refuse builds on a device of their own.
            let built = entry.build(mesh.clone(), &roomy).unwrap();
            let json = built.params.to_string();
            assert!(json.contains(&limit), "{}: {json}", entry.name);
            embree += 1;
            continue;
        }
        ours += 1;
        match entry.build(mesh.clone(), &tight) {
            Err(BuildError::TooLarge { limit_bytes, .. }) => {
                assert_eq!(limit_bytes, 4096, "{}", entry.name)
            }
            Err(e) => panic!("{}: {e}", entry.name),
            Ok(_) => panic!("{} built within 4 KiB", entry.name),
        }
        let built = entry.build(mesh.clone(), &roomy).unwrap();
        let json = built.params.to_string();
        assert!(json.contains(&limit), "{}: {json}", entry.name);
    }
    assert_eq!(ours, 27, "our structures with a memory limit");
    assert!(embree >= 7, "{embree} Embree entries");
}
