//! `simulate`: the surface a tool path leaves on a window, a patch or a part map.

use std::path::PathBuf;

use crest::pipeline::ToolSource;
use crest::pipeline::simulate::{FeedSource, GridRequest, Output, SimulateRequest};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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

/// The grid keywords (exactly one grid: `window`, `patch_at` or `patch_near` with
/// `patch_mm`, or `map_mm` with `region`).
const GRID_KEYWORDS: [&str; 6] = [
    "window",
    "patch_at",
    "patch_near",
    "patch_mm",
    "map_mm",
    "region",
];

/// The keywords a function that simulates was given, taken one by one; what is left at the
/// end is an unexpected keyword.
pub(crate) struct Keywords<'py> {
    function: &'static str,
    given: Bound<'py, PyDict>,
}

impl<'py> Keywords<'py> {
    /// The keywords of `function` (a copy: the caller's dict is left alone).
    pub(crate) fn new(
        py: Python<'py>,
        function: &'static str,
        kwargs: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Self> {
        let given = match kwargs {
            Some(d) => d.copy()?,
            None => PyDict::new(py),
        };
        Ok(Keywords { function, given })
    }

    /// Set `key` (a keyword the function itself takes and passes on).
    pub(crate) fn set(&self, key: &str, value: impl IntoPyObject<'py>) -> PyResult<()> {
        self.given.set_item(key, value)
    }

    /// Refuse `keys` (keywords this function does not take).
    pub(crate) fn refuse(&self, keys: &[&str]) -> PyResult<()> {
        for k in keys {
            if self.given.contains(*k)? {
                return Err(self.unexpected(k));
            }
        }
        Ok(())
    }

    fn unexpected(&self, key: &str) -> PyErr {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "{}() got an unexpected keyword argument '{key}'",
            self.function
        ))
    }

    /// Take `key`: `None` when not given or given as `None`.
    pub(crate) fn take<T: for<'a> FromPyObject<'a>>(&self, key: &str) -> PyResult<Option<T>> {
        let Some(v) = self.given.get_item(key)? else {
            return Ok(None);
        };
        self.given.del_item(key)?;
        if v.is_none() {
            return Ok(None);
        }
        v.extract::<T>().map(Some).map_err(|e| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "{}() argument '{key}': {e}",
                self.function
            ))
        })
    }

    /// Every keyword taken: a keyword left over is refused.
    pub(crate) fn finish(self) -> PyResult<()> {
        match self.given.keys().iter().next() {
            Some(k) => Err(self.unexpected(&k.to_string())),
            None => Ok(()),
        }
    }
}

/// The request of `simulate`'s keywords: the one place where Python's keywords become a
/// [`SimulateRequest`] (`simulate`, `map_tasks` and `atlas_tasks` all come here). Each
/// keyword is the request's field name, so library messages (`‹grid_um›`) name it.
/// `model` defaults to `default_model` (as the command's `--model`). With `grid` (a
/// function that places its own grids), the grid keywords are refused.
pub(crate) fn request_of(
    kw: &Keywords<'_>,
    file: PathBuf,
    tool: Option<ToolSource>,
    default_model: &str,
    grid: Option<GridRequest>,
) -> PyResult<SimulateRequest> {
    let bad = |m: &str| crate::crest_error(m);
    let grid = match grid {
        Some(g) => {
            kw.refuse(&GRID_KEYWORDS)?;
            g
        }
        None => crest::pipeline::simulate::GridChoice {
            window: kw.take("window")?,
            patch_at: kw.take("patch_at")?,
            patch_near: kw.take("patch_near")?,
            patch_mm: kw.take("patch_mm")?,
            map_mm: kw.take("map_mm")?,
            region: kw.take("region")?,
        }
        .resolve()
        .map_err(|e| bad(&e.to_string()))?,
    };
    let model = kw.take::<String>("model")?;
    let model = match model.as_deref().unwrap_or(default_model) {
        "ice" => crest::surface::ModelKind::Ice,
        "dome" => crest::surface::ModelKind::Dome,
        "swept" => crest::surface::ModelKind::Swept,
        m => {
            return Err(bad(&format!(
                "model must be 'ice', 'dome' or 'swept', got '{m}'"
            )));
        }
    };
    let feed = match kw.take::<String>("feed")?.as_deref() {
        None => None,
        Some("programmed") => Some(FeedSource::Programmed),
        Some("predicted") => Some(FeedSource::Predicted),
        Some(f) => {
            return Err(bad(&format!(
                "feed must be 'programmed' or 'predicted', got '{f}'"
            )));
        }
    };
    Ok(SimulateRequest {
        file,
        tool,
        teeth: kw.take("teeth")?,
        helix_deg: kw.take("helix_deg")?,
        part: kw.take("part")?,
        absolute: kw.take("absolute")?.unwrap_or(false),
        process: kw.take("process")?,
        rpm: kw.take("rpm")?,
        feed_mm_min: kw.take("feed_mm_min")?,
        fz_mm: kw.take("fz_mm")?,
        feed,
        machine: kw.take("machine")?,
        rtcp: Default::default(),
        model,
        dtheta_deg: kw.take("dtheta_deg")?.unwrap_or(1.0),
        grid_um: kw.take("grid_um")?,
        chord_tol_um: kw.take("chord_tol_um")?,
        band_um: kw.take("band_um")?,
        grid,
        ap_mm: kw.take("ap_mm")?,
        path: kw.take("path")?,
        moves: Default::default(),
    })
}

/// Simulate the surface a tool path leaves (as `crest simulate`): give exactly one of
/// `window=(x0, y0, x1, y1)` (mm, WCS), `patch_at=s_mm` or `patch_near=(x, y, z)` with
/// `patch_mm=(length, width)`, or `map_mm=spacing` (a part map; needs `part`). `tool` is a
/// `Cutter` or the path of a `tool.toml` (default: the file's TLDATA with `teeth`). The other
/// keywords are `crest simulate`'s options (`crest.pyi` lists them). Returns a `HeightMap`
/// (window, patch) or a `PartMap`. The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (file, *, tool = None, **options))]
pub(crate) fn simulate(
    py: Python<'_>,
    file: PathBuf,
    tool: Option<Bound<'_, PyAny>>,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyObject> {
    let kw = Keywords::new(py, "simulate", options)?;
    let req = request_of(&kw, file, tool_source(tool)?, "ice", None)?;
    kw.finish()?;
    let run = py
        .allow_threads(|| crest::pipeline::simulate::simulate(&req, &crest::pipeline::Silent))
        .map_err(err)?;
    match run.output {
        Output::Grid(sim) => Ok(Py::new(py, HeightMap { inner: sim.map })?.into_any()),
        Output::Map(m) => Ok(Py::new(py, part_map(py, &m)?)?.into_any()),
    }
}
