//! The Python module `crest`: tool paths as numpy arrays, cutters, simulated height maps,
//! metrics and designed experiments as picklable tasks, all through the library's
//! `crest::pipeline` (no subprocess). Long computations release the GIL.

use pyo3::create_exception;
use pyo3::prelude::*;

create_exception!(
    crest,
    CrestError,
    pyo3::exceptions::PyException,
    "An error of crest: bad input (naming file, line and column) or a failed computation. \
     The message is the command line's; `file`, `line` and `column` are the place in an \
     input it names (None when it names none)."
);

/// A crest error as a Python exception: the message and its causes, one per line, as the
/// command line prints them (without the code frame), and the place in an input it names
/// (the error's `crest::parse::Located`, as the command line's frame) as `file`, `line` and
/// `column`.
fn err(e: impl Into<miette::Report>) -> PyErr {
    let e: miette::Report = e.into();
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        msg.push_str("\n  caused by: ");
        msg.push_str(&cause.to_string());
    }
    let place = e
        .chain()
        .find_map(crest::pipeline::located::of_error)
        .map(|l| (l.file.clone(), l.span));
    let py_err = crest_error(msg);
    if let Some((file, span)) = place {
        Python::with_gil(|py| {
            let value = py_err.value(py);
            // Setting an attribute on an exception instance cannot fail.
            let _ = value.setattr("file", file);
            let _ = value.setattr("line", (span.line > 0).then_some(span.line));
            let _ = value.setattr("column", (span.column > 0).then_some(span.column));
        });
    }
    py_err
}

/// A [`CrestError`] with `message`, its request fields as keywords (`‹grid_um›` → `grid_um`).
fn crest_error(message: impl AsRef<str>) -> PyErr {
    CrestError::new_err(crest::pipeline::fields::for_python(message.as_ref()).into_owned())
}

fn json_loads<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    // Warnings and checks in the results name request fields as keywords.
    let text = crest::pipeline::fields::for_python(text);
    py.import("json")?.call_method1("loads", (text.as_ref(),))
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

mod cutter;
mod maps;
mod metrics;
mod path;
mod simulate;
mod tasks;

/// crest: predicted 5-axis ball-end machined surfaces from tool paths (Python face).
#[pymodule]
#[pyo3(name = "crest")]
fn crest_py(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let error = m.py().get_type::<CrestError>();
    for name in ["file", "line", "column"] {
        error.setattr(name, m.py().None())?;
    }
    m.add("CrestError", error)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<cutter::Cutter>()?;
    m.add_class::<maps::HeightMap>()?;
    m.add_class::<maps::PartMap>()?;
    m.add_function(wrap_pyfunction!(maps::read_map, m)?)?;
    m.add_function(wrap_pyfunction!(path::read_path, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::metrics, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(path::plan_feed, m)?)?;
    m.add_function(wrap_pyfunction!(path::resample, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::study_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::map_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::atlas_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::runout_tasks, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::run_task, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::merge, m)?)?;
    Ok(())
}
