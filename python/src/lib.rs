//! The Python module `crest`: tool paths as numpy arrays, cutters, simulated height maps,
//! metrics and designed experiments as picklable tasks, all through the library's
//! `crest::pipeline` (no subprocess). Long computations release the GIL.

use std::path::PathBuf;

use crest::pipeline::ToolSource;
use crest::pipeline::simulate::{FeedSource, GridRequest, Output, SimulateRequest};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::create_exception;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

create_exception!(
    crest,
    CrestError,
    pyo3::exceptions::PyException,
    "An error of crest: bad input (naming file, line and column) or a failed computation. \
     The message is the command line's."
);

/// A crest error as a Python exception: the message and its causes, one per line, as the
/// command line prints them (without the code frame).
fn err(e: miette::Report) -> PyErr {
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        msg.push_str("\n  caused by: ");
        msg.push_str(&cause.to_string());
    }
    CrestError::new_err(msg)
}

fn json_loads<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (text,))
}

fn json_dumps(obj: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = obj.extract::<String>() {
        return Ok(s);
    }
    obj.py()
        .import("json")?
        .call_method1("dumps", (obj,))?
        .extract()
}

// ------------------------------------------------------------------------------------------
// Tool paths
// ------------------------------------------------------------------------------------------

/// Read a tool-path file (NX CLSF, other APT, contact12 CSV; chosen by content) into one
/// dict per tool path: `name`, `tool_name`, and per posture `tip` (N×3, mm), `axis` (N×3,
/// unit), `motion` (list of "from", "rapid", "cut", "cycle", "gohome"), `feed_mm_min` and
/// `spindle_rpm` (N, NaN before the first FEDRAT/SPINDL), `line` (N, source line),
/// `contact` and `normal` (N×3, NaN where the file has no contact data).
#[pyfunction]
#[pyo3(signature = (file, *, absolute = false))]
fn read_path<'py>(py: Python<'py>, file: PathBuf, absolute: bool) -> PyResult<Bound<'py, PyList>> {
    let opts = crest::toolpath::LowerOptions {
        apply_msys: absolute,
        ..Default::default()
    };
    let program = py
        .allow_threads(|| crest::io::toolpath::read_program_with(&file, opts))
        .map_err(err)?;
    let out = PyList::empty(py);
    for p in &program.paths {
        let n = p.postures.len();
        let mut tip = Array2::<f64>::zeros((n, 3));
        let mut axis = Array2::<f64>::zeros((n, 3));
        let mut contact = Array2::<f64>::from_elem((n, 3), f64::NAN);
        let mut normal = Array2::<f64>::from_elem((n, 3), f64::NAN);
        let mut feed = Array1::<f64>::from_elem(n, f64::NAN);
        let mut rpm = Array1::<f64>::from_elem(n, f64::NAN);
        let mut line = Array1::<u32>::zeros(n);
        let mut motion = Vec::with_capacity(n);
        for (i, q) in p.postures.iter().enumerate() {
            for k in 0..3 {
                tip[[i, k]] = q.position[k];
                axis[[i, k]] = q.axis[k];
            }
            if let Some(c) = &q.contact {
                for k in 0..3 {
                    contact[[i, k]] = c.point[k];
                    normal[[i, k]] = c.normal[k];
                }
            }
            feed[i] = q.feed_mm_min.unwrap_or(f64::NAN);
            rpm[i] = q.spindle_rpm.unwrap_or(f64::NAN);
            line[i] = q.line;
            motion.push(
                match q.motion {
                    crest::toolpath::MotionKind::From => "from",
                    crest::toolpath::MotionKind::Rapid => "rapid",
                    crest::toolpath::MotionKind::Cut => "cut",
                    crest::toolpath::MotionKind::Cycle => "cycle",
                    crest::toolpath::MotionKind::GoHome => "gohome",
                }
                .to_string(),
            );
        }
        let d = PyDict::new(py);
        d.set_item("name", &p.name)?;
        d.set_item("tool_name", &p.tool_name)?;
        d.set_item("tip", tip.into_pyarray(py))?;
        d.set_item("axis", axis.into_pyarray(py))?;
        d.set_item("motion", motion)?;
        d.set_item("feed_mm_min", feed.into_pyarray(py))?;
        d.set_item("spindle_rpm", rpm.into_pyarray(py))?;
        d.set_item("line", line.into_pyarray(py))?;
        d.set_item("contact", contact.into_pyarray(py))?;
        d.set_item("normal", normal.into_pyarray(py))?;
        out.append(d)?;
    }
    Ok(out)
}

// ------------------------------------------------------------------------------------------
// Cutters
// ------------------------------------------------------------------------------------------

