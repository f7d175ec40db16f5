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
    #[arg(long, value_enum, default_value_t = RuleArg::Exact)]
    pub rule: RuleArg,
    /// Print one JSON object on stdout.
    #[arg(long)]
    pub json: bool,
}

/// The `--rule` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum RuleArg {
    /// Marin et al. 2023, Eq 8: a tooth cuts when its radius at the generating height
    /// exceeds the largest one less the nominal crest height.
    Paper,
    /// Lower envelope of the teeth's feed-direction profiles.
    Exact,
}

impl From<RuleArg> for Rule {
    fn from(r: RuleArg) -> Rule {
        match r {
            RuleArg::Paper => Rule::Paper,
            RuleArg::Exact => Rule::Exact,
        }
    }
}

/// Name of a shape in output.
pub fn shape_name(shape: Shape) -> &'static str {
    match shape {
        Shape::Ball => "ball",
        Shape::Torus { .. } => "torus",
        Shape::Flat => "flat",
    }
}

/// Run `crest tool`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let cutter = crest::pipeline::load_tool(&args.tool)?;
    let rule = Rule::from(args.rule);
    let a = analyse(&cutter, args.lead_deg, args.ap_mm, args.fz_mm, rule)
        .map_err(|e| miette::miette!("{e}"))?;
    let r = cutter.radius_mm;
    if args.json {
        let teeth: Vec<serde_json::Value> = a
            .teeth
            .iter()
            .map(|t| {
                serde_json::json!({
                    "index": t.index,
                    "radius_mm": t.radius_mm,
                    "local_radius_mm": t.local_radius_mm,
                    "runout_um": t.runout_mm * 1e3,
                    "normal_deviation_um": t.normal_deviation_mm * 1e3,
                    "participates": t.participates,
                    "participates_paper": t.participates_paper,
                    "participates_exact": t.participates_exact,
                    "effective_radius_mm": t.effective_radius_mm,
                    "cutting_speed_ratio": t.effective_radius_mm / r,
                    "effective_radius_error_pct": t.effective_radius_error_pct,
                })
            })
            .collect();
        let out = serde_json::json!({
            "tool": args.tool.display().to_string(),
            "shape": shape_name(cutter.shape),
            "radius_mm": r,
            "corner_radius_mm": cutter.corner_radius_mm(),
            "teeth_count": cutter.teeth(),
            "helix_deg": cutter.helix_rad.to_degrees(),
            "lead_deg": args.lead_deg,
            "ap_mm": args.ap_mm,
            "fz_mm": args.fz_mm,
            "rule": rule.name(),
            "effective_radius_mm": a.effective_radius_mm,
            "cutting_speed_ratio": a.cutting_speed_ratio,
            "cutting_speed_pct": 100.0 * a.cutting_speed_ratio,
            "contact_radius_mm": a.contact_radius_mm,
            "generating_height_mm": a.generating_height_mm,
            "crest_height_um": a.crest_height_mm * 1e3,
            "crest_height_corrected_um": a.crest_height_corrected_mm * 1e3,
            "crest_height_exact_um": a.crest_height_exact_mm * 1e3,
            "zc": a.zc,
            "zc_paper": a.zc_paper,
            "zc_exact": a.zc_exact,
            "fz_effective_mm": a.fz_effective_mm,
            "participating_teeth": a.teeth.iter().filter(|t| t.participates).map(|t| t.index).collect::<Vec<_>>(),
            "teeth": teeth,
        });
        outln!("{out}");
        return Ok(Outcome::Ok);
    }
    let mut s = String::new();
    use std::fmt::Write as _;
    let _ = writeln!(
        s,
        "tool {}: {} R {} mm{}, {} teeth, helix {:.3}°",
        args.tool.display(),
        shape_name(cutter.shape),
        r,
        match cutter.shape {
            Shape::Torus { corner_radius_mm } => format!(" rc {corner_radius_mm} mm"),
            _ => String::new(),
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
        "tooth  radius_mm  run-out_um  normal_dev_um  cuts  R_ef_mm   R_ef_error_%"
    );
    for t in &a.teeth {
        let _ = writeln!(
            s,
            "{:>5}  {:>9.5}  {:>10.3}  {:>13.3}  {:>4}  {:>8.5}  {:>12.5}",
            t.index,
            t.radius_mm,
            t.runout_mm * 1e3,
            t.normal_deviation_mm * 1e3,
            if t.participates { "yes" } else { "no" },
            t.effective_radius_mm,
            t.effective_radius_error_pct
        );
    }
    outln!("{}", s.trim_end_matches('\n'));
    Ok(Outcome::Ok)
}
