//! `metrics`: profile and ISO 25178 areal parameters of a height map or a file.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::maps::HeightMap;

#[allow(clippy::too_many_arguments)]
pub(crate) fn metrics_of<'py>(
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
    let bad = |e: String| crate::crest_error(e);
    let pp = Preprocess {
        level: Level::parse(level).map_err(|e| bad(e.to_string()))?,
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
        .map_err(|e| bad(e.to_string()))?;
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
pub(crate) fn metrics<'py>(
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
        let h = HeightMap::read(path.clone(), dx_um, dy_um, None)?;
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