/// A cutter, as `crest` reads it from a `tool.toml`.
///
/// `Cutter.from_toml(path)` reads a file; `Cutter(shape="ball", radius_mm=5.0, teeth=2,
/// helix_deg=0.0, **more)` writes the same keys as a `tool.toml` (any key of the file,
/// e.g. `corner_radius_mm` for a torus) and checks them with the same rules and messages.
#[pyclass(module = "crest", frozen)]
#[derive(Clone)]
struct Cutter {
    /// The tool.toml text the cutter was read from.
    #[pyo3(get)]
    toml: String,
    /// Where it came from (a path, or "<keyword arguments>").
    #[pyo3(get)]
    source: String,
    inner: crest::tool::Cutter,
}

fn toml_value(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Ok(if v.extract::<bool>()? {
            "true"
        } else {
            "false"
        }
        .into());
    }
    if let Ok(i) = v.extract::<i64>() {
        return Ok(i.to_string());
    }
    if let Ok(f) = v.extract::<f64>() {
        return Ok(format!("{f:?}"));
    }
    if let Ok(s) = v.extract::<String>() {
        return Ok(format!("{s:?}"));
    }
    if let Ok(items) = v.extract::<Vec<Bound<'_, PyAny>>>() {
        let parts: PyResult<Vec<String>> = items.iter().map(toml_value).collect();
        return Ok(format!("[{}]", parts?.join(", ")));
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "cannot write {} as a tool.toml value",
        v.repr()?
    )))
}

#[pymethods]
impl Cutter {
    #[new]
    #[pyo3(signature = (**kwargs))]
    fn new(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Cutter> {
        let mut top = String::new();
        let mut tables = String::new();
        if let Some(kw) = kwargs {
            for (k, v) in kw.iter() {
                let key: String = k.extract()?;
                if let Ok(table) = v.downcast::<PyDict>() {
                    tables.push_str(&format!("\n[{key}]\n"));
                    for (tk, tv) in table.iter() {
                        let tk: String = tk.extract()?;
                        tables.push_str(&format!("{tk} = {}\n", toml_value(&tv)?));
                    }
                } else {
                    top.push_str(&format!("{key} = {}\n", toml_value(&v)?));
                }
            }
        }
        Cutter::from_text(&(top + &tables), "<keyword arguments>")
    }

    /// Read a `tool.toml`.
    #[staticmethod]
    fn from_toml(path: PathBuf) -> PyResult<Cutter> {
        let text = crest::io::text::read_text(&path, "tool file").map_err(|e| err(e.into()))?;
        Cutter::from_text(&text, &path.display().to_string())
    }

    /// Read `tool.toml` text (`file` names it in messages).
    #[staticmethod]
    #[pyo3(name = "from_text", signature = (text, file = "<text>"))]
    fn py_from_text(text: &str, file: &str) -> PyResult<Cutter> {
        Cutter::from_text(text, file)
    }

    /// Nominal radius, mm.
    #[getter]
    fn radius_mm(&self) -> f64 {
        self.inner.radius_mm
    }

    /// Number of teeth.
    #[getter]
    fn teeth(&self) -> usize {
        self.inner.teeth()
    }

    /// The tool analysis of `crest tool --json` at one engagement: effective radius, crest
    /// height, participating teeth (`rule` "exact" or "paper"), as a dict with the same keys
    /// and values.
    #[pyo3(signature = (lead_deg, ap_mm, fz_mm, rule = "exact"))]
    fn analyse<'py>(
        &self,
        py: Python<'py>,
        lead_deg: f64,
        ap_mm: f64,
        fz_mm: f64,
        rule: &str,
    ) -> PyResult<Bound<'py, PyAny>> {
        let rule = match rule {
            "exact" => crest::tool::Rule::Exact,
            "paper" => crest::tool::Rule::Paper,
            r => {
                return Err(CrestError::new_err(format!(
                    "rule must be 'exact' or 'paper', got '{r}'"
                )));
            }
        };
        let a = crest::tool::analyse(&self.inner, lead_deg, ap_mm, fz_mm, rule)
            .map_err(|e| CrestError::new_err(e.to_string()))?;
        let v = crest::pipeline::tool::analysis_json(
            &self.inner,
            &self.source,
            (lead_deg, ap_mm, fz_mm),
            rule,
            &a,
        );
        json_loads(py, &v.to_string())
    }

    fn __repr__(&self) -> String {
        format!(
            "Cutter(source={:?}, radius_mm={}, teeth={})",
            self.source,
            self.inner.radius_mm,
            self.inner.teeth()
        )
    }
}

impl Cutter {
    fn from_text(text: &str, file: &str) -> PyResult<Cutter> {
        let inner = crest::pipeline::tool_from_text(text, file).map_err(err)?;
        Ok(Cutter {
            toml: text.to_string(),
            source: file.to_string(),
            inner,
        })
    }
}

