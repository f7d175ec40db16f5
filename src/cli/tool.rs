//! `crest tool`: cutter analysis for one engagement on a plane — effective radius and
//! cutting-speed ratio (002 Table 3), crest height (Eq 14), participating teeth and the
//! corrected feed mark spacing (Eqs 7-8).

use super::Outcome;
use crest::tool::{Rule, Shape, analyse};
use std::path::PathBuf;

/// Options of `crest tool`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Cutter description (`tool.toml`).
    #[arg(long, value_name = "TOOL.TOML")]
    pub tool: PathBuf,
    /// Lead angle β between the tool axis and the surface normal, in the feed direction, degrees.
    #[arg(long = "lead-deg", value_name = "DEG", allow_hyphen_values = true)]
    pub lead_deg: f64,
    /// Depth of cut along the surface normal, mm.
    #[arg(long = "ap-mm", value_name = "MM", allow_hyphen_values = true)]
    pub ap_mm: f64,
    /// Feed per tooth, mm.
    #[arg(long = "fz-mm", value_name = "MM", allow_hyphen_values = true)]
    pub fz_mm: f64,
    /// Which teeth cut: `exact` (the lower envelope of every tooth's marks) or `paper` (the
    /// participating-tooth rule of Marin et al. 2023, Eq 8, for reproducing the paper).
    #[arg(long, value_enum, default_value_t = Rule::Exact)]
    pub rule: Rule,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Run `crest tool`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let cutter = crest::pipeline::load_tool(&args.tool)?;
    let rule = args.rule;
    let a = analyse(&cutter, args.lead_deg, args.ap_mm, args.fz_mm, rule)
        .map_err(|e| miette::miette!("{e}"))?;
    let r = cutter.radius_mm;
    if args.json {
        let out = crest::pipeline::tool::analysis_json(
            &cutter,
            &args.tool.display().to_string(),
            (args.lead_deg, args.ap_mm, args.fz_mm),
            rule,
            &a,
        );
        outln!("{out}");
        return Ok(Outcome::Ok);
    }
    let mut s = String::new();
    use std::fmt::Write as _;
    let _ = writeln!(
        s,
        "tool {}: {} R {} mm{}, {} teeth, helix {:.3}°",
        args.tool.display(),
        cutter.shape.name(),
        r,
        match &cutter.shape {
            Shape::Torus { corner_radius_mm } => format!(" rc {corner_radius_mm} mm"),
            Shape::Ball | Shape::Flat => String::new(),
            _ => format!(" ({})", cutter.describe()),
        },
        cutter.teeth(),
        cutter.helix_rad.to_degrees()
    );
    let _ = writeln!(
        s,
        "engagement: lead {}°, ap {} mm, fz {} mm/tooth, rule {}",
        args.lead_deg,
        args.ap_mm,
        args.fz_mm,
        rule.name()
    );
    let _ = writeln!(
        s,
        "effective radius      {:.5} mm  (cutting speed {:.3} % of nominal; contact radius {:.4} mm)",
        a.effective_radius_mm,
        100.0 * a.cutting_speed_ratio,
        a.contact_radius_mm
    );
    let _ = writeln!(
        s,
        "crest height          {:.6} µm at fz",
        a.crest_height_mm * 1e3
    );
    let _ = writeln!(
        s,
        "participating teeth   zc = {} of {}  (paper {}, exact {}); fz_eff = {:.5} mm",
        a.zc,
        cutter.teeth(),
        a.zc_paper,
        a.zc_exact,
        a.fz_effective_mm
    );
    let _ = writeln!(
        s,
        "crest height corrected {:.6} µm  (exact 1-D envelope {:.6} µm)",
        a.crest_height_corrected_mm * 1e3,
        a.crest_height_exact_mm * 1e3
    );
    let _ = writeln!(
        s,
        "tooth  radius_mm  run-out_um  normal_dev_um  cuts  R_ef_mm   R_ef_error_%{}",
        if cutter.has_axial_dev() {
            "  axial_um"
        } else {
            ""
        }
    );
    for t in &a.teeth {
        let _ = writeln!(
            s,
            "{:>5}  {:>9.5}  {:>10.3}  {:>13.3}  {:>4}  {:>8.5}  {:>12.5}{}",
            t.index,
            t.radius_mm,
            t.runout_mm * 1e3,
            t.normal_deviation_mm * 1e3,
            if t.participates { "yes" } else { "no" },
            t.effective_radius_mm,
            t.effective_radius_error_pct,
            if cutter.has_axial_dev() {
                format!("  {:>8.3}", t.axial_deviation_mm * 1e3)
            } else {
                String::new()
            }
        );
    }
    outln!("{}", s.trim_end_matches('\n'));
    Ok(Outcome::Ok)
}
