//! Studies, run-out sweeps and part maps as picklable tasks: made, run anywhere, merged into
//! the bytes of the command line.

use std::path::PathBuf;

use crest::pipeline::ToolSource;
use crest::pipeline::simulate::GridRequest;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::maps::part_map;
use crate::simulate::{Keywords, request_of, tool_source};
use crate::{err, json_dumps, json_loads};

/// The tasks of a designed experiment (`crest study` design): `design` is a path to the
/// design TOML, or its text (its `tool` then relative to the working directory). One task
/// per run, each a plain dict (picklable) carrying the design and tool texts; with
/// `monte_carlo` = N also the Monte Carlo settings (N samples of `seed`, as `crest study
/// --monte-carlo N --seed S`).
#[pyfunction]
#[pyo3(signature = (design, *, monte_carlo = None, seed = 1))]
pub(crate) fn study_tasks<'py>(
    py: Python<'py>,
    design: &str,
    monte_carlo: Option<usize>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let texts = if design.contains('\n') || design.contains('=') {
        let d = crest::config::design::parse_design(design, "<design>").map_err(err)?;
        let tool_file = d.tool.display().to_string();
        let tool_toml = crest::io::text::read_text(&d.tool, "tool file", crest::io::input::CONFIG)
            .map_err(err)?;
        crest::pipeline::design::DesignTexts {
            design_file: "<design>".into(),
            design_toml: design.to_string(),
            tool_file,
            tool_toml,
        }
    } else {
        crest::pipeline::design::load_design_texts(std::path::Path::new(design)).map_err(err)?
    };
    let mc = crest::pipeline::tasks::MonteCarlo::of(monte_carlo.map(|n| (n, seed)));
    let tasks = crest::pipeline::tasks::design_tasks_with(&texts, mc).map_err(err)?;
    let text = serde_json::to_string(&tasks).map_err(|e| crate::crest_error(e.to_string()))?;
    json_loads(py, &text)
}

/// The tile tasks of a part map (`simulate(..., map_mm=...)` with the same keywords):
/// `tasks` plain dicts (picklable), task k simulating cells k, k+tasks, … of the map. The
/// file paths are made absolute; every worker must see the files there.
#[pyfunction]
#[pyo3(signature = (file, *, tasks, map_mm, part, tool = None, **options))]
pub(crate) fn map_tasks<'py>(
    py: Python<'py>,
    file: PathBuf,
    tasks: usize,
    map_mm: f64,
    part: PathBuf,
    tool: Option<Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let kw = Keywords::new(py, "map_tasks", options)?;
    kw.set("map_mm", map_mm)?;
    kw.set("part", part)?;
    let mut req = request_of(
        &kw,
        absolute(file),
        absolute_tool(tool_source(tool)?),
        "ice",
        None,
    )?;
    kw.finish()?;
    req.part = req.part.map(absolute);
    req.process = req.process.map(absolute);
    req.machine = req.machine.map(absolute);
    let tasks = crest::pipeline::tasks::map::map_tasks(&req, tasks).map_err(err)?;
    let text = serde_json::to_string(&tasks).map_err(|e| crate::crest_error(e.to_string()))?;
    json_loads(py, &text)
}

/// A path made absolute (tasks run in other processes, maybe elsewhere).
fn absolute(p: PathBuf) -> PathBuf {
    std::path::absolute(&p).unwrap_or(p)
}

/// A tool file made absolute (tasks run in other processes, maybe elsewhere).
fn absolute_tool(tool: Option<ToolSource>) -> Option<ToolSource> {
    tool.map(|t| match t {
        ToolSource::File(p) => ToolSource::File(absolute(p)),
        text => text,
    })
}