// ------------------------------------------------------------------------------------------
// Height maps
// ------------------------------------------------------------------------------------------

/// A height map: heights in µm on a regular grid (`z_um[row, col]`, rows along y
/// ascending, NaN = not reached), spacing `dx_um`, `dy_um`, origin (`x0_mm`, `y0_mm`) of
/// node (0, 0) in the grid's frame.
#[pyclass(module = "crest")]
#[derive(Clone)]
struct HeightMap {
    inner: crest::surface::HeightMap,
}

#[pymethods]
impl HeightMap {
    /// A height map from a 2-D array of heights in µm (rows along y).
    #[new]
    #[pyo3(signature = (z_um, dx_um, dy_um = None, x0_mm = 0.0, y0_mm = 0.0))]
    fn new(
        z_um: PyReadonlyArray2<'_, f64>,
        dx_um: f64,
        dy_um: Option<f64>,
        x0_mm: f64,
        y0_mm: f64,
    ) -> HeightMap {
        let a = z_um.as_array();
        let (ny, nx) = a.dim();
        HeightMap {
            inner: crest::surface::HeightMap {
                nx,
                ny,
                dx_um,
                dy_um: dy_um.unwrap_or(dx_um),
                x0_mm,
                y0_mm,
                z_um: a.iter().copied().collect(),
            },
        }
    }

    /// Read a height map (.csv, .xyz/.txt, .gsf, .sdf).
    #[staticmethod]
    #[pyo3(signature = (path, dx_um = None, dy_um = None))]
    fn read(path: PathBuf, dx_um: Option<f64>, dy_um: Option<f64>) -> PyResult<HeightMap> {
        let opts = crest::io::ReadOptions { dx_um, dy_um };
        crest::io::read_heightmap(&path, &opts)
            .map(|inner| HeightMap { inner })
            .map_err(|e| CrestError::new_err(e.to_string()))
    }

    /// Heights, µm: a (ny, nx) float64 array (a copy).
    #[getter]
    fn z_um<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let m = &self.inner;
        Array2::from_shape_vec((m.ny, m.nx), m.z_um.clone())
            .map(|a| a.into_pyarray(py))
            .map_err(|e| CrestError::new_err(e.to_string()))
    }

    /// Columns.
    #[getter]
    fn nx(&self) -> usize {
        self.inner.nx
    }

    /// Rows.
    #[getter]
    fn ny(&self) -> usize {
        self.inner.ny
    }

    /// Spacing along x, µm.
    #[getter]
    fn dx_um(&self) -> f64 {
        self.inner.dx_um
    }

    /// Spacing along y, µm.
    #[getter]
    fn dy_um(&self) -> f64 {
        self.inner.dy_um
    }

    /// (x0_mm, y0_mm): node (0, 0) in the grid's frame, mm.
    #[getter]
    fn origin_mm(&self) -> (f64, f64) {
        (self.inner.x0_mm, self.inner.y0_mm)
    }

    /// x of each column, mm.
    #[getter]
    fn x_mm<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        let m = &self.inner;
        Array1::from_iter((0..m.nx).map(|i| m.x0_mm + i as f64 * m.dx_um * 1e-3)).into_pyarray(py)
    }

    /// y of each row, mm.
    #[getter]
    fn y_mm<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        let m = &self.inner;
        Array1::from_iter((0..m.ny).map(|j| m.y0_mm + j as f64 * m.dy_um * 1e-3)).into_pyarray(py)
    }

    /// Write as Gwyddion Simple Field (.gsf).
    fn to_gsf(&self, path: PathBuf) -> PyResult<()> {
        self.write(path, crest::io::HeightMapFormat::Gsf)
    }

    /// Write as ISO 25178-71 SDF (.sdf).
    fn to_sdf(&self, path: PathBuf) -> PyResult<()> {
        self.write(path, crest::io::HeightMapFormat::Sdf)
    }

    /// Write as grid CSV (.csv: one line per row, µm).
    fn to_csv(&self, path: PathBuf) -> PyResult<()> {
        self.write(path, crest::io::HeightMapFormat::Csv)
    }

    /// Profile or ISO 25178 areal parameters (see `crest.metrics`).
    #[pyo3(signature = (params = None, *, level = "none", lambda_s_um = None, lambda_c_um = None, ends = "reflect", profile = None, sections = 5))]
    #[allow(clippy::too_many_arguments)]
    fn metrics<'py>(
        &self,
        py: Python<'py>,
        params: Option<String>,
        level: &str,
        lambda_s_um: Option<f64>,
        lambda_c_um: Option<f64>,
        ends: &str,
        profile: Option<String>,
        sections: usize,
    ) -> PyResult<Bound<'py, PyDict>> {
        metrics_of(
            py,
            &self.inner,
            "height map",
            params,
            level,
            lambda_s_um,
            lambda_c_um,
            ends,
            profile,
            sections,
        )
    }

    /// Pickling: the constructor and its arguments (the heights as a numpy array, which
    /// pickles its float64 values bit for bit).
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, pyo3::types::PyTuple>)> {
        let py = slf.py();
        let this = slf.borrow();
        let m = &this.inner;
        let z = this.z_um(py)?;
        let args = (z, m.dx_um, m.dy_um, m.x0_mm, m.y0_mm).into_pyobject(py)?;
        Ok((py.get_type::<HeightMap>().into_any(), args))
    }

    fn __repr__(&self) -> String {
        let m = &self.inner;
        format!(
            "HeightMap(nx={}, ny={}, dx_um={}, dy_um={}, origin_mm=({}, {}))",
            m.nx, m.ny, m.dx_um, m.dy_um, m.x0_mm, m.y0_mm
        )
    }
}

