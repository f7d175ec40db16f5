//! Loading the inputs a command names on disk: `tool.toml`, `machine.toml`,
//! `process.toml`, each read through [`crate::io::text`] and checked by [`crate::config`],
//! with errors that name the file, line and column (and show the offending text).

use crate::config::{ConfigError, MachineError, ProcessConfig, ToolConfigError};
use crate::io::text::read_text;
use crate::kinematics::Machine;
use crate::parse::{Located, Span};
use crate::pipeline::{Error, Result};
use crate::tool::Cutter;
use std::path::{Path, PathBuf};

/// A rejected `tool.toml`: a [`Located`] message in the file, the file's text for the frame.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
#[error("{}:{}:{}: {}", .0.file.as_deref().unwrap_or_default(), .0.span.line, .0.span.column, .0.problem)]
#[diagnostic(transparent)]
pub struct ToolFileError(pub Located);

impl ToolFileError {
    /// A [`ToolConfigError`] on `text`, read from `file`.
    pub fn new(file: &str, text: &str, e: &ToolConfigError) -> ToolFileError {
        ToolFileError(located_in(file, text, e.span(), e.message()))
    }
}

/// `message` at `span` of the configuration file `file` whose text is `text` (shown in the
/// code frame).
pub(crate) fn located_in(file: &str, text: &str, span: Span, message: String) -> Located {
    Located::message(span, message)
        .in_file(file)
        .with_text(text)
}

/// Read `path` as a `tool.toml`.
pub fn load_tool(path: &Path) -> Result<Cutter> {
    let text = read_text(path, "tool file", crate::io::input::CONFIG)?;
    tool_from_text(&text, &path.display().to_string())
}

/// Where a run's `tool.toml` comes from: a file on disk, or its text already in memory (the
/// Python package's `Cutter`), `name` naming it in messages.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ToolSource {
    /// A `tool.toml` file.
    File(PathBuf),
    /// `tool.toml` text, named `name` in messages.
    Text {
        /// Where the text came from (a path or a description).
        name: String,
        /// The `tool.toml` text.
        text: String,
    },
}

impl ToolSource {
    /// The name messages give it: the path as given, or the text's name.
    pub fn name(&self) -> String {
        match self {
            ToolSource::File(p) => p.display().to_string(),
            ToolSource::Text { name, .. } => name.clone(),
        }
    }

    /// The cutter it describes.
    pub fn load(&self) -> Result<Cutter> {
        match self {
            ToolSource::File(p) => load_tool(p),
            ToolSource::Text { name, text } => tool_from_text(text, name),
        }
    }

    /// The minimum chip thickness its `edge_radius_um` gives (mm), or None.
    pub fn min_chip(&self) -> Result<Option<f64>> {
        match self {
            ToolSource::File(p) => tool_min_chip(Some(p)),
            ToolSource::Text { name, text } => crate::config::load_tool_min_chip(text)
                .map_err(|e| ToolFileError::new(name, text, &e).into()),
        }
    }
}

/// Read `tool.toml` text that came from `file`.
pub fn tool_from_text(text: &str, file: &str) -> Result<Cutter> {
    crate::config::load_tool_toml(text).map_err(|e| ToolFileError::new(file, text, &e).into())
}

/// Read `path` as a machine description.
pub fn load_machine(path: &Path) -> Result<Machine> {
    let text = read_text(path, "machine file", crate::io::input::CONFIG)?;
    let file = path.display().to_string();
    Machine::from_toml_str(&text).map_err(|e| {
        let e = match &e {
            MachineError::Missing { at, .. } | MachineError::Invalid { at, .. } => {
                let line = at.line;
                let msg = e.to_string();
                let msg = msg
                    .strip_prefix(&format!("line {line}: "))
                    .unwrap_or(&msg)
                    .to_string();
                // The column of the line's first character (the key or table).
                let column = text
                    .lines()
                    .nth(line.saturating_sub(1) as usize)
                    .map_or(1, |l| l.len() - l.trim_start().len() + 1);
                let column = u32::try_from(column).unwrap_or(u32::MAX);
                ConfigError::new(&file, Span::line_column(line, column), msg)
            }
            MachineError::Toml { at, message } => ConfigError::new(&file, *at, message.clone()),
            _ => ConfigError::whole(&file, e.to_string()),
        };
        e.into()
    })
}

