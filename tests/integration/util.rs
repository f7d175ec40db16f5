//! Helpers shared by the areas, written once: the `crest` command, repository and sample
//! paths, temporary folders, JSON and CSV outputs, hand-built postures and straight passes,
//! and the proptest generators of random 5-axis steps.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use crest::math::{Point3, Vec3};
use crest::toolpath::{Contact, MotionKind, Posture};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------
// Paths and commands
// ---------------------------------------------------------------------------------------

/// The repository root.
pub const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// `&'static str` path of a file of the repository, e.g. `repo_file!("samples/x.toml")`
/// (usable in `const` items and `include_str!`).
macro_rules! repo_file {
    ($rel:literal) => {
        concat!(env!("CARGO_MANIFEST_DIR"), "/", $rel)
    };
}

pub(crate) use repo_file;

/// The variable that names the folder of the real NX files (`../shared/samples-external/` in
/// this project's CI). They have no licence to ship, so a clone does not have them.
pub const EXTERNAL_SAMPLES_VAR: &str = "CREST_EXTERNAL_SAMPLES";

/// The folder of the real NX files (`CREST_EXTERNAL_SAMPLES`), or `None`: a test that needs
/// them then returns at once, and `external_samples_not_run` says how many did not run. Each
/// such test asks once, as `let Some(dir) = external_samples() else { return };`, which is
/// the form that count looks for.
pub fn external_samples() -> Option<PathBuf> {
    std::env::var_os(EXTERNAL_SAMPLES_VAR)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
}

/// One line on a run without `CREST_EXTERNAL_SAMPLES`: how many tests returned at once for
/// want of the real NX files, and how to run them. It counts the guards
/// (`external_samples() else`) in the test sources, and writes to stderr directly, which
/// the test harness does not capture.
#[test]
fn external_samples_not_run() {
    if external_samples().is_some() {
        return;
    }
    let dir = repo("tests/integration");
    let mut skipped = 0;
    for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.unwrap_or_else(|e| panic!("{e}")).path();
        if path.extension().is_some_and(|x| x == "rs") && !path.ends_with("util.rs") {
            let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{e}"));
            skipped += text.matches("external_samples() else").count();
        }
    }
    assert!(skipped > 0, "no test reads the real NX files");
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr(),
        "note: {skipped} tests that read the real NX files did not run; to run them, set \
         {EXTERNAL_SAMPLES_VAR} to the folder that holds them (this project's CI: \
         ../shared/samples-external)"
    );
}

/// A file of the repository.
pub fn repo(rel: &str) -> PathBuf {
    Path::new(ROOT).join(rel)
}

/// A file of `samples/synth/` (synthetic paths and their tools).
pub fn synth_sample(name: &str) -> PathBuf {
    repo("samples/synth").join(name)
}

/// A real NX export that ships with the repository (`samples/nx/`, Apache-2.0).
pub fn nx_sample(name: &str) -> PathBuf {
    repo("samples/nx").join(name)
}

/// Every `.cls` file of the folder of real NX files, sorted.
pub fn external_cls_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "cls"))
        .collect();
    v.sort();
    v
}

/// The `crest` binary as an `assert_cmd` command.
pub fn crest() -> assert_cmd::Command {
    assert_cmd::Command::cargo_bin("crest").unwrap_or_else(|e| panic!("{e}"))
}

// ---------------------------------------------------------------------------------------
// Files
// ---------------------------------------------------------------------------------------

/// A fresh temporary folder, removed when dropped.
pub fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"))
}

/// Write `content` to `dir/name` and return the path.
pub fn write(dir: &Path, name: &str, content: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    p
}

/// The text of a file (the path in the panic message).
pub fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

// ---------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------

/// Parse a JSON document (the text in the panic message).
pub fn json(bytes: &[u8]) -> serde_json::Value {
    serde_json::from_slice(bytes)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(bytes)))
}

/// The JSON a finished command printed on stdout.
pub fn stdout_json(a: &assert_cmd::assert::Assert) -> serde_json::Value {
    json(&a.get_output().stdout)
}

/// Run `cmd`, require success, and parse its stdout as JSON.
pub fn success_json(cmd: &mut assert_cmd::Command) -> serde_json::Value {
    stdout_json(&cmd.assert().success())
}

/// The stdout of a successful process as JSON; its stderr in the panic message otherwise.
pub fn output_json(out: &std::process::Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "{:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    json(&out.stdout)
}

/// A CSV output as cells: every line (the header included) split at commas.
pub fn read_csv(path: &Path) -> Vec<Vec<String>> {
    read(path)
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// The columns `crest resample` writes.
pub const RESAMPLE_HEADER: &str =
    "s_mm,t_s,theta_deg,x,y,z,i,j,k,cx,cy,cz,nx,ny,nz,fx,fy,fz,feed_mm_min";

/// Index of column `name` in a CSV `header`.
pub fn column(header: &str, name: &str) -> usize {
    header
        .split(',')
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name} in {header}"))
}

/// A numeric CSV output whose first line is `header`: the rows as numbers, `None` for
/// empty cells.
pub fn read_number_csv(path: &Path, header: &str) -> Vec<Vec<Option<f64>>> {
    let text = read(path);
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(header), "{}", path.display());
    lines
        .map(|l| {
            l.split(',')
                .map(|c| {
                    (!c.is_empty()).then(|| c.parse::<f64>().unwrap_or_else(|e| panic!("{c}: {e}")))
                })
                .collect()
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Tool paths built by hand (the straight passes are in `passes.rs`, which the surface
// benchmark includes too)
// ---------------------------------------------------------------------------------------

mod passes;
pub use passes::{height_stats, pass};

/// A posture without arc, contact data, feed or spindle speed, on line 0; set the rest
/// with struct update syntax.
pub fn posture(position: Point3, axis: Vec3, motion: MotionKind) -> Posture {
    Posture {
        position,
        axis,
        motion,
        arc: None,
        contact: None,
        feed_mm_min: None,
        spindle_rpm: None,
        line: 0,
    }
}

// ---------------------------------------------------------------------------------------
// Random 5-axis paths (proptest)
// ---------------------------------------------------------------------------------------

/// The geometric part of a random posture: displacement from the previous posture, tool
/// axis (polar within 1 rad of +z, azimuth) and surface normal (polar within 45° of +z,
/// azimuth).
pub type StepGeometry = ([f64; 3], [f64; 2], [f64; 2]);

/// Generator of [`StepGeometry`]. Callers nest it in a tuple with their own fields: a
/// tuple generates its members in order, so the values drawn from a seed are those of the
/// flat tuple the resample tests were written with (their regression seeds still apply).
pub fn step_geometry() -> impl Strategy<Value = StepGeometry> {
    (
        [-2.0..2.0f64, -2.0..2.0f64, -0.5..0.5f64],
        [0.0..1.0f64, 0.0..TAU],
        [0.0..0.78f64, 0.0..TAU],
    )
}

/// Unit vector from polar and azimuth angles about +z.
pub fn unit(polar: f64, azimuth: f64) -> Vec3 {
    Vec3::new(
        polar.sin() * azimuth.cos(),
        polar.sin() * azimuth.sin(),
        polar.cos(),
    )
}

/// Contact data of a random posture: a CC point at a fixed offset below the tip.
pub fn contact_below(tip: Point3, normal: Vec3) -> Contact {
    Contact {
        point: tip + Vec3::new(0.3, -0.2, -1.0),
        normal,
        normal_derived: false,
    }
}