impl HeightMap {
    fn write(&self, path: PathBuf, format: crest::io::HeightMapFormat) -> PyResult<()> {
        let map = &self.inner;
        crest::io::write_atomic(&path, |w| crest::io::write_heightmap_to(w, format, map))
            .map_err(|e| CrestError::new_err(format!("cannot write {}: {e}", path.display())))
    }
}

/// A simulated part map: points on the design surface (N×3, mm), their normals (N×3) and
/// heights along the normals (N, µm; NaN = not reached).
#[pyclass(module = "crest", get_all)]
struct PartMap {
    points: Py<numpy::PyArray2<f64>>,
    normals: Py<numpy::PyArray2<f64>>,
    height_um: Py<numpy::PyArray1<f64>>,
    nodes_cut: usize,
}

#[pymethods]
impl PartMap {
    /// A part map from its arrays: points (N×3, mm), normals (N×3), heights (N, µm).
    #[new]
    #[pyo3(signature = (points, normals, height_um, nodes_cut = 0))]
    fn new(
        points: Bound<'_, numpy::PyArray2<f64>>,
        normals: Bound<'_, numpy::PyArray2<f64>>,
        height_um: Bound<'_, numpy::PyArray1<f64>>,
        nodes_cut: usize,
    ) -> PyResult<PartMap> {
        use numpy::PyUntypedArrayMethods;
        let n = height_um.len();
        for (name, a) in [("points", &points), ("normals", &normals)] {
            if a.shape() != [n, 3] {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "{name} must have shape ({n}, 3) to match height_um, got {:?}",
                    a.shape()
                )));
            }
        }
        Ok(PartMap {
            points: points.unbind(),
            normals: normals.unbind(),
            height_um: height_um.unbind(),
            nodes_cut,
        })
    }

    /// Pickling: the constructor and its arrays.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, pyo3::types::PyTuple>)> {
        let py = slf.py();
        let this = slf.borrow();
        let args = (
            this.points.bind(py).clone(),
            this.normals.bind(py).clone(),
            this.height_um.bind(py).clone(),
            this.nodes_cut,
        )
            .into_pyobject(py)?;
        Ok((py.get_type::<PartMap>().into_any(), args))
    }
}

// ------------------------------------------------------------------------------------------
// Metrics
// ------------------------------------------------------------------------------------------

#[allow(clippy::too_many_arguments)]
fn metrics_of<'py>(
    py: Python<'py>,
    map: &crest::surface::HeightMap,
    file: &str,
    params: Option<String>,
    level: &str,
    lambda_s_um: Option<f64>,
    lambda_c_um: Option<f64>,
    ends: &str,
    profile: Option<String>,
    sections: usize,
) -> PyResult<Bound<'py, PyDict>> {
    use crest::metrics::{
        EndEffects, Level, ParamSet, Preprocess, ProfileSpec, areal_parameters, extract_profile,
        preprocess_map, preprocess_profile, profile_parameters,
    };
    let bad = |e: String| CrestError::new_err(e);
    let pp = Preprocess {
        level: Level::parse(level).map_err(bad)?,
        lambda_s_um,
        lambda_c_um,
        ends: match ends {
            "reflect" => EndEffects::Reflect,
            "trim" => EndEffects::Trim,
            other => {
                return Err(bad(format!(
                    "ends must be 'reflect' or 'trim', got '{other}'"
                )));
            }
        },
    };
    let spec = profile
        .as_deref()
        .map(ProfileSpec::parse)
        .transpose()
        .map_err(bad)?;
    let set = match &params {
        Some(list) => ParamSet::parse(list, spec.is_some()),
        None => Ok(ParamSet::all(spec.is_some())),
    }
    .map_err(|e| bad(e.to_string()))?;
    if set.params().is_empty() {
        return Err(bad("params lists no parameter".into()));
    }
    let filtered = pp.lambda_s_um.is_some() || pp.lambda_c_um.is_some();
    let values = py
        .allow_threads(|| -> Result<_, String> {
            if let Some(spec) = spec {
                let raw = extract_profile(map, spec).map_err(|e| format!("{file}: {e}"))?;
                let prof = preprocess_profile(&raw, &pp).map_err(|e| format!("{file}: {e}"))?;
                profile_parameters(&prof, &set, sections).map_err(|e| format!("{file}: {e}"))
            } else if pp.level.degree() == 0 && !filtered {
                areal_parameters(map, &set).map_err(|e| format!("{file}: {e}"))
            } else {
                let m = preprocess_map(map, &pp).map_err(|e| format!("{file}: {e}"))?;
                areal_parameters(&m, &set).map_err(|e| format!("{file}: {e}"))
            }
        })
        .map_err(bad)?;
    let d = PyDict::new(py);
    for (p, v) in &values {
        d.set_item(p.symbol(), *v)?;
    }
    Ok(d)
}

