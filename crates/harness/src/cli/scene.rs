//! `raybench scene list | export | preview`: see what scenes exist, write one as OBJ, and render
//! a shaded picture of it through its camera (see [`crate::output::preview`]).
//!
//! * [`write_generators`] and [`write_real_scenes`] print the scene part of both `raybench list`
//!   and `raybench scene list` (the latter adds each generator's named views).
//! * [`export`]: a scene spec or an OBJ path → an OBJ file, atomically, through
//!   [`raybench_scenes::write_obj`]; the file loads back bit for bit.

use crate::output::preview::preview;
use anyhow::{Result, bail};
use clap::{Args, Subcommand};
use raybench_scenes::GeneratorInfo;
use std::io::{self, Write};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where real OBJ scenes are looked for: `../shared/scenes` next to the repository.
pub fn real_scenes_dir() -> PathBuf {
    raybench_scenes::suites_dir().join("../../shared/scenes")
}

/// The `*.obj` files (any case) in [`real_scenes_dir`], sorted.
pub fn real_scenes() -> io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(real_scenes_dir())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("obj")))
        .collect();
    files.sort();
    Ok(files)
}

/// The names of `info`'s views, by generating it small; the error says what failed (a generator
/// error, or a panic, which is caught so one broken generator does not hide the others).
pub fn generator_views(info: &GeneratorInfo) -> Result<Vec<String>, String> {
    let spec = raybench_scenes::view_probe_spec(info);
    match catch_unwind(AssertUnwindSafe(|| raybench_scenes::view_names(info))) {
        Ok(Ok(names)) => Ok(names),
        Ok(Err(e)) => Err(e.to_string()),
        Err(panic) => Err(format!(
            "generator spec `{spec}`: panicked: {}",
            panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "no message".into())
        )),
    }
}

/// Every generator with its description and parameters; with `views`, also its named views
/// (or why they could not be learned). Returns how many generators failed to generate.
pub fn write_generators(out: &mut dyn Write, views: bool) -> io::Result<usize> {
    let mut failed = 0;
    writeln!(
        out,
        "Scene generators (spec: name[:key=value,...]; every generator also takes view=NAME):"
    )?;
    for g in raybench_scenes::generators() {
        writeln!(out, "  {:<24} {}", g.name, g.description)?;
        for p in g.params {
            writeln!(out, "  {:<24}   {}: {}", "", p.key, p.describe())?;
        }
        if views {
            match generator_views(g) {
                Ok(names) => writeln!(out, "  {:<24}   views: {}", "", names.join(", "))?,
                Err(e) => {
                    failed += 1;
                    writeln!(out, "  {:<24}   views: ERROR: {e}", "")?;
                }
            }
        }
    }
    writeln!(
        out,
        "  {:<24} a Wavefront OBJ file (triangulated, positions only){}",
        "PATH.obj",
        if views { "; views: default" } else { "" }
    )?;
    Ok(failed)
}

/// The real OBJ scenes in [`real_scenes_dir`] with their sizes, or a note that it is absent.
pub fn write_real_scenes(out: &mut dyn Write) -> io::Result<()> {
    let dir = real_scenes_dir();
    let shown = dir.canonicalize().unwrap_or_else(|_| dir.clone());
    match real_scenes() {
        Ok(files) => {
            writeln!(out, "Real scenes ({}):", shown.display())?;
            if files.is_empty() {
                writeln!(out, "  (no .obj files)")?;
            }
            for f in files {
                let size = std::fs::metadata(&f).map(|m| m.len()).unwrap_or(0);
                let name = f.file_name().unwrap_or_default().to_string_lossy();
                writeln!(
                    out,
                    "  {name:<32} {:>8.1} MB  {}",
                    size as f64 / 1e6,
                    shown.join(&*name).display()
                )?;
            }
        }
        Err(_) => writeln!(
            out,
            "Real scenes: {} is absent (suites skip those files with a note)",
            dir.display()
        )?,
    }
    Ok(())
}

/// `raybench scene list`. Generators that fail are listed with their error (and counted on
/// stderr), not hidden; the listing itself still succeeds.
fn list(out: &mut dyn Write) -> io::Result<()> {
    let failed = write_generators(out, true)?;
    writeln!(out)?;
    write_real_scenes(out)?;
    out.flush()?;
    if failed > 0 {
        eprintln!("raybench: {failed} generator(s) failed to generate (see `views: ERROR` above)");
    }
    Ok(())
}

fn is_obj_path(name: &str) -> bool {
    Path::new(name)
        .extension()
        .is_some_and(|x| x.eq_ignore_ascii_case("obj"))
}