/// The minimum chip thickness a tool file gives through `edge_radius_um` (mm), or None
/// (no file or no edge radius).
pub fn tool_min_chip(path: Option<&Path>) -> Result<Option<f64>> {
    let Some(path) = path else { return Ok(None) };
    let text = read_text(path, "tool file", crate::io::input::CONFIG)?;
    crate::config::load_tool_min_chip(&text)
        .map_err(|e| ToolFileError::new(&path.display().to_string(), &text, &e).into())
}

/// Read `path` as a `process.toml`.
pub fn load_process(path: &Path) -> Result<ProcessConfig> {
    let text = read_text(path, "process file", crate::io::input::CONFIG)?;
    Ok(ProcessConfig::parse(&text, &path.display().to_string())?)
}

/// Default helix angle of a tool taken from TLDATA (which has none), degrees.
pub const TLDATA_HELIX_DEG: f64 = 30.0;

/// The cutter of a run: `tool.toml` when given, else the first tool path's TLDATA with
/// `teeth` (TLDATA has no tooth count) and `helix_deg` (default [`TLDATA_HELIX_DEG`]).
/// Returns the cutter, a one-line description of where it came from, and warnings (a
/// `tool.toml` whose radii disagree with the file's TLDATA).
pub fn resolve_cutter(
    tool: Option<&ToolSource>,
    program: &crate::toolpath::Program,
    file: &Path,
    teeth: Option<usize>,
    helix_deg: Option<f64>,
) -> Result<(Cutter, String, Vec<String>)> {
    use crate::tool::Shape;
    let tldata = program.paths.iter().find_map(|p| p.tool.clone());
    if let Some(source) = tool {
        let cutter = source.load()?;
        let mut warnings = Vec::new();
        if let Some(t) = &tldata {
            let r = 0.5 * t.diameter_mm;
            if t.diameter_mm > 0.0
                && ((r - cutter.radius_mm).abs() > 1e-3
                    || (t.corner_radius_mm - cutter.corner_radius_mm()).abs() > 1e-3)
            {
                warnings.push(format!(
                    "{} has R {} mm, corner radius {} mm, but {}'s TLDATA says D {} mm (R {r} mm), corner radius {} mm: the simulated surface will not be the one the path was computed for",
                    source.name(),
                    cutter.radius_mm,
                    cutter.corner_radius_mm(),
                    file.display(),
                    t.diameter_mm,
                    t.corner_radius_mm
                ));
            }
        }
        return Ok((cutter, source.name(), warnings));
    }
    let Some(t) = tldata else {
        return Err(Error::Input(format!(
            "{} has no TLDATA to take the tool from: give ‹tool› tool.toml",
            file.display()
        )));
    };
    let r = 0.5 * t.diameter_mm;
    if !(r.is_finite() && r > 0.0 && t.corner_radius_mm.is_finite() && t.corner_radius_mm >= 0.0) {
        return Err(Error::Input(format!(
            "{}: TLDATA gives diameter {} mm and corner radius {} mm, which describe no milling cutter: give ‹tool› tool.toml",
            file.display(),
            t.diameter_mm,
            t.corner_radius_mm
        )));
    }
    let Some(teeth) = teeth else {
        return Err(Error::Request(format!(
            "the tool comes from {}'s TLDATA (D {} mm, corner radius {} mm), which has no tooth count: give ‹teeth› N (or ‹tool› tool.toml)",
            file.display(),
            t.diameter_mm,
            t.corner_radius_mm
        )));
    };
    if !(1..=crate::config::MAX_TEETH as usize).contains(&teeth) {
        return Err(Error::field(
            "teeth",
            format!(
                "must be between 1 and {}, got {teeth}",
                crate::config::MAX_TEETH
            ),
        ));
    }
    let helix = helix_deg.unwrap_or(TLDATA_HELIX_DEG);
    if !(helix.is_finite() && helix.abs() < 89.0) {
        return Err(Error::field(
            "helix_deg",
            format!("must lie within ±89°, got {helix}"),
        ));
    }
    let helix_note = if helix_deg.is_none() {
        " (assumed; ‹helix_deg› to change)"
    } else {
        ""
    };
    if let Some(p) = t.apt_profile() {
        // APT's seven parameters describe a shape of their own: angles back to degrees.
        let deg = [
            p[0],
            p[1],
            p[2],
            p[3],
            p[4].to_degrees(),
            p[5].to_degrees(),
            p[6],
        ];
        let (m, warning) = crate::tool::meridian::apt(deg).map_err(|e| {
            Error::Input(format!(
                "{}: the tool's APT parameters describe no cutter: {e}; give ‹tool› tool.toml",
                file.display()
            ))
        })?;
        let cutter = Cutter::from_meridian(m, teeth, helix.to_radians());
        let what = format!(
            "{} from {}'s CUTTER/TLDATA, {teeth} teeth, helix {helix}°{helix_note}",
            cutter.describe(),
            file.display()
        );
        return Ok((cutter, what, warning.into_iter().collect()));
    }
    let rc = t.corner_radius_mm.min(r);
    let (shape, name) = if (rc - r).abs() <= 1e-6 * r {
        (Shape::Ball, "ball end")
    } else if rc <= 1e-9 {
        (Shape::Flat, "flat end")
    } else {
        (
            Shape::Torus {
                corner_radius_mm: rc,
            },
            "bull nose",
        )
    };
    let cutter = Cutter::new(shape, r, teeth, helix.to_radians());
    let what = format!(
        "{name} D {} mm, corner radius {} mm from {}'s TLDATA, {teeth} teeth, helix {helix}°{helix_note}",
        t.diameter_mm,
        rc,
        file.display(),
    );
    Ok((cutter, what, Vec::new()))
}

