//! `crest study`: a designed-experiment file read from disk, its tool loaded (relative to the
//! design file), every run simulated in parallel and the factor effects computed.

use crate::io::text::read_text;
use crate::study::design::{Design, Effects, RunResult, design_effects, run_design};
use crate::study::run::simulate_run;
use crate::tool::Cutter;
use miette::{WrapErr, miette};
use std::path::Path;

/// A finished designed experiment.
#[derive(Debug, Clone)]
pub struct DesignRun {
    /// The design.
    pub design: Design,
    /// The tool.
    pub cutter: Cutter,
    /// One result per run, in run order.
    pub results: Vec<RunResult>,
    /// Factor effects per response, in response order.
    pub effects: Vec<Effects>,
}

/// Read the design `path` and its tool (without running anything).
pub fn load_design(path: &Path) -> miette::Result<(Design, Cutter)> {
    let text = read_text(path, "design")?;
    let file = path.display().to_string();
    let design = crate::config::design::parse_design(&text, &file)?;
    let tool_path = path.parent().unwrap_or(Path::new(".")).join(&design.tool);
    let cutter = super::load_tool(&tool_path).wrap_err_with(|| {
        format!(
            "{file}: cannot read tool file {} (the path is relative to the design file)",
            tool_path.display()
        )
    })?;
    Ok((design, cutter))
}

/// Run every run of `design` with `cutter` on the current rayon pool (`tick` once per
/// finished run). Fails, naming every failed run, unless all succeed.
pub fn run(
    design: Design,
    cutter: Cutter,
    file: &str,
    tick: &(dyn Fn() + Sync),
) -> miette::Result<DesignRun> {
    let results = run_design(&design, |p| simulate_run(&design, &cutter, p), tick);
    let failed: Vec<String> = results
        .iter()
        .filter_map(|r| {
            r.error
                .as_ref()
                .map(|e| format!("run {}: {e}", r.point.run))
        })
        .collect();
    if !failed.is_empty() {
        return Err(miette!(
            "{file}: {} of {} runs failed, nothing written:\n  {}",
            failed.len(),
            results.len(),
            failed.join("\n  ")
        ));
    }
    let effects = design_effects(&design, &results);
    Ok(DesignRun {
        design,
        cutter,
        results,
        effects,
    })
}
