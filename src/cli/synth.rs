//! `crest synth`: write a synthetic tool path with contact data for a known surface, as
//! NX-style CLSF (`.cls`) or contact12 (`.txt`, `.csv`).

use super::Outcome;
use clap::ValueEnum;
use crest::synth::{Orientation, PathSpec, Pattern, Step, Surface, generate};
use miette::{IntoDiagnostic, WrapErr, miette};
use std::path::{Path, PathBuf};

/// The surfaces `crest synth` knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SurfaceKind {
    /// The plane z = 0 (default field 20 × 10 mm).
    Plane,
    /// z = −0.004·x² + 0.1 mm extruded along y (Lavernhe et al., Fig 7; default field 10 × 10 mm).
    ExtrudedParabola,
    /// z = x·y / 200 mm (the paraboloid of Lavernhe et al.'s feed study; passes along its rulings; default field
    /// 40 × 40 mm).
    HyperbolicParaboloid,
    /// Camber waves and twist: z = sin(2πx/40) + 0.5 sin(2πy/30) + 0.002·x·y mm
    /// (default field 40 × 20 mm).
    BladePatch,
    /// A convex cylinder about the x axis, top line on z = 0 (radius --surface-radius-mm,
    /// default 20; default field 10 × 6 mm).
    ConvexCylinder,
    /// A concave cylinder (a trough) about the x axis, bottom line on z = 0 (radius
    /// --surface-radius-mm, default 20; default field 10 × 6 mm).
    ConcaveCylinder,
    /// A convex sphere, top on the origin (radius --surface-radius-mm, default 20; default
    /// field 6 × 6 mm).
    Sphere,
}

impl SurfaceKind {
    fn surface(self, radius_mm: f64) -> Surface {
        match self {
            SurfaceKind::Plane => Surface::Plane,
            SurfaceKind::ExtrudedParabola => Surface::paper_parabola(),
            SurfaceKind::HyperbolicParaboloid => Surface::paper_hyperbolic_paraboloid(),
            SurfaceKind::BladePatch => Surface::default_blade(),
            SurfaceKind::ConvexCylinder => Surface::ConvexCylinder { radius_mm },
            SurfaceKind::ConcaveCylinder => Surface::ConcaveCylinder { radius_mm },
            SurfaceKind::Sphere => Surface::Sphere { radius_mm },
        }
    }

    fn default_size_mm(self) -> (f64, f64) {
        match self {
            SurfaceKind::Plane => (20.0, 10.0),
            SurfaceKind::ExtrudedParabola => (10.0, 10.0),
            SurfaceKind::HyperbolicParaboloid => (40.0, 40.0),
            SurfaceKind::BladePatch => (40.0, 20.0),
            SurfaceKind::ConvexCylinder | SurfaceKind::ConcaveCylinder => (10.0, 6.0),
            SurfaceKind::Sphere => (6.0, 6.0),
        }
    }
}