/// Profile or ISO 25178 areal parameters of a height map (a `HeightMap` or a file), as a
/// dict symbol → value (µm, degrees, %, as `crest metrics`; NaN where undefined).
/// `params` is a comma-separated list (default: all); `level` "none", "plane" or "poly:N";
/// `profile` "row:K", "col:K" or "angle:DEG" for profile parameters.
#[pyfunction]
#[pyo3(signature = (map, params = None, *, level = "none", lambda_s_um = None, lambda_c_um = None, ends = "reflect", profile = None, sections = 5, dx_um = None, dy_um = None))]
#[allow(clippy::too_many_arguments)]
fn metrics<'py>(
    py: Python<'py>,
    map: &Bound<'py, PyAny>,
    params: Option<String>,
    level: &str,
    lambda_s_um: Option<f64>,
    lambda_c_um: Option<f64>,
    ends: &str,
    profile: Option<String>,
    sections: usize,
    dx_um: Option<f64>,
    dy_um: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (inner, file) = if let Ok(h) = map.downcast::<HeightMap>() {
        (h.borrow().inner.clone(), "height map".to_string())
    } else {
        let path: PathBuf = map.extract()?;
        let h = HeightMap::read(path.clone(), dx_um, dy_um)?;
        (h.inner, path.display().to_string())
    };
    metrics_of(
        py,
        &inner,
        &file,
        params,
        level,
        lambda_s_um,
        lambda_c_um,
        ends,
        profile,
        sections,
    )
}

// ------------------------------------------------------------------------------------------
// Simulation
// ------------------------------------------------------------------------------------------