/// The patch tasks of a roughness atlas (`crest atlas`, the same options): `tasks` plain
/// dicts (picklable), task k simulating patches k, k+tasks, … of the atlas (a patch every
/// `every_mm` over every finishing region; `patch_mm` = (L, W), default twice the local
/// stepover); the other keywords are `simulate`'s, but for the grid (the atlas places its
/// patches), `feed` and `machine`. The file paths are made absolute; every worker must see
/// the files there.
#[pyfunction]
#[pyo3(signature = (file, *, tasks, every_mm, patch_mm = None, tool = None, **options))]
pub(crate) fn atlas_tasks<'py>(
    py: Python<'py>,
    file: PathBuf,
    tasks: usize,
    every_mm: f64,
    patch_mm: Option<[f64; 2]>,
    tool: Option<Bound<'py, PyAny>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let kw = Keywords::new(py, "atlas_tasks", options)?;
    kw.refuse(&["feed", "machine"])?;
    // The grid of the shared request: a placeholder each patch replaces.
    let grid = GridRequest::PatchNear {
        point: [0.0; 3],
        length_mm: 1.0,
        width_mm: 1.0,
    };
    let tool = absolute_tool(tool_source(tool)?);
    let mut simulate = request_of(&kw, absolute(file), tool, "dome", Some(grid))?;
    kw.finish()?;
    simulate.part = simulate.part.map(absolute);
    simulate.process = simulate.process.map(absolute);
    let req = crest::pipeline::atlas::AtlasRequest {
        simulate,
        every_mm,
        patch_mm: patch_mm.map(|p| (p[0], p[1])),
    };
    let tasks = crest::pipeline::tasks::atlas::atlas_tasks(&req, tasks).map_err(err)?;
    let text = serde_json::to_string(&tasks).map_err(|e| crate::crest_error(e.to_string()))?;
    json_loads(py, &text)
}

/// The tasks of a run-out sweep (`crest runout` study): `study` is a path to the study TOML,
/// or its text (its `tool` then relative to the working directory). With `tasks`, that many
/// tasks (task k: cases k-1, k-1+tasks, … of the sweep, 0-based); by default one task per
/// case. Each a plain dict (picklable) carrying the study and tool texts.
#[pyfunction]
#[pyo3(signature = (study, *, tasks = None))]
pub(crate) fn runout_tasks<'py>(
    py: Python<'py>,
    study: &str,
    tasks: Option<usize>,
) -> PyResult<Bound<'py, PyAny>> {
    let texts = if study.contains('\n') || study.contains('=') {
        crest::pipeline::runout::runout_texts(
            "<study>",
            study.to_string(),
            std::path::Path::new(""),
        )
    } else {
        crest::pipeline::runout::load_runout_texts(std::path::Path::new(study))
    }
    .map_err(err)?;
    let tasks = crest::pipeline::tasks::runout::runout_tasks(&texts, tasks).map_err(err)?;
    let text = serde_json::to_string(&tasks).map_err(|e| crate::crest_error(e.to_string()))?;
    json_loads(py, &text)
}

/// Run one task of `study_tasks`, `runout_tasks`, `map_tasks` or `atlas_tasks` (a dict, or its JSON text);
/// returns the result as a dict (picklable). A study run that fails comes back with its
/// `error`. Releases the GIL.
#[pyfunction]
pub(crate) fn run_task<'py>(
    py: Python<'py>,
    task: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let text = json_dumps(task)?;
    let task: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| crate::crest_error(format!("not a crest task: {e}")))?;
    let result = py
        .allow_threads(|| crest::pipeline::tasks::run_any(task))
        .map_err(err)?;
    json_loads(py, &result.to_string())
}