/// Options of `crest synth`.
#[derive(Debug, clap::Args)]
#[command(group(
    clap::ArgGroup::new("step").required(true).args(["scallop_um", "stepover_mm"])
))]
pub struct Args {
    /// Surface to machine.
    #[arg(value_enum)]
    pub surface: SurfaceKind,
    /// Cutter description (tool.toml).
    #[arg(long, value_name = "TOOL.toml")]
    pub tool: PathBuf,
    /// Tilt λ of the tool axis from the surface normal, degrees (in the plane set by the yaw).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub tilt_deg: Option<f64>,
    /// Yaw ψ: rotation of the inclination plane about the normal, from the feed, degrees.
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub yaw_deg: Option<f64>,
    /// Lead β in the feed direction, degrees (the same as --tilt-deg β --yaw-deg 0).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true, conflicts_with_all = ["tilt_deg", "yaw_deg"])]
    pub lead_deg: Option<f64>,
    /// One fixed tool axis for the whole path, I,J,K (a 3-axis path: 0,0,1), instead of an
    /// axis set from the surface normal.
    #[arg(long, value_name = "I,J,K", allow_hyphen_values = true, conflicts_with_all = ["tilt_deg", "yaw_deg", "lead_deg"])]
    pub axis: Option<String>,
    /// Radius of the cylinders and the sphere, mm.
    #[arg(long, value_name = "MM", default_value_t = 20.0)]
    pub surface_radius_mm: f64,
    /// Measure --stepover-mm along the surface across the passes (through the field's
    /// centre) instead of between the drive planes.
    #[arg(long, requires = "stepover_mm")]
    pub stepover_along_surface: bool,
    /// Also write the design surface of the field (and a margin of the tool radius + 1 mm)
    /// as binary STL, for `crest simulate --part` and `crest contact --part`.
    #[arg(long, value_name = "PART.STL")]
    pub part_stl: Option<PathBuf>,
    /// Chord tolerance of the STL facets, µm.
    #[arg(long, value_name = "UM", default_value_t = 0.05, requires = "part_stl")]
    pub part_tol_um: f64,
    /// Target scallop height, µm: the stepover comes from the exact swept envelope.
    #[arg(long, value_name = "UM")]
    pub scallop_um: Option<f64>,
    /// Distance between the passes' drive planes, mm.
    #[arg(long, value_name = "MM")]
    pub stepover_mm: Option<f64>,
    /// Programmed feed, mm/min.
    #[arg(long, value_name = "MM_PER_MIN")]
    pub feed_mm_min: f64,
    /// Feed at the end of each pass, mm/min: the feed falls or rises linearly along every
    /// pass from --feed-mm-min, one FEDRAT per move (e.g. 4000 → 500, as Lavernhe et al., Fig 6).
    #[arg(long, value_name = "MM_PER_MIN")]
    pub feed_end_mm_min: Option<f64>,
    /// Spindle speed, rpm.
    #[arg(long, value_name = "RPM")]
    pub rpm: f64,
    /// Field: length along the passes, width across, mm (centred on the origin).
    #[arg(long, value_name = "A,B", value_delimiter = ',', num_args = 1)]
    pub size_mm: Option<Vec<f64>>,
    /// Direction of the passes in the XY plane, degrees from +X.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub pass_angle_deg: f64,
    /// Alternate the pass direction (default: one-way, every pass in the same direction).
    #[arg(long)]
    pub zigzag: bool,
    /// Spacing of CC points along a pass, mm.
    #[arg(long, value_name = "MM", default_value_t = 0.5)]
    pub point_step_mm: f64,
    /// Retract along the tool axis between passes, mm.
    #[arg(long, value_name = "MM", default_value_t = 5.0)]
    pub clearance_mm: f64,
    /// Output file: `.cls` (CLSF with contact data) or `.txt`/`.csv` (contact12).
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,
    /// Print one JSON object (stepover_mm, passes, …) on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OutKind {
    Clsf,
    Contact12,
}

fn out_kind(path: &Path) -> miette::Result<OutKind> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("cls" | "clsf") => Ok(OutKind::Clsf),
        Some("txt" | "csv") => Ok(OutKind::Contact12),
        _ => Err(miette!(
            "{}: unknown output extension (use .cls for CLSF, .txt or .csv for contact12)",
            path.display()
        )),
    }
}