/// `name` with `triangles=N` set: an error for an OBJ path, for a generator without a
/// `triangles` parameter (naming it and its parameters), and for a spec that sets it already.
/// An unknown generator is left as it is, for [`raybench_scenes::resolve`] to report.
pub fn with_triangles(name: &str, triangles: Option<u64>) -> Result<String> {
    let Some(n) = triangles else {
        return Ok(name.to_owned());
    };
    if is_obj_path(name) {
        bail!("--triangles {n}: `{name}` is an OBJ file; --triangles applies to generators");
    }
    let (gen_name, rest) = name.split_once(':').unwrap_or((name, ""));
    let Some(info) = raybench_scenes::generators()
        .iter()
        .find(|g| g.name.eq_ignore_ascii_case(gen_name.trim()))
    else {
        return Ok(name.to_owned());
    };
    if !info.params.iter().any(|p| p.key == "triangles") {
        let keys: Vec<&str> = info.params.iter().map(|p| p.key).collect();
        bail!(
            "--triangles {n}: generator `{}` has no `triangles` parameter (its parameters: {})",
            info.name,
            if keys.is_empty() {
                "none".to_owned()
            } else {
                keys.join(", ")
            }
        );
    }
    let sets_it = rest.split(',').any(|item| {
        item.split_once('=')
            .is_some_and(|(k, _)| k.trim() == "triangles")
    });
    if sets_it {
        bail!("--triangles {n} and `triangles=` in the spec `{name}`: give one of them");
    }
    Ok(if rest.trim().is_empty() {
        format!("{}:triangles={n}", gen_name.trim())
    } else {
        format!("{name},triangles={n}")
    })
}

/// What [`export`] wrote.
#[derive(Debug)]
pub struct ExportSummary {
    /// The spec that makes this mesh again (with `--triangles` folded in).
    pub spec: String,
    pub vertices: usize,
    pub triangles: usize,
    /// Vertices of the scene's mesh not written (unused by any triangle).
    pub unused_vertices: usize,
    /// True when the file's vertex numbering differs from the scene's (see
    /// [`raybench_scenes::in_file_order`]); triangle order is always kept.
    pub renumbered: bool,
    /// Loader notes and removed-triangle counts of the scene, for the user.
    pub notes: Vec<String>,
}

/// `raybench scene export`: resolves `name` (generator spec or .obj path) with `triangles` and
/// `seed` and writes it to `out` as OBJ, atomically. Nothing is created when anything fails.
pub fn export(name: &str, triangles: Option<u64>, seed: u64, out: &Path) -> Result<ExportSummary> {
    let spec = with_triangles(name, triangles)?;
    let scene = raybench_scenes::resolve(&spec, seed)?;
    let source = serde_json::to_string(&scene.source)?;
    let header = format!(
        "raybench {} scene export\nspec: {spec}\nseed: {seed}\nsource: {source}\nscene: {}",
        env!("CARGO_PKG_VERSION"),
        scene.name
    );
    crate::atomic::write_atomic_with(out, |w| raybench_scenes::write_obj(&scene.mesh, &header, w))?;
    let written = raybench_scenes::in_file_order(&scene.mesh);
    let mut notes = scene.loader_notes.clone();
    let removed = scene.removed;
    if removed.total() > 0 {
        notes.push(format!(
            "{} triangles were removed before export (Embree would ignore them)",
            removed.total()
        ));
    }
    Ok(ExportSummary {
        spec,
        vertices: written.positions().len(),
        triangles: written.len(),
        unused_vertices: scene.mesh.positions().len() - written.positions().len(),
        renumbered: written != *scene.mesh,
        notes,
    })
}

#[derive(Subcommand, Debug)]
pub enum SceneCommand {
    /// Every generator (parameters, named views) and the real OBJ scenes.
    List,
    /// Write a scene as a Wavefront OBJ file (loads back bit for bit).
    Export(ExportArgs),
    /// Render a shaded picture of a scene from its camera (traced with Embree) as a PNG.
    Preview(PreviewArgs),
}

#[derive(Args, Debug)]
pub struct ExportArgs {
    /// A generator spec (teapot, grass:density=500) or an .obj path.
    name: String,
    /// Sets the generator's `triangles` parameter (an error for generators without one).
    #[arg(long)]
    triangles: Option<u64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The OBJ file to write (atomically: a temporary file, then a rename).
    #[arg(long)]
    out: PathBuf,
}

#[derive(Args, Debug)]
pub struct PreviewArgs {
    /// A generator spec (teapot, grass:density=500) or an .obj path.
    name: String,
    /// A named view of the scene (see `raybench scene list`); default: the scene's default.
    #[arg(long)]
    view: Option<String>,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The PNG file to write (atomically: a temporary file, then a rename).
    #[arg(long)]
    out: PathBuf,
}

/// `raybench scene list | export | preview`.
pub fn run(cmd: SceneCommand) -> Result<ExitCode> {
    match cmd {
        SceneCommand::List => list(&mut std::io::stdout().lock())?,
        SceneCommand::Export(a) => {
            let s = export(&a.name, a.triangles, a.seed, &a.out)?;
            for note in &s.notes {
                eprintln!("note: {note}");
            }
            if s.renumbered {
                eprintln!(
                    "note: vertices renumbered in order of first use ({} unused dropped), as \
                     OBJ loaders read them back; triangle order is unchanged",
                    s.unused_vertices
                );
            }
            println!(
                "{}: {} vertices, {} triangles ({}, seed {})",
                a.out.display(),
                s.vertices,
                s.triangles,
                s.spec,
                a.seed
            );
        }
        SceneCommand::Preview(a) => {
            let start = std::time::Instant::now();
            let s = preview(
                &a.name,
                a.view.as_deref(),
                a.width,
                a.height,
                a.seed,
                &a.out,
            )?;
            println!(
                "{}: {}×{} of {} ({} triangles), view `{}`, {:.0} % of pixels hit, {:.2} s",
                a.out.display(),
                a.width,
                a.height,
                s.scene,
                s.triangles,
                s.view,
                s.coverage * 100.0,
                start.elapsed().as_secs_f64()
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