/// Assemble the results of every task of one design (any order) as `crest study` does:
/// a dict with `title`, `runs` and `effects` (the objects of `crest study --json`) and
/// `files` (name → bytes of runs.csv, effects.csv and the SVG charts, the bytes `crest
/// study` writes). With `output`, the files are also written into that folder. Fails like
/// `crest study` when a run failed, and when runs are missing, repeated or of another design.
/// The results of every task of one part map (`map_tasks`) give the `PartMap` `simulate`
/// gives; with `output` (a .ply path) its PLY is written, the bytes of `crest simulate`.
/// The results of every task of one run-out sweep (`runout_tasks`) give a dict with `rule`,
/// `x`, `tool`, `rows` (as `crest runout --json`) and `files` (runout.csv and the charts,
/// the bytes `crest runout` writes); with `output` they are written into that folder.
/// The results of every task of one atlas (`atlas_tasks`) give a dict with `rows`,
/// `regions` and `files` (atlas.csv, the bytes `crest atlas` writes); with `output` (.csv
/// or .ply) the table or point cloud is written.
#[pyfunction]
#[pyo3(signature = (results, output = None))]
pub(crate) fn merge<'py>(
    py: Python<'py>,
    results: &Bound<'py, PyAny>,
    output: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    use crest::pipeline::tasks::Merged;
    let mut parsed = Vec::new();
    for (i, r) in results.try_iter()?.enumerate() {
        let text = json_dumps(&r?)?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| crate::crest_error(format!("not a crest task result: {e}")))?;
        parsed.push((format!("result {}", i + 1), v));
    }
    let merged = py
        .allow_threads(|| -> miette::Result<_> {
            match crest::pipeline::tasks::merge_any(parsed)? {
                Merged::Design(done) => {
                    let files = crest::pipeline::design::render_outputs(&done)?;
                    if let Some(dir) = &output {
                        crest::io::write_files(dir, &files).map_err(|e| {
                            miette::miette!("cannot write into {}: {e}", dir.display())
                        })?;
                    }
                    Ok((Merged::Design(done), files))
                }
                Merged::Map(m) => {
                    if let Some(path) = &output {
                        crest::io::write_atomic(path, |w| {
                            crest::io::mesh::write_map_ply(&m.points, w)
                        })
                        .map_err(|e| miette::miette!("cannot write {}: {e}", path.display()))?;
                    }
                    Ok((Merged::Map(m), Vec::new()))
                }
                Merged::Atlas(a) => {
                    let mut csv = Vec::new();
                    crest::io::atlas::write_atlas_csv(&a.rows, &mut csv)
                        .map_err(|e| miette::miette!("cannot write the atlas: {e}"))?;
                    if let Some(path) = &output {
                        let ply = path
                            .extension()
                            .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
                        crest::io::write_atomic(path, |w| {
                            if ply {
                                crest::io::atlas::write_atlas_ply(&a.rows, w)
                            } else {
                                w.write_all(&csv)
                            }
                        })
                        .map_err(|e| miette::miette!("cannot write {}: {e}", path.display()))?;
                    }
                    Ok((Merged::Atlas(a), vec![("atlas.csv".to_string(), csv)]))
                }
                Merged::Runout(run) => {
                    let files = crest::pipeline::runout::render_outputs(&run)?;
                    if let Some(dir) = &output {
                        crest::io::write_files(dir, &files).map_err(|e| {
                            miette::miette!("cannot write into {}: {e}", dir.display())
                        })?;
                    }
                    Ok((Merged::Runout(run), files))
                }
            }
        })
        .map_err(err)?;
    let (done, files) = match merged {
        (Merged::Map(m), _) => {
            return Ok(Py::new(py, part_map(py, &m)?)?.into_bound(py).into_any());
        }
        (Merged::Runout(run), files) => return runout_dict(py, &run, &files),
        (Merged::Atlas(a), files) => {
            let d = PyDict::new(py);
            let rows =
                serde_json::to_string(&a.rows).map_err(|e| crate::crest_error(e.to_string()))?;
            d.set_item("rows", json_loads(py, &rows)?)?;
            d.set_item("regions", a.regions)?;
            let f = PyDict::new(py);
            for (name, bytes) in &files {
                f.set_item(name, pyo3::types::PyBytes::new(py, bytes))?;
            }
            d.set_item("files", f)?;
            return Ok(d.into_any());
        }
        (Merged::Design(done), files) => (done, files),
    };
    let d = PyDict::new(py);
    d.set_item("title", &done.design.title)?;
    let runs: Vec<serde_json::Value> = done
        .results
        .iter()
        .map(|r| crest::pipeline::design::run_json(&done.design, r))
        .collect();
    let effects = crest::pipeline::design::effects_json(&done.design, &done.effects);
    d.set_item(
        "runs",
        json_loads(py, &serde_json::Value::from(runs).to_string())?,
    )?;
    d.set_item(
        "effects",
        json_loads(py, &serde_json::Value::from(effects).to_string())?,
    )?;
    let f = PyDict::new(py);
    for (name, bytes) in &files {
        f.set_item(name, pyo3::types::PyBytes::new(py, bytes))?;
    }
    d.set_item("files", f)?;
    Ok(d.into_any())
}

/// A merged run-out study as `merge` returns it: `rule`, `x`, `tool`, `rows` (the objects of
/// `crest runout --json`) and `files` (name → bytes).
pub(crate) fn runout_dict<'py>(
    py: Python<'py>,
    run: &crest::pipeline::runout::RunoutRun,
    files: &[(String, Vec<u8>)],
) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("rule", run.study.rule.name())?;
    d.set_item("x", run.study.x.key())?;
    d.set_item("tool", run.tool_path.display().to_string())?;
    let rows = serde_json::to_string(&run.rows).map_err(|e| crate::crest_error(e.to_string()))?;
    d.set_item("rows", json_loads(py, &rows)?)?;
    let f = PyDict::new(py);
    for (name, bytes) in files {
        f.set_item(name, pyo3::types::PyBytes::new(py, bytes))?;
    }
    d.set_item("files", f)?;
    Ok(d.into_any())
}