/// Run `crest synth`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    let kind = out_kind(&args.output)?;
    let cutter = crest::pipeline::load_tool(&args.tool)?;
    let size_mm = match args.size_mm.as_deref() {
        None => args.surface.default_size_mm(),
        Some([a, b]) => (*a, *b),
        Some(v) => {
            return Err(miette!(
                "--size-mm takes two lengths A,B (along, across the passes), got {} values",
                v.len()
            ));
        }
    };
    let orientation = match (args.lead_deg, &args.axis) {
        (Some(lead), _) => Orientation::Lead {
            lead_rad: lead.to_radians(),
        },
        (None, Some(a)) => {
            let v: Vec<f64> = a
                .split(',')
                .map(|t| t.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| miette!("--axis wants three numbers I,J,K, got '{a}'"))?;
            let axis = match v.as_slice() {
                [i, j, k] => crest::math::Vec3::new(*i, *j, *k),
                _ => return Err(miette!("--axis wants three numbers I,J,K, got '{a}'")),
            };
            let Some(axis) = crest::math::normalize_or_none(&axis, 1e-9)
                .filter(|a| a.iter().all(|c| c.is_finite()))
            else {
                return Err(miette!("--axis {a} is not a direction"));
            };
            Orientation::Fixed { axis }
        }
        (None, None) => Orientation::TiltYaw {
            tilt_rad: args.tilt_deg.unwrap_or(0.0).to_radians(),
            yaw_rad: args.yaw_deg.unwrap_or(0.0).to_radians(),
        },
    };
    let step = match (args.scallop_um, args.stepover_mm) {
        (Some(h), _) => Step::Scallop {
            height_mm: h * 1e-3,
        },
        (None, Some(s)) if args.stepover_along_surface => Step::SurfaceArc { spacing_mm: s },
        (None, Some(s)) => Step::Stepover { spacing_mm: s },
        (None, None) => return Err(miette!("give --scallop-um or --stepover-mm")),
    };
    if !(args.surface_radius_mm.is_finite() && args.surface_radius_mm > 0.0) {
        return Err(miette!(
            "--surface-radius-mm must be positive, got {}",
            args.surface_radius_mm
        ));
    }
    let margin = cutter.radius_mm + 1.0;
    let mut spec = PathSpec::new(
        args.surface.surface(args.surface_radius_mm),
        cutter,
        orientation,
        step,
        size_mm,
    );
    spec.pass_angle_rad = args.pass_angle_deg.to_radians();
    spec.pattern = if args.zigzag {
        Pattern::Zigzag
    } else {
        Pattern::OneWay
    };
    spec.point_step_mm = args.point_step_mm;
    spec.clearance_mm = args.clearance_mm;
    spec.feed_mm_min = args.feed_mm_min;
    spec.feed_end_mm_min = args.feed_end_mm_min;
    spec.spindle_rpm = args.rpm;
    super::check_outputs(std::iter::once(args.output.as_path()).chain(args.part_stl.as_deref()))?;
    let synth = generate(&spec).map_err(|e| miette!("crest synth: {e}"))?;
    let part = match &args.part_stl {
        Some(_) => Some(
            crest::synth::mesh::surface_mesh(
                &spec.surface,
                size_mm,
                spec.pass_angle_rad,
                margin,
                args.part_tol_um * 1e-3,
            )
            .map_err(|e| miette!("crest synth --part-stl: {e}"))?,
        ),
        None => None,
    };

    let program = &synth.program;
    let mut outputs = crest::io::output::Outputs::new();
    let staged = outputs.file(&args.output, |w| match kind {
        OutKind::Clsf => crest::toolpath::write_clsf(program, w),
        OutKind::Contact12 => match program.paths.first() {
            // Every move, so that the clearance moves between passes survive.
            Some(p) => crest::toolpath::write_contact12(p, true, w),
            None => Ok(()),
        },
    });
    staged
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", args.output.display()))?;
    if let (Some(path), Some(mesh)) = (&args.part_stl, &part) {
        outputs
            .file(path, |w| crest::io::mesh::write_stl(mesh, w))
            .into_diagnostic()
            .wrap_err_with(|| format!("cannot write {}", path.display()))?;
    }
    outputs
        .land()
        .into_diagnostic()
        .wrap_err("cannot write the outputs (none was changed)")?;

    let postures: usize = program.paths.iter().map(|p| p.postures.len()).sum();
    let (tilt_deg, yaw_deg) = match args.lead_deg {
        Some(lead) => (lead, 0.0),
        None => (args.tilt_deg.unwrap_or(0.0), args.yaw_deg.unwrap_or(0.0)),
    };
    if args.json {
        let report = serde_json::json!({
            "surface": spec.surface.name(),
            "output": args.output.display().to_string(),
            "format": match kind { OutKind::Clsf => "clsf", OutKind::Contact12 => "contact12" },
            "tool": spec.tool_name,
            "stepover_mm": synth.stepover_mm,
            "passes": synth.passes,
            "points_per_pass": synth.points_per_pass,
            "postures": postures,
            "scallop_um": args.scallop_um,
            "plane_step_mm": synth.plane_step_mm,
            "r_eff_mm": crest::io::tables::json_number(synth.r_eff_mm),
            "tilt_deg": tilt_deg,
            "yaw_deg": yaw_deg,
            "pass_angle_deg": args.pass_angle_deg,
            "pattern": if args.zigzag { "zigzag" } else { "one-way" },
            "size_mm": [size_mm.0, size_mm.1],
            "feed_mm_min": args.feed_mm_min,
            "feed_end_mm_min": args.feed_end_mm_min,
            "rpm": args.rpm,
            "axis": args.axis,
            "stepover_along_surface": args.stepover_along_surface,
            "surface_radius_mm": spec.surface.radius_mm(),
            "part_stl": args.part_stl.as_ref().map(|p| p.display().to_string()),
            "part_triangles": part.as_ref().map(|m| m.triangles.len()),
        });
        outln!("{report}");
    } else {
        outln!(
            "wrote {}: {} passes of {} points, stepover {:.4} mm, {} postures",
            args.output.display(),
            synth.passes,
            synth.points_per_pass,
            synth.stepover_mm,
            postures
        );
    }
    Ok(Outcome::Ok)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crest::synth::Surface;
    use crest::tool::{Cutter, Shape};
    use crest::toolpath::MotionKind;

    /// Write a synthetic path through the CLI's writer choice and read it back with the
    /// reader every command uses: the same postures (to the written precision).
    fn round_trip(ext: &str) {
        let cutter = Cutter::new(Shape::Ball, 5.0, 4, 30f64.to_radians());
        let mut spec = PathSpec::new(
            Surface::default_blade(),
            cutter,
            Orientation::TiltYaw {
                tilt_rad: 10f64.to_radians(),
                yaw_rad: 20f64.to_radians(),
            },
            Step::Scallop { height_mm: 0.002 },
            (10.0, 4.0),
        );
        spec.pattern = Pattern::Zigzag;
        spec.pass_angle_rad = 0.4;
        spec.point_step_mm = 1.0;
        let synth = generate(&spec).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(format!("p.{ext}"));
        let kind = out_kind(&out).unwrap();
        crest::io::write_atomic(&out, |w| match kind {
            OutKind::Clsf => crest::toolpath::write_clsf(&synth.program, w),
            OutKind::Contact12 => {
                crest::toolpath::write_contact12(&synth.program.paths[0], true, w)
            }
        })
        .unwrap();
        let back = crest::io::toolpath::read_program(&out).unwrap();
        let (a, b) = (&synth.program.paths[0], &back.paths[0]);
        assert_eq!(a.postures.len(), b.postures.len());
        assert_eq!(a.cutting_runs(), b.cutting_runs());
        for (p, q) in a.postures.iter().zip(&b.postures) {
            assert_eq!(p.motion, q.motion);
            assert!(
                (p.position - q.position).norm() < 2e-6,
                "{:?} {:?}",
                p.position,
                q.position
            );
            assert!((p.axis - q.axis).norm() < 1e-6);
            match (&p.contact, &q.contact) {
                (Some(c), Some(d)) => {
                    assert!((c.point - d.point).norm() < 2e-6);
                    assert!((c.normal - d.normal).norm() < 1e-6);
                }
                (None, None) => {}
                _ => panic!("contact data lost at {:?}", p.position),
            }
            // The writer states FEDRAT before the first feed move; rapids carry no feed.
            if kind == OutKind::Clsf && p.motion == MotionKind::Cut {
                assert_eq!(p.feed_mm_min, q.feed_mm_min);
                assert_eq!(p.spindle_rpm, q.spindle_rpm);
            }
        }
        assert!(b.postures.iter().any(|p| p.motion == MotionKind::Cut));
    }

    #[test]
    fn clsf_round_trip_keeps_postures() {
        round_trip("cls");
    }

    #[test]
    fn contact12_round_trip_keeps_postures() {
        round_trip("txt");
    }
}