/// The tool paths `path` (1-based, as users count them) selects among the `n` of `file`,
/// 0-based: that one, or all of them.
pub fn select_paths(file: &Path, path: Option<usize>, n: usize) -> Result<Vec<usize>> {
    match path {
        Some(k) if k >= 1 && k <= n => Ok(vec![k - 1]),
        Some(k) => Err(Error::Request(format!(
            "{}: tool path {k} is out of range: the file has {n} tool path(s)",
            file.display()
        ))),
        None => Ok((0..n).collect()),
    }
}

/// The extent of the tool paths of `file` for budgets (one pass over the file, constant
/// memory): cutting length, cutting runs and the range of programmed feeds, of the path
/// `only` (0-based) or of all, with the moves `moves` selects as cutting.
pub fn path_extent(
    file: &Path,
    read: impl Into<crate::io::toolpath::ReadOptions>,
    only: Option<usize>,
    moves: crate::toolpath::Moves,
) -> Result<crate::resample::PathExtent> {
    use crate::toolpath::{Posture, Toolpath};
    let mut runs = 0usize;
    let mut in_run = false;
    let mut index: Option<usize> = None;
    let mut last_name = String::new();
    let mut sink = |path: &Toolpath, p: &Posture| -> std::io::Result<()> {
        if path.stats.postures == 1 {
            index = Some(index.map_or(0, |i| i + 1));
            in_run = false;
            last_name = path.name.clone();
        }
        if only.is_some() && index != only {
            return Ok(());
        }
        let cut = moves.cuts(p.motion);
        if cut && !in_run {
            runs += 1;
        }
        in_run = cut;
        Ok(())
    };
    let program = crate::io::toolpath::stream_program(file, read, &mut sink)?;
    let mut extent = crate::resample::PathExtent {
        runs,
        ..Default::default()
    };
    for (i, p) in program.paths.iter().enumerate() {
        if only.is_some_and(|o| o != i) {
            continue;
        }
        extent.cutting_mm += match moves {
            crate::toolpath::Moves::Cut => p.stats.cutting_length_mm,
            crate::toolpath::Moves::All => p.stats.feed_length_mm,
        };
        // The highest speed bounds the estimate whichever SPINDL the resampling takes.
        let top = p.stats.spindles_rpm.iter().copied().filter(|n| *n > 0.0);
        extent.spindle_rpm = top.chain(extent.spindle_rpm).reduce(f64::max);
        for &f in &p.stats.feeds_mm_min {
            if f > 0.0 {
                extent.feed_range_mm_min = Some(match extent.feed_range_mm_min {
                    Some((lo, hi)) => (lo.min(f), hi.max(f)),
                    None => (f, f),
                });
            }
        }
    }
    Ok(extent)
}

/// Bytes per row of `crest resample`'s CSV, for the output budget.
pub const RESAMPLE_ROW_BYTES: f64 = 200.0;

/// Refuse an output estimated beyond `max_gb` unless `force`: the message gives the
/// estimate and the options that lift the cap.
pub fn check_output_budget(what: &str, bytes: f64, max_gb: f64, force: bool) -> Result<()> {
    if force || bytes <= max_gb * 1e9 {
        return Ok(());
    }
    Err(Error::Result(format!(
        "{what} would write about {:.2} GB, more than ‹max_output_gb› {max_gb}: check the inputs (a typo in a coordinate or a tiny step?), or raise ‹max_output_gb› / give ‹force›",
        bytes / 1e9
    )))
}
