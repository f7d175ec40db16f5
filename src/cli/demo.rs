//! `crest demo`: the whole pipeline on an embedded default, in one command.
//!
//! The default is the 002 case study on a plane: a ball end of R 5 mm with 4 teeth and a 30°
//! helix, 10 µm of run-out, lead 15°, fz 0.05 mm at 80 m/min, passes 0.2 mm apart. The demo
//! makes the contact-data path itself (`synth`), writes it as CLSF, reads it back
//! (`parse`/`toolpath`), converts it to contact12, resamples it at a constant spindle step,
//! sweeps the teeth's edges over a window (ICE model), computes the roughness parameters,
//! draws the plots, and writes a short report that holds the simulated feed marks against
//! the closed-form crest of 002 Eqs 7, 8 and 14.

use super::Outcome;
use crest::metrics::{self, ParamSet, ProfileSpec};
use crest::resample::{self, Mode};
use crest::surface::{self, GridSpec, Model};
use crest::synth::{self, Orientation, PathSpec, Step, Surface};
use crest::tool::{self, Rule};
use miette::{Context, IntoDiagnostic};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The embedded tool: 002's ball end with 10 µm of run-out in the direction of tooth 1.
const DEMO_TOOL: &str = r#"# the case-study tool of Marin et al. 2023 with 10 µm of run-out
shape = "ball"
radius_mm = 5.0
teeth = 4
helix_deg = 30.0
[runout]
offset_um = 10.0
offset_phase_deg = 0.0
"#;

const LEAD_DEG: f64 = 15.0;
const FZ_MM: f64 = 0.05;
const STEPOVER_MM: f64 = 0.2;
/// 80 m/min on a 10 mm ball: n = 80 000 / (π · 10) rpm.
const RPM: f64 = 2546.479;
const DTHETA_DEG: f64 = 1.0;
const GRID_UM: f64 = 2.0;

/// Options of `crest demo`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder for everything the demo writes (created if missing).
    #[arg(short = 'o', long = "out", default_value = "crest-demo")]
    pub out: PathBuf,
}