/// Where `tool=` comes from: a `Cutter` carries its tool.toml text (and where it came from);
/// anything else is the path of a tool.toml.
fn tool_source(tool: Option<Bound<'_, PyAny>>) -> PyResult<Option<ToolSource>> {
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
fn request_of(
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
    let bad = |m: &str| CrestError::new_err(m.to_string());
    let given = [
        window.is_some(),
        patch_at.is_some(),
        patch_near.is_some(),
        map_mm.is_some(),
    ]
    .iter()
    .filter(|b| **b)
    .count();
    if given != 1 {
        return Err(bad(
            "give exactly one of window=(X0,Y0,X1,Y1), patch_at=S_MM or patch_near=(X,Y,Z) with patch_mm=(L,W), or map_mm=SPACING",
        ));
    }
    let grid = if let Some([x0_mm, y0_mm, x1_mm, y1_mm]) = window {
        GridRequest::Window {
            x0_mm,
            y0_mm,
            x1_mm,
            y1_mm,
        }
    } else if let Some(spacing_mm) = map_mm {
        GridRequest::Map { spacing_mm, region }
    } else {
        let [length_mm, width_mm] =
            patch_mm.ok_or_else(|| bad("a patch needs patch_mm=(LENGTH, WIDTH)"))?;
        match (patch_near, patch_at) {
            (Some(point), _) => GridRequest::PatchNear {
                point,
                length_mm,
                width_mm,
            },
            (None, Some(s_mm)) => GridRequest::PatchAt {
                s_mm,
                length_mm,
                width_mm,
            },
            (None, None) => unreachable!("one grid was given"),
        }
    };
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
fn simulate(
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

// ------------------------------------------------------------------------------------------
// Resampling
// ------------------------------------------------------------------------------------------

/// Resample the cutting moves of a tool-path file (as `crest resample`, programmed feed):
/// `mode` "fz" (even feed per tooth) or "dtheta" (constant spindle step `dtheta_deg`).
/// Returns a dict of numpy arrays, one entry per sample, with the columns of `crest
/// resample`'s CSV (`s_mm`, `t_s`, `theta_deg`, `x`, `y`, `z`, `i`, `j`, `k`, `cx`, `cy`,
/// `cz`, `nx`, `ny`, `nz` (NaN without contact data), `fx`, `fy`, `fz`, `feed_mm_min`) and
/// `path` (0-based tool path index), at full precision. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (file, *, mode, fz_mm, teeth, dtheta_deg = 0.5, rpm = None, feed_mm_min = None, axis = "slerp", spline = false, path = None))]
#[allow(clippy::too_many_arguments)]
fn resample<'py>(
    py: Python<'py>,
    file: PathBuf,
    mode: &str,
    fz_mm: f64,
    teeth: usize,
    dtheta_deg: f64,
    rpm: Option<f64>,
    feed_mm_min: Option<f64>,
    axis: &str,
    spline: bool,
    path: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    use crest::resample::{AxisInterpolation, Mode, Options};
    let bad = |m: String| CrestError::new_err(m);
    let mode = match mode {
        "fz" => Mode::FeedPerTooth,
        "dtheta" => Mode::SpindleStep {
            dtheta_rad: dtheta_deg.to_radians(),
        },
        m => return Err(bad(format!("mode must be 'fz' or 'dtheta', got '{m}'"))),
    };
    let axis = match axis {
        "slerp" => AxisInterpolation::Slerp,
        "nlerp" => AxisInterpolation::Nlerp,
        a => return Err(bad(format!("axis must be 'slerp' or 'nlerp', got '{a}'"))),
    };
    let mut opts = Options::new(mode, fz_mm, teeth)
        .with_axis_interpolation(axis)
        .with_spline(spline);
    opts.rpm = rpm;
    opts.feed_mm_min = feed_mm_min;
    let cols = py
        .allow_threads(|| -> miette::Result<Vec<Vec<f64>>> {
            crest::resample::Resampler::new(&opts)
                .map_err(|e| miette::miette!("{}: {e}", file.display()))?;
            let program = crest::io::toolpath::read_program(&file)?;
            let selected: Vec<usize> = match path {
                Some(n) if n >= 1 && n <= program.paths.len() => vec![n - 1],
                Some(n) => {
                    return Err(miette::miette!(
                        "{}: --path {n} is out of range: the file has {} tool path(s)",
                        file.display(),
                        program.paths.len()
                    ));
                }
                None => (0..program.paths.len()).collect(),
            };
            let mut cols = vec![Vec::new(); 20];
            for idx in selected {
                let p = &program.paths[idx];
                crest::resample::resample_with(p, &opts, |s| {
                    let nan3 = [f64::NAN; 3];
                    let c = s.contact.map_or(nan3, |c| [c.x, c.y, c.z]);
                    let n = s.normal.map_or(nan3, |n| [n.x, n.y, n.z]);
                    let row = [
                        s.s_mm,
                        s.t_s,
                        s.theta_rad.to_degrees(),
                        s.position.x,
                        s.position.y,
                        s.position.z,
                        s.axis.x,
                        s.axis.y,
                        s.axis.z,
                        c[0],
                        c[1],
                        c[2],
                        n[0],
                        n[1],
                        n[2],
                        s.feed_dir.x,
                        s.feed_dir.y,
                        s.feed_dir.z,
                        s.feed_mm_min,
                        idx as f64,
                    ];
                    for (col, v) in cols.iter_mut().zip(row) {
                        col.push(v);
                    }
                })
                .map_err(|e| {
                    miette::miette!(
                        "{}: tool path {}: {e}",
                        file.display(),
                        if p.name.is_empty() {
                            "(unnamed)"
                        } else {
                            &p.name
                        }
                    )
                })?;
            }
            Ok(cols)
        })
        .map_err(err)?;
    let names = [
        "s_mm",
        "t_s",
        "theta_deg",
        "x",
        "y",
        "z",
        "i",
        "j",
        "k",
        "cx",
        "cy",
        "cz",
        "nx",
        "ny",
        "nz",
        "fx",
        "fy",
        "fz",
        "feed_mm_min",
    ];
    let d = PyDict::new(py);
    let mut cols = cols.into_iter();
    for name in names {
        d.set_item(
            name,
            Array1::from(cols.next().unwrap_or_default()).into_pyarray(py),
        )?;
    }
    let path_col: Vec<i64> = cols
        .next()
        .unwrap_or_default()
        .into_iter()
        .map(|v| v as i64)
        .collect();
    d.set_item("path", Array1::from(path_col).into_pyarray(py))?;
    Ok(d)
}

// ------------------------------------------------------------------------------------------
// Feed planning
// ------------------------------------------------------------------------------------------

/// Plan the feed the machine really reaches (as `crest feed`): one dict per tool path with
/// `name`, `total_time_s`, `programmed_time_s`, `self_check_ok` and per posture `t_s`,
/// `feed_mm_min`, `path_speed_mm_min`, `line` (numpy arrays). `level` "jerk" or "acc".
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (file, machine, *, level = "jerk", absolute = false))]
fn plan_feed<'py>(
    py: Python<'py>,
    file: PathBuf,
    machine: PathBuf,
    level: &str,
    absolute: bool,
) -> PyResult<Bound<'py, PyList>> {
    use crest::kinematics::{Level, plan_input, plan_poses};
    let level = match level {
        "jerk" => Level::Jerk,
        "acc" => Level::Acceleration,
        l => {
            return Err(CrestError::new_err(format!(
                "level must be 'jerk' or 'acc', got '{l}'"
            )));
        }
    };
    let plans = py
        .allow_threads(|| -> miette::Result<_> {
            let machine = crest::pipeline::load_machine(&machine)?;
            let read = crest::io::toolpath::ReadOptions {
                lower: crest::toolpath::LowerOptions {
                    apply_msys: absolute,
                    ..Default::default()
                },
                machine: Some(machine.clone()),
                rtcp: Default::default(),
            };
            let program = crest::io::toolpath::read_program_with(&file, read)?;
            let name = file.display().to_string();
            let mut plans = Vec::new();
            for path in &program.paths {
                let input = plan_input(path);
                let plan = plan_poses(&input, &machine, level).map_err(|e| {
                    let msg = e.to_string();
                    let line = e.line();
                    let msg = msg
                        .strip_prefix(&format!("line {line}: "))
                        .unwrap_or(&msg)
                        .to_string();
                    miette::miette!("{name}:{line}:1: {msg} (tool path \"{}\")", path.name)
                })?;
                plans.push((path.name.clone(), input, plan));
            }
            Ok(plans)
        })
        .map_err(err)?;
    let out = PyList::empty(py);
    for (name, input, plan) in plans {
        let d = PyDict::new(py);
        d.set_item("name", name)?;
        d.set_item("total_time_s", plan.total_time_s)?;
        d.set_item("programmed_time_s", plan.programmed_time_s)?;
        d.set_item("self_check_ok", plan.self_check_ok())?;
        let col = |f: &dyn Fn(&crest::kinematics::PlannedPosture) -> f64| {
            Array1::from_iter(plan.postures.iter().map(f))
        };
        d.set_item("t_s", col(&|p| p.t_s).into_pyarray(py))?;
        d.set_item("feed_mm_min", col(&|p| p.feed_mm_s * 60.0).into_pyarray(py))?;
        d.set_item(
            "path_speed_mm_min",
            col(&|p| p.path_speed_mm_s * 60.0).into_pyarray(py),
        )?;
        d.set_item(
            "line",
            Array1::from_iter(input.iter().map(|i| i.line)).into_pyarray(py),
        )?;
        out.append(d)?;
    }
    Ok(out)
}

