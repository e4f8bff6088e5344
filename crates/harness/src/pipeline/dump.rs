//! `--dump-hits DIR`: every ray and its answer, per scene × structure × workload, in a small
//! little-endian binary format any outside tool can read and check.
//!
//! One file per scene × structure × workload, named `<scene>__<structure>__<workload>.hits`
//! (the scene name made file-safe), plus `index.json` listing every file with its scene,
//! structure, workload, record count and kind. Every file is written atomically.
//!
//! Ray workloads only: closest-point workloads (`points-near`, `points-volume`) are not dumped
//! (their disputed queries are in the report with the point's bits), and a run that has them
//! says so in a note.
//!
//! ## Format, version 1 (all little-endian)
//!
//! Header, 32 bytes:
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | `[u8; 8]` | magic `RAYBHITS` |
//! | 8 | u32 | version = 1 |
//! | 12 | u32 | record size in bytes = 56 |
//! | 16 | u64 | record count |
//! | 24 | u32 | flags: bit 0 set = any-hit workload (records carry occlusion, no hit data) |
//! | 28 | u32 | reserved, 0 |
//!
//! Then `record count` records of 56 bytes:
//!
//! | offset | type | field |
//! |---|---|---|
//! | 0 | u32 | ray index in the workload's ray list (a subsample skips indices) |
//! | 4 | u32 | flags: bit 0 set = hit (closest-hit workloads) or occluded (any-hit workloads) |
//! | 8 | 8 × f32 | the ray: origin x, y, z, direction x, y, z, t_min, t_max (the exact bits traced) |
//! | 40 | f32 | t of the closest hit; +inf on a miss and in any-hit records |
//! | 44 | u32 | prim: the hit triangle's index in the mesh; `u32::MAX` on a miss and in any-hit records |
//! | 48 | f32 | u (Embree's barycentric of vertex 1); 0 when there is no hit |
//! | 52 | f32 | v (barycentric of vertex 2); 0 when there is no hit |
//!
//! With numpy: `np.fromfile(path, dtype=[("index","<u4"),("flags","<u4"),("ray","<f4",8),
//! ("t","<f4"),("prim","<u4"),("u","<f4"),("v","<f4")], offset=32)`.

use super::measure::Answers;
use crate::atomic::write_atomic;
use anyhow::{Context, Result, bail, ensure};
use raybench_accel::Hit;
use raybench_geom::Ray;
use raybench_scenes::Workload;
use raybench_scenes::input::read_input;
use serde::{Deserialize, Serialize};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

pub const MAGIC: [u8; 8] = *b"RAYBHITS";
pub const VERSION: u32 = 1;
pub const HEADER_BYTES: usize = 32;
pub const RECORD_BYTES: usize = 56;
/// Header flag: the workload asks "is anything in the way" (records carry occlusion only).
pub const ANY_HIT_WORKLOAD: u32 = 1;
/// Record flag: hit (closest-hit workloads) or occluded (any-hit workloads).
pub const RECORD_HIT: u32 = 1;
/// `prim` of a record without a hit.
pub const NO_PRIM: u32 = u32::MAX;

/// One ray and its answer, as read back from a dump.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DumpRecord {
    pub ray_index: u32,
    pub ray_bits: [u32; 8],
    /// Closest-hit workloads: the hit, `None` for a miss. Always `None` for any-hit workloads.
    pub hit: Option<Hit>,
    /// Any-hit workloads: occluded. Closest-hit workloads: `hit.is_some()`.
    pub occluded: bool,
}

impl DumpRecord {
    pub fn ray(&self) -> Ray {
        Ray::from_bits(self.ray_bits)
    }
}

/// A whole dump file.
#[derive(Clone, Debug, PartialEq)]
pub struct HitDump {
    pub any_hit: bool,
    pub records: Vec<DumpRecord>,
}

/// One line of `index.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DumpEntry {
    pub file: String,
    pub scene: String,
    pub structure: String,
    pub workload: String,
    pub any_hit: bool,
    pub records: usize,
}

/// `index.json`: what each file of the dump directory holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DumpIndex {
    pub format: String,
    pub files: Vec<DumpEntry>,
}