/// Run `crest demo`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    // Everything is built in a staging folder beside the output folder (the demo reads back
    // what it wrote, as a user's file would be read) and lands there whole at the end.
    let out = &args.out;
    let staging = crest::io::output::Staging::beside(out)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot create a folder beside {}", out.display()))?;
    let dir = staging.path().to_path_buf();
    let dir = &dir;
    let mut wrote: Vec<(PathBuf, String)> = Vec::new();

    // 1. Tool and synthetic contact-data path.
    let cutter = crest::config::load_tool_toml(DEMO_TOOL)
        .map_err(|e| miette::miette!("embedded tool: {e}"))?;
    let teeth = cutter.teeth();
    let feed_mm_min = teeth as f64 * FZ_MM * RPM;
    let mut spec = PathSpec::new(
        Surface::Plane,
        cutter.clone(),
        Orientation::Lead {
            lead_rad: LEAD_DEG.to_radians(),
        },
        Step::Stepover {
            spacing_mm: STEPOVER_MM,
        },
        (3.0, 1.6),
    );
    spec.feed_mm_min = feed_mm_min;
    spec.spindle_rpm = RPM;
    spec.point_step_mm = 0.25;
    spec.name = "DEMO_PLANE_LEAD15".into();
    let synthetic = synth::generate(&spec).map_err(|e| miette::miette!("demo path: {e}"))?;
    let cls = dir.join("demo.cls");
    write_file(&cls, |w| crest::toolpath::write_clsf(&synthetic.program, w))?;
    wrote.push((
        cls.clone(),
        format!("CLSF with contact data, {} passes", synthetic.passes),
    ));

    // 2. Read it back as a user's file would be read, and convert it to contact12.
    let program = crest::io::toolpath::read_program(&cls)?;
    let path = program
        .paths
        .first()
        .ok_or_else(|| miette::miette!("{}: no tool path read back", cls.display()))?;
    let csv = dir.join("demo-contact12.csv");
    write_file(&csv, |w| crest::toolpath::write_contact12(path, false, w))?;
    wrote.push((
        csv,
        "contact12 CSV (cutting moves with contact data)".into(),
    ));

    // 3. Resample at a constant spindle step.
    let opts = resample::Options::new(
        Mode::SpindleStep {
            dtheta_rad: DTHETA_DEG.to_radians(),
        },
        FZ_MM,
        teeth,
    );
    let samples =
        resample::resample(path, &opts).map_err(|e| miette::miette!("resampling: {e}"))?;

    // 4. Simulate a window in the middle of the field (ICE model).
    let window = GridSpec::Window {
        x0_mm: -0.5,
        y0_mm: -0.3,
        x1_mm: 0.5,
        y1_mm: 0.3,
    };
    let sim_opts = surface::Options::new(
        Model::Ice {
            dtheta_rad: DTHETA_DEG.to_radians(),
        },
        window,
        GRID_UM * 1e-3,
    );
    let started = std::time::Instant::now();
    let sim = surface::simulate(&samples, &cutter, &sim_opts, &|_, _| {})
        .map_err(|e| miette::miette!("simulation: {e}"))?;
    let sim_seconds = started.elapsed().as_secs_f64();
    let map = &sim.map;
    for ext in ["gsf", "csv"] {
        let p = dir.join(format!("heightmap.{ext}"));
        crest::io::write_heightmap(&p, map)
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", p.display()))?;
        wrote.push((
            p,
            format!("height map {} × {} at {GRID_UM} µm", map.nx, map.ny),
        ));
    }

    // 5. Metrics: areal parameters and the profile along the feed through the window centre.
    let areal = metrics::areal_parameters(map, &ParamSet::all(false))
        .map_err(|e| miette::miette!("areal parameters: {e}"))?;
    let row = map.ny / 2;
    let profile = metrics::extract_profile(map, ProfileSpec::Row(row))
        .map_err(|e| miette::miette!("profile: {e}"))?;
    let rz_feed =
        metrics::profile_values(&profile, 5).map_err(|e| miette::miette!("profile: {e}"))?;

    // The closed-form model of 002: participating teeth, fz_eff and the crest (Eqs 7, 8, 14).
    let analysis = tool::analyse(&cutter, LEAD_DEG, 0.4, FZ_MM, Rule::Paper)
        .map_err(|e| miette::miette!("tool analysis: {e}"))?;

    // 6. Plots.
    let heat = dir.join("heightmap.png");
    crest::plot::heightmap::plot_heightmap(
        map,
        "Simulated surface (ICE model, 10 µm run-out); 0 = the nominal surface",
        &heat,
    )
    .map_err(|e| miette::miette!("{}: {e}", heat.display()))?;
    wrote.push((heat, "height map plot".into()));
    let x_mm: Vec<f64> = (0..profile.z.len())
        .map(|i| i as f64 * profile.step_um * 1e-3)
        .collect();
    let prof = dir.join("profile-feed.svg");
    crest::plot::profile::plot_profiles(
        "Profile along the feed (window centre)",
        (&x_mm, &profile.z),
        None,
        &prof,
    )
    .map_err(|e| miette::miette!("{}: {e}", prof.display()))?;
    wrote.push((prof, "profile along the feed".into()));
    let troch = dir.join("trochoids.svg");
    let troch_opts = crest::plot::trochoid::TrochoidOptions {
        stepover_mm: STEPOVER_MM,
        fz_mm: analysis.fz_effective_mm,
        ..Default::default()
    };
    crest::plot::trochoid::plot_trochoids(&cutter, &troch_opts, &troch)
        .map_err(|e| miette::miette!("{}: {e}", troch.display()))?;
    wrote.push((
        troch,
        "trochoids of the cutting-edge elements (as Marin et al. 2023, Fig 14)".into(),
    ));
    let view = dir.join("view.html");
    let info = crest::report::view::ViewInfo {
        title: "crest demo: simulated surface (ICE model, 10 µm run-out)".into(),
        source: "heightmap.gsf".into(),
        file: Some("heightmap.gsf".into()),
    };
    // The heights as heightmap.gsf stores them (float32), so that a clicked profile's Rz is
    // the one `crest metrics heightmap.gsf --profile line:…` prints.
    let stored = crest::io::as_stored(map, crest::io::HeightMapFormat::Gsf)
        .map_err(|e| miette::miette!("3-D view: {e}"))?;
    let html = crest::report::view::heightmap_page(&stored, &info)
        .map_err(|e| miette::miette!("3-D view: {e}"))?;
    write_file(&view, |w| w.write_all(html.as_bytes()))?;
    wrote.push((
        view,
        "3-D viewer (open in a browser; click two points for a profile and its Rz)".into(),
    ));

    // 7. Short report.
    let mut md = String::new();
    let _ = writeln!(md, "# crest demo\n");
    let _ = writeln!(
        md,
        "Regenerate: `crest demo -o {}` (from the repository: `cargo run --release -- demo -o {}`)\n",
        out.display(),
        out.display()
    );
    let _ = writeln!(
        md,
        "Ball end R 5 mm, {teeth} teeth, helix 30°, run-out e0 = 10 µm; lead {LEAD_DEG}°, \
         fz {FZ_MM} mm, {RPM:.1} rpm ({feed_mm_min:.1} mm/min), stepover {STEPOVER_MM} mm; \
         ICE model, Δθ = {DTHETA_DEG}°, grid {GRID_UM} µm, {} samples, simulated in {sim_seconds:.2} s.\n",
        samples.len()
    );
    let _ = writeln!(
        md,
        "| quantity | closed form (Marin et al. 2023, Eqs 7, 8, 14) | simulated |\n|---|---|---|"
    );
    let _ = writeln!(md, "| participating teeth | {} of {teeth} | |", analysis.zc);
    let _ = writeln!(
        md,
        "| feed-mark spacing fz_eff [mm] | {:.4} | |",
        analysis.fz_effective_mm
    );
    let _ = writeln!(
        md,
        "| crest height / Rz along the feed [µm] | {:.4} | {:.4} (Rz, row {row}) |",
        analysis.crest_height_corrected_mm * 1e3,
        rz_feed.rz
    );
    let _ = writeln!(
        md,
        "| lateral crest, stepover {STEPOVER_MM} mm [µm] | {:.4} | |",
        tool::crest_height_mm(5.0, STEPOVER_MM) * 1e3
    );
    let _ = writeln!(
        md,
        "\nAreal parameters of the simulated window (µm, %, degrees):\n"
    );
    let _ = writeln!(md, "| parameter | value |\n|---|---|");
    for (p, v) in &areal {
        let _ = writeln!(md, "| {} | {v:.4} |", p.symbol());
    }
    let _ = writeln!(md, "\nFiles:\n");
    for (p, what) in &wrote {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let _ = writeln!(md, "- `{name}`: {what}");
    }
    let report = dir.join("report.md");
    write_file(&report, |w| w.write_all(md.as_bytes()))?;
    wrote.push((report, "this summary".into()));
    staging
        .land(out)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write the demo into {}", out.display()))?;

    outln!("crest demo: the case study of Marin et al. 2023 on a plane, with 10 µm of run-out");
    outln!(
        "  teeth cutting: {} of {teeth}, feed marks {:.3} mm apart, crest {:.3} µm (closed form), Rz {:.3} µm (simulated)",
        analysis.zc,
        analysis.fz_effective_mm,
        analysis.crest_height_corrected_mm * 1e3,
        rz_feed.rz
    );
    for (p, what) in &wrote {
        let name = p.file_name().map(PathBuf::from).unwrap_or_default();
        outln!("  wrote {}: {what}", out.join(name).display());
    }
    Ok(Outcome::Ok)
}

fn write_file<F>(path: &Path, fill: F) -> miette::Result<()>
where
    F: FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>,
{
    crest::io::write_atomic(path, fill)
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", path.display()))
}
