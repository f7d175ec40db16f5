//! Tool paths as numpy arrays: `read_path`, `resample` and `plan_feed` (the feed the machine
//! reaches), as `crest inspect`, `crest resample` and `crest feed` compute them.

use std::path::PathBuf;

use numpy::IntoPyArray;
use numpy::ndarray::{Array1, Array2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::err;

/// Read a tool-path file (NX CLSF, other APT, contact12 CSV; chosen by content) into one
/// dict per tool path: `name`, `tool_name`, and per posture `tip` (N×3, mm), `axis` (N×3,
/// unit), `motion` (list of "from", "rapid", "cut", "cycle", "gohome"), `feed_mm_min` and
/// `spindle_rpm` (N, NaN before the first FEDRAT/SPINDL), `line` (N, source line),
/// `contact` and `normal` (N×3, NaN where the file has no contact data).
#[pyfunction]
#[pyo3(signature = (file, *, absolute = false))]
pub(crate) fn read_path<'py>(
    py: Python<'py>,
    file: PathBuf,
    absolute: bool,
) -> PyResult<Bound<'py, PyList>> {
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
            motion.push(q.motion.name().to_string());
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

/// Resample the cutting moves of a tool-path file (as `crest resample`, programmed feed):
/// `mode` "fz" (even feed per tooth) or "dtheta" (constant spindle step `dtheta_deg`).
/// Returns a dict of numpy arrays, one entry per sample, with the columns of `crest
/// resample`'s CSV (`s_mm`, `t_s`, `theta_deg`, `x`, `y`, `z`, `i`, `j`, `k`, `cx`, `cy`,
/// `cz`, `nx`, `ny`, `nz` (NaN without contact data), `fx`, `fy`, `fz`, `feed_mm_min`) and
/// `path` (0-based tool path index), at full precision. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (file, *, mode, fz_mm, teeth, dtheta_deg = 0.5, rpm = None, feed_mm_min = None, axis = "slerp", spline = false, path = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn resample<'py>(
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
    use crest::resample::{AxisInterpolation, Mode};
    let bad = |m: String| crate::crest_error(m);
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
    let req = crest::pipeline::resample::ResampleRequest {
        file,
        mode,
        fz_mm: Some(fz_mm),
        teeth: Some(teeth),
        rpm,
        feed_mm_min,
        feed: None,
        machine: None,
        rtcp: crest::nc::Rtcp::Auto,
        axis,
        spline,
        path,
        moves: crest::toolpath::Moves::Cut,
    };
    let cols = py
        .allow_threads(|| -> miette::Result<Vec<Vec<f64>>> {
            let mut cols = vec![Vec::new(); 20];
            crest::pipeline::resample::resample_each(&req, |idx, s| {
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
            })?;
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

/// Plan the feed the machine really reaches (as `crest feed`): one dict per tool path with
/// `name`, `total_time_s`, `programmed_time_s`, `self_check_ok` and per posture `t_s`,
/// `feed_mm_min`, `path_speed_mm_min`, `line` (numpy arrays). `level` "jerk" or "acc".
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (file, machine, *, level = "jerk", absolute = false))]
pub(crate) fn plan_feed<'py>(
    py: Python<'py>,
    file: PathBuf,
    machine: PathBuf,
    level: &str,
    absolute: bool,
) -> PyResult<Bound<'py, PyList>> {
    use crest::kinematics::Level;
    let level = match level {
        "jerk" => Level::Jerk,
        "acc" => Level::Acceleration,
        l => {
            return Err(crate::crest_error(format!(
                "level must be 'jerk' or 'acc', got '{l}'"
            )));
        }
    };
    let plans = py
        .allow_threads(|| -> crest::pipeline::Result<_> {
            let machine = crest::pipeline::load_machine(&machine)?;
            crest::pipeline::feed::plan_file(&file, &machine, level, absolute, Default::default())
        })
        .map_err(err)?;
    let out = PyList::empty(py);
    for crest::pipeline::feed::PlannedPath { name, input, plan } in plans {
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