// ------------------------------------------------------------------------------------------
// Studies as tasks
// ------------------------------------------------------------------------------------------

/// The tasks of a designed experiment (`crest study` design): `design` is a path to the
/// design TOML, or its text (its `tool` then relative to the working directory). One task
/// per run, each a plain dict (picklable) carrying the design and tool texts; with
/// `monte_carlo` = N also the Monte Carlo settings (N samples of `seed`, as `crest study
/// --monte-carlo N --seed S`).
#[pyfunction]
#[pyo3(signature = (design, *, monte_carlo = None, seed = 1))]
fn study_tasks<'py>(
    py: Python<'py>,
    design: &str,
    monte_carlo: Option<usize>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let texts = if design.contains('\n') || design.contains('=') {
        let d =
            crest::config::design::parse_design(design, "<design>").map_err(|e| err(e.into()))?;
        let tool_file = d.tool.display().to_string();
        let tool_toml =
            crest::io::text::read_text(&d.tool, "tool file").map_err(|e| err(e.into()))?;
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
    let text = serde_json::to_string(&tasks).map_err(|e| CrestError::new_err(e.to_string()))?;
    json_loads(py, &text)
}

/// The tile tasks of a part map (`simulate(..., map_mm=...)` with the same options): `tasks`
/// plain dicts (picklable), task k simulating cells k, k+tasks, … of the map. The file
/// paths are made absolute; every worker must see the files there.
#[pyfunction]
#[pyo3(signature = (file, *, tasks, map_mm, part, region = None, tool = None, process = None, rpm = None, feed_mm_min = None, fz_mm = None, feed = None, machine = None, model = "ice", dtheta_deg = 1.0, grid_um = None, chord_tol_um = None, band_um = None, ap_mm = None, path = None, teeth = None, helix_deg = None, absolute = false))]
#[allow(clippy::too_many_arguments)]
fn map_tasks<'py>(
    py: Python<'py>,
    file: PathBuf,
    tasks: usize,
    map_mm: f64,
    part: PathBuf,
    region: Option<[f64; 6]>,
    tool: Option<Bound<'py, PyAny>>,
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
) -> PyResult<Bound<'py, PyAny>> {
    let abs = |p: PathBuf| std::path::absolute(&p).unwrap_or(p);
    let req = request_of(
        abs(file),
        tool_source(tool)?.map(|t| match t {
            ToolSource::File(p) => ToolSource::File(abs(p)),
            text => text,
        }),
        None,
        None,
        None,
        None,
        Some(map_mm),
        region,
        Some(abs(part)),
        process.map(abs),
        rpm,
        feed_mm_min,
        fz_mm,
        feed,
        machine.map(abs),
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
    let tasks = crest::pipeline::tasks::map::map_tasks(&req, tasks).map_err(err)?;
    let text = serde_json::to_string(&tasks).map_err(|e| CrestError::new_err(e.to_string()))?;
    json_loads(py, &text)
}

