//! `HeightMap` (a simulated or measured grid of heights) and `PartMap` (heights along the
//! normals of a part's design surface), with their numpy views and files.

use std::path::PathBuf;

use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::metrics::metrics_of;

/// A height map: heights in µm on a regular grid (`z_um[row, col]`, rows along y
/// ascending, NaN = not reached), spacing `dx_um`, `dy_um`, origin (`x0_mm`, `y0_mm`) of
/// node (0, 0) in the grid's frame.
#[pyclass(module = "crest")]
#[derive(Clone)]
pub(crate) struct HeightMap {
    pub(crate) inner: crest::surface::HeightMap,
}

/// Read a height map, as `HeightMap.read` does (the same object): `.csv`, `.xyz`/`.txt`,
/// `.gsf`, `.sdf`, `.x3p`, or an instrument's `.sur`, `.al3d`, `.gwy`, `.plu`, `.plux`,
/// `.opd`, `.vk4`; `channel` names a `.gwy` channel by its title.
#[pyfunction]
#[pyo3(signature = (path, dx_um = None, dy_um = None, channel = None))]
pub(crate) fn read_map(
    path: PathBuf,
    dx_um: Option<f64>,
    dy_um: Option<f64>,
    channel: Option<String>,
) -> PyResult<HeightMap> {
    HeightMap::read(path, dx_um, dy_um, channel)
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

    /// Read a height map (.csv, .xyz/.txt, .gsf, .sdf, .x3p, or an instrument's .sur,
    /// .al3d, .gwy, .plu, .plux, .opd, .vk4; `channel`: a .gwy channel's title).
    #[staticmethod]
    #[pyo3(signature = (path, dx_um = None, dy_um = None, channel = None))]
    pub(crate) fn read(
        path: PathBuf,
        dx_um: Option<f64>,
        dy_um: Option<f64>,
        channel: Option<String>,
    ) -> PyResult<HeightMap> {
        let opts = crest::io::ReadOptions {
            dx_um,
            dy_um,
            channel,
        };
        crest::io::read_heightmap(&path, &opts)
            .map(|inner| HeightMap { inner })
            .map_err(|e| crate::crest_error(e.to_string()))
    }

    /// Heights, µm: a (ny, nx) float64 array (a copy).
    #[getter]
    fn z_um<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let m = &self.inner;
        Array2::from_shape_vec((m.ny, m.nx), m.z_um.clone())
            .map(|a| a.into_pyarray(py))
            .map_err(|e| crate::crest_error(e.to_string()))
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
            .map_err(|e| crate::crest_error(format!("cannot write {}: {e}", path.display())))
    }
}

/// A simulated part map: points on the design surface (N×3, mm), their normals (N×3) and
/// heights along the normals (N, µm; NaN = not reached).
#[pyclass(module = "crest", get_all)]
pub(crate) struct PartMap {
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

pub(crate) fn part_map(py: Python<'_>, m: &crest::surface::PartMap) -> PyResult<PartMap> {
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