/// The bytes of a dump: `rays[k]` answered by `answers` entry `k`, with ray index
/// `indices[k]` (or `k` when `indices` is `None`).
pub fn encode(rays: &[Ray], indices: Option<&[usize]>, answers: &Answers) -> Result<Vec<u8>> {
    ensure!(
        answers.len() == rays.len() && indices.is_none_or(|i| i.len() == rays.len()),
        "dump: {} rays, {} answers, {:?} indices",
        rays.len(),
        answers.len(),
        indices.map(<[usize]>::len)
    );
    let any_hit = matches!(answers, Answers::Any(_));
    let mut out = Vec::with_capacity(HEADER_BYTES + RECORD_BYTES * rays.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(RECORD_BYTES as u32).to_le_bytes());
    out.extend_from_slice(&(rays.len() as u64).to_le_bytes());
    out.extend_from_slice(&(if any_hit { ANY_HIT_WORKLOAD } else { 0 }).to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    for (k, ray) in rays.iter().enumerate() {
        let index = indices.map_or(k, |i| i[k]);
        let index = u32::try_from(index).context("dump: ray index beyond u32")?;
        let (flag, hit) = match answers {
            Answers::Closest(h) => (h[k].is_some(), h[k]),
            Answers::Any(o) => (o[k], None),
        };
        push_record(&mut out, index, ray, flag, hit);
    }
    Ok(out)
}

fn push_record(out: &mut Vec<u8>, index: u32, ray: &Ray, flag: bool, hit: Option<Hit>) {
    out.extend_from_slice(&index.to_le_bytes());
    out.extend_from_slice(&(if flag { RECORD_HIT } else { 0 }).to_le_bytes());
    for bits in ray.to_bits() {
        out.extend_from_slice(&bits.to_le_bytes());
    }
    let (t, prim, u, v) = hit.map_or((f32::INFINITY, NO_PRIM, 0.0, 0.0), |h| {
        (h.t, h.prim, h.u, h.v)
    });
    out.extend_from_slice(&t.to_le_bytes());
    out.extend_from_slice(&prim.to_le_bytes());
    out.extend_from_slice(&u.to_le_bytes());
    out.extend_from_slice(&v.to_le_bytes());
}

fn u32_at(bytes: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"))
}

/// Reads a dump file back, checking the magic, version, record size and length.
pub fn read_dump(path: &Path) -> Result<HitDump> {
    let bytes = read_input(path)?;
    decode(&bytes).with_context(|| format!("{}", path.display()))
}

/// Parses the bytes of a dump (see the module documentation).
pub fn decode(bytes: &[u8]) -> Result<HitDump> {
    ensure!(
        bytes.len() >= HEADER_BYTES,
        "{} bytes: shorter than the {HEADER_BYTES}-byte header",
        bytes.len()
    );
    ensure!(bytes[..8] == MAGIC, "not a raybench hit dump (bad magic)");
    let version = u32_at(bytes, 8);
    ensure!(
        version == VERSION,
        "dump version {version}, expected {VERSION}"
    );
    let record_bytes = u32_at(bytes, 12) as usize;
    ensure!(
        record_bytes == RECORD_BYTES,
        "record size {record_bytes}, expected {RECORD_BYTES}"
    );
    let count = u64::from_le_bytes(bytes[16..24].try_into().expect("8 bytes"));
    let body = &bytes[HEADER_BYTES..];
    if count.checked_mul(RECORD_BYTES as u64) != Some(body.len() as u64) {
        bail!(
            "header says {count} records, the file holds {} bytes of records",
            body.len()
        );
    }
    let any_hit = u32_at(bytes, 24) & ANY_HIT_WORKLOAD != 0;
    let records = body
        .chunks_exact(RECORD_BYTES)
        .map(|r| decode_record(r, any_hit))
        .collect();
    Ok(HitDump { any_hit, records })
}

fn decode_record(r: &[u8], any_hit: bool) -> DumpRecord {
    let flag = u32_at(r, 4) & RECORD_HIT != 0;
    let ray_bits: [u32; 8] = std::array::from_fn(|i| u32_at(r, 8 + 4 * i));
    let hit = (!any_hit && flag).then(|| Hit {
        t: f32::from_bits(u32_at(r, 40)),
        prim: u32_at(r, 44),
        u: f32::from_bits(u32_at(r, 48)),
        v: f32::from_bits(u32_at(r, 52)),
    });
    DumpRecord {
        ray_index: u32_at(r, 0),
        ray_bits,
        hit,
        occluded: flag,
    }
}

/// A dump directory being filled: unique file names, and the index written at the end.
#[derive(Debug)]
pub struct DumpDir {
    dir: PathBuf,
    used: HashSet<String>,
    files: Vec<DumpEntry>,
}

impl DumpDir {
    /// Dumps into `dir` (created if needed). The commands claim it first (`crate::outdir`:
    /// locked, checked, proven writable) before any work.
    pub fn create(dir: &Path) -> Result<DumpDir> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--dump-hits {} cannot be created", dir.display()))?;
        Ok(DumpDir {
            dir: dir.to_path_buf(),
            used: HashSet::new(),
            files: Vec::new(),
        })
    }

    /// Writes one scene × structure × workload (see [`encode`] for the arguments).
    pub fn write(
        &mut self,
        scene: &str,
        structure: &str,
        workload: &str,
        rays: &[Ray],
        indices: Option<&[usize]>,
        answers: &Answers,
    ) -> Result<PathBuf> {
        let bytes = encode(rays, indices, answers)?;
        let file = self.unique_file_name(scene, structure, workload);
        let path = self.dir.join(&file);
        write_atomic(&path, &bytes)?;
        self.files.push(DumpEntry {
            file,
            scene: scene.to_string(),
            structure: structure.to_string(),
            workload: workload.to_string(),
            any_hit: matches!(answers, Answers::Any(_)),
            records: rays.len(),
        });
        Ok(path)
    }

    /// `scene__structure__workload.hits`, with `-2`, `-3`… when two scene names map to the
    /// same file-safe name (`a:b` and `a-b`).
    fn unique_file_name(&mut self, scene: &str, structure: &str, workload: &str) -> String {
        let stem = format!(
            "{}__{structure}__{workload}",
            crate::output::render::names::slug(scene)
        );
        let file = (1..)
            .map(|k| match k {
                1 => format!("{stem}.hits"),
                k => format!("{stem}-{k}.hits"),
            })
            .find(|f| !self.used.contains(f))
            .expect("some suffix is free");
        self.used.insert(file.clone());
        file
    }

    /// Writes `index.json` (atomically) and returns its path.
    pub fn finish(self) -> Result<PathBuf> {
        let index = DumpIndex {
            format: format!(
                "raybench hit dump v{VERSION}: {HEADER_BYTES}-byte header, {RECORD_BYTES}-byte \
                 little-endian records (see docs/report-format.md, \"Hit dumps\")"
            ),
            files: self.files,
        };
        crate::report::write_json_atomic(&self.dir, "index.json", &index)
    }
}