/// The tasks of a run-out sweep (`crest runout` study): `study` is a path to the study TOML,
/// or its text (its `tool` then relative to the working directory). With `tasks`, that many
/// tasks (task k: cases k-1, k-1+tasks, … of the sweep, 0-based); by default one task per
/// case. Each a plain dict (picklable) carrying the study and tool texts.
#[pyfunction]
#[pyo3(signature = (study, *, tasks = None))]
fn runout_tasks<'py>(
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
    let text = serde_json::to_string(&tasks).map_err(|e| CrestError::new_err(e.to_string()))?;
    json_loads(py, &text)
}

/// Run one task of `study_tasks`, `runout_tasks` or `map_tasks` (a dict, or its JSON text);
/// returns the result as a dict (picklable). A study run that fails comes back with its
/// `error`. Releases the GIL.
#[pyfunction]
fn run_task<'py>(py: Python<'py>, task: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let text = json_dumps(task)?;
    let task: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| CrestError::new_err(format!("not a crest task: {e}")))?;
    let result = py
        .allow_threads(|| crest::pipeline::tasks::run_any(task))
        .map_err(err)?;
    json_loads(py, &result.to_string())
}

fn part_map(py: Python<'_>, m: &crest::surface::PartMap) -> PyResult<PartMap> {
    let n = m.points.len();
    let mut points = Array2::<f64>::zeros((n, 3));
    let mut normals = Array2::<f64>::zeros((n, 3));
    let mut h = Array1::<f64>::zeros(n);
    for (i, p) in m.points.iter().enumerate() {
        for k in 0..3 {
            points[[i, k]] = p.point[k];
            normals[[i, k]] = p.normal[k];
        }
        h[i] = p.height_um;
    }
    Ok(PartMap {
        points: points.into_pyarray(py).unbind(),
        normals: normals.into_pyarray(py).unbind(),
        height_um: h.into_pyarray(py).unbind(),
        nodes_cut: m.nodes_cut,
    })
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
#[pyfunction]
#[pyo3(signature = (results, output = None))]
fn merge<'py>(
    py: Python<'py>,
    results: &Bound<'py, PyAny>,
    output: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    use crest::pipeline::tasks::Merged;
    let mut parsed = Vec::new();
    for (i, r) in results.try_iter()?.enumerate() {
        let text = json_dumps(&r?)?;
        let v: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| CrestError::new_err(format!("not a crest task result: {e}")))?;
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
fn runout_dict<'py>(
    py: Python<'py>,
    run: &crest::pipeline::runout::RunoutRun,
    files: &[(String, Vec<u8>)],
) -> PyResult<Bound<'py, PyAny>> {
    let d = PyDict::new(py);
    d.set_item("rule", run.study.rule.name())?;
    d.set_item("x", run.study.x.key())?;
    d.set_item("tool", run.tool_path.display().to_string())?;
    let rows = serde_json::to_string(&run.rows).map_err(|e| CrestError::new_err(e.to_string()))?;
    d.set_item("rows", json_loads(py, &rows)?)?;
    let f = PyDict::new(py);
    for (name, bytes) in files {
        f.set_item(name, pyo3::types::PyBytes::new(py, bytes))?;
    }
    d.set_item("files", f)?;
    Ok(d.into_any())
}

/// crest: predicted 5-axis ball-end machined surfaces from tool paths (Python face).
#[pymodule]
#[pyo3(name = "crest")]
fn crest_py(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("CrestError", m.py().get_type::<CrestError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Cutter>()?;
    m.add_class::<HeightMap>()?;
    m.add_class::<PartMap>()?;
    m.add_function(wrap_pyfunction!(read_path, m)?)?;
    m.add_function(wrap_pyfunction!(metrics, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(plan_feed, m)?)?;
    m.add_function(wrap_pyfunction!(resample, m)?)?;
    m.add_function(wrap_pyfunction!(study_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(map_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(runout_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(run_task, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    Ok(())
}
