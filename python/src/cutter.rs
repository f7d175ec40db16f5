//! `Cutter`: a tool as `crest` reads it from a `tool.toml`, built from a file or from keys.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{err, json_loads};

/// A cutter, as `crest` reads it from a `tool.toml`.
///
/// `Cutter.from_toml(path)` reads a file; `Cutter(shape="ball", radius_mm=5.0, teeth=2,
/// helix_deg=0.0, **more)` writes the same keys as a `tool.toml` (any key of the file,
/// e.g. `corner_radius_mm` for a torus) and checks them with the same rules and messages.
#[pyclass(module = "crest", frozen)]
#[derive(Clone)]
pub(crate) struct Cutter {
    /// The tool.toml text the cutter was read from.
    #[pyo3(get)]
    pub(crate) toml: String,
    /// Where it came from (a path, or "<keyword arguments>").
    #[pyo3(get)]
    pub(crate) source: String,
    inner: crest::tool::Cutter,
}

pub(crate) fn toml_value(v: &Bound<'_, PyAny>) -> PyResult<String> {
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
        let text = crest::io::text::read_text(&path, "tool file", crest::io::input::CONFIG)
            .map_err(err)?;
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
                return Err(crate::crest_error(format!(
                    "rule must be 'exact' or 'paper', got '{r}'"
                )));
            }
        };
        let a = crest::tool::analyse(&self.inner, lead_deg, ap_mm, fz_mm, rule)
            .map_err(|e| crate::crest_error(e.to_string()))?;
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