/// The note a run or verify with `--dump-hits` and closest-point workloads carries.
pub(crate) fn points_not_dumped(dumping: bool, workloads: &[Workload]) -> Option<String> {
    let points: Vec<&str> = workloads
        .iter()
        .filter(|w| w.is_point_query())
        .map(Workload::name)
        .collect();
    (dumping && !points.is_empty()).then(|| {
        format!(
            "--dump-hits covers ray workloads only: {} not dumped",
            points.join(", ")
        )
    })
}

/// Reads `index.json` of a dump directory.
pub fn read_index(dir: &Path) -> Result<DumpIndex> {
    let path = dir.join("index.json");
    let bytes = read_input(&path)?;
    serde_json::from_slice(&bytes).with_context(|| format!("parsing {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use raybench_geom::Vec3;

    fn rays() -> Vec<Ray> {
        vec![
            Ray::infinite(Vec3::new(0.5, 0.25, 1.0), Vec3::new(0.0, -0.0, -1.0)),
            Ray::new(Vec3::ONE, Vec3::X, 0.125, 7.5),
        ]
    }

    #[test]
    fn closest_hits_round_trip_bit_for_bit() {
        let hit = Hit {
            t: 1.0,
            prim: 3,
            u: 0.25,
            v: 0.5,
        };
        let answers = Answers::Closest(vec![Some(hit), None]);
        let bytes = encode(&rays(), Some(&[4, 9]), &answers).unwrap();
        assert_eq!(bytes.len(), HEADER_BYTES + 2 * RECORD_BYTES);
        let back = decode(&bytes).unwrap();
        assert!(!back.any_hit);
        assert_eq!(back.records[0].ray_index, 4);
        assert_eq!(back.records[0].hit, Some(hit));
        assert_eq!(back.records[0].ray_bits, rays()[0].to_bits());
        assert_eq!(
            back.records[1],
            DumpRecord {
                ray_index: 9,
                ray_bits: rays()[1].to_bits(),
                hit: None,
                occluded: false,
            }
        );
        // A miss is written as prim = u32::MAX and t = +inf.
        let miss = &bytes[HEADER_BYTES + RECORD_BYTES..];
        assert_eq!(u32_at(miss, 44), NO_PRIM);
        assert_eq!(f32::from_bits(u32_at(miss, 40)), f32::INFINITY);
    }

    #[test]
    fn occlusion_round_trips_without_hit_data() {
        let answers = Answers::Any(vec![true, false]);
        let back = decode(&encode(&rays(), None, &answers).unwrap()).unwrap();
        assert!(back.any_hit);
        let flags: Vec<(u32, bool, Option<Hit>)> = back
            .records
            .iter()
            .map(|r| (r.ray_index, r.occluded, r.hit))
            .collect();
        assert_eq!(flags, [(0, true, None), (1, false, None)]);
    }

    #[test]
    fn damaged_files_are_clear_errors() {
        let good = encode(&rays(), None, &Answers::Any(vec![true, false])).unwrap();
        let err = |b: &[u8]| format!("{:#}", decode(b).unwrap_err());
        assert!(err(&good[..10]).contains("header"));
        assert!(err(&good[..good.len() - 1]).contains("2 records"));
        let mut bad = good.clone();
        bad[0] = b'X';
        assert!(err(&bad).contains("magic"));
        let mut bad = good;
        bad[8] = 2;
        assert!(err(&bad).contains("version 2"));
    }
}
