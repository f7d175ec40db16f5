//! `simulate`: the surface a tool path leaves on a window, a patch or a part map.

use std::path::PathBuf;

use crest::pipeline::ToolSource;
use crest::pipeline::simulate::{FeedSource, Output, SimulateRequest};
use pyo3::prelude::*;

use crate::cutter::Cutter;
use crate::err;
use crate::maps::{HeightMap, part_map};

/// Where `tool=` comes from: a `Cutter` carries its tool.toml text (and where it came from);
/// anything else is the path of a tool.toml.
pub(crate) fn tool_source(tool: Option<Bound<'_, PyAny>>) -> PyResult<Option<ToolSource>> {
    let Some(t) = tool else { return Ok(None) };
    Ok(Some(match t.downcast::<Cutter>() {
        Ok(c) => {
            let c = c.get();
            ToolSource::Text {
                name: c.source.clone(),
                text: c.toml.clone(),
            }
        }
        Err(_) => ToolSource::File(t.extract::<PathBuf>().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(
                "tool must be a crest.Cutter or the path of a tool.toml",
            )
        })?),
    }))
}

/// The request of `simulate`'s options (the grid exactly one of window, patch, map).
#[allow(clippy::too_many_arguments)]
pub(crate) fn request_of(
    file: PathBuf,
    tool: Option<ToolSource>,
    window: Option<[f64; 4]>,
    patch_at: Option<f64>,
    patch_near: Option<[f64; 3]>,
    patch_mm: Option<[f64; 2]>,
    map_mm: Option<f64>,
    region: Option<[f64; 6]>,
    part: Option<PathBuf>,
    process: Option<PathBuf>,
    rpm: Option<f64>,
    feed_mm_min: Option<f64>,
    fz_mm: Option<f64>,
    feed: Option<&str>,
    machine: Option<PathBuf>,
    model: &str,
    dtheta_deg: f64,
    grid_um: Option<f64>,
    chord_tol_um: Option<f64>,
    band_um: Option<f64>,
    ap_mm: Option<f64>,
    path: Option<usize>,
    teeth: Option<usize>,
    helix_deg: Option<f64>,
    absolute: bool,
) -> PyResult<SimulateRequest> {
    let bad = |m: &str| crate::crest_error(m);
    let grid = crest::pipeline::simulate::GridChoice {
        window,
        patch_at,
        patch_near,
        patch_mm,
        map_mm,
        region,
    }
    .resolve()
    .map_err(|e| bad(&e.to_string()))?;
    let model = match model {
        "ice" => crest::surface::ModelKind::Ice,
        "dome" => crest::surface::ModelKind::Dome,
        "swept" => crest::surface::ModelKind::Swept,
        m => {
            return Err(bad(&format!(
                "model must be 'ice', 'dome' or 'swept', got '{m}'"
            )));
        }
    };
    let feed = match feed {
        None => None,
        Some("programmed") => Some(FeedSource::Programmed),
        Some("predicted") => Some(FeedSource::Predicted),
        Some(f) => {
            return Err(bad(&format!(
                "feed must be 'programmed' or 'predicted', got '{f}'"
            )));
        }
    };
    let req = SimulateRequest {
        file,
        tool,
        teeth,
        helix_deg,
        part,
        absolute,
        process,
        rpm,
        feed_mm_min,
        fz_mm,
        feed,
        machine,
        rtcp: Default::default(),
        model,
        dtheta_deg,
        grid_um,
        chord_tol_um,
        band_um,
        grid,
        ap_mm,
        path,
        moves: Default::default(),
    };
    Ok(req)
}

/// Simulate the surface a tool path leaves (as `crest simulate`): give exactly one of
/// `window=(x0, y0, x1, y1)` (mm, WCS), `patch_at=s_mm` or `patch_near=(x, y, z)` with
/// `patch_mm=(length, width)`, or `map_mm=spacing` (a part map; needs `part`). `tool` is a
/// `Cutter` or the path of a `tool.toml` (default: the file's TLDATA with `teeth`). Returns
/// a `HeightMap` (window, patch) or a `PartMap`. The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (file, *, tool = None, window = None, patch_at = None, patch_near = None, patch_mm = None, map_mm = None, region = None, part = None, process = None, rpm = None, feed_mm_min = None, fz_mm = None, feed = None, machine = None, model = "ice", dtheta_deg = 1.0, grid_um = None, chord_tol_um = None, band_um = None, ap_mm = None, path = None, teeth = None, helix_deg = None, absolute = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate(
    py: Python<'_>,
    file: PathBuf,
    tool: Option<Bound<'_, PyAny>>,
    window: Option<[f64; 4]>,
    patch_at: Option<f64>,
    patch_near: Option<[f64; 3]>,
    patch_mm: Option<[f64; 2]>,
    map_mm: Option<f64>,
    region: Option<[f64; 6]>,
    part: Option<PathBuf>,
    process: Option<PathBuf>,
    rpm: Option<f64>,
    feed_mm_min: Option<f64>,
    fz_mm: Option<f64>,
    feed: Option<&str>,
    machine: Option<PathBuf>,
    model: &str,
    dtheta_deg: f64,
    grid_um: Option<f64>,
    chord_tol_um: Option<f64>,
    band_um: Option<f64>,
    ap_mm: Option<f64>,
    path: Option<usize>,
    teeth: Option<usize>,
    helix_deg: Option<f64>,
    absolute: bool,
) -> PyResult<PyObject> {
    let req = request_of(
        file,
        tool_source(tool)?,
        window,
        patch_at,
        patch_near,
        patch_mm,
        map_mm,
        region,
        part,
        process,
        rpm,
        feed_mm_min,
        fz_mm,
        feed,
        machine,
        model,
        dtheta_deg,
        grid_um,
        chord_tol_um,
        band_um,
        ap_mm,
        path,
        teeth,
        helix_deg,
        absolute,
    )?;
    let run = py
        .allow_threads(|| crest::pipeline::simulate::simulate(&req, &crest::pipeline::Silent))
        .map_err(err)?;
    match run.output {
        Output::Grid(sim) => Ok(Py::new(py, HeightMap { inner: sim.map })?.into_any()),
        Output::Map(m) => Ok(Py::new(py, part_map(py, &m)?)?.into_any()),
    }
}
