//! `crest view`: a height map (CSV, GSF, SDF, xyz) or a part map (PLY) as one self-contained
//! 3-D viewer page (HTML with three.js and the data embedded).

use std::path::PathBuf;

use miette::{IntoDiagnostic, WrapErr, miette};

use super::Outcome;
use crest::io::{ReadOptions, read_heightmap};
use crest::report::view::{self, ViewInfo};

/// Options of `crest view`.
#[derive(Debug, clap::Args)]
#[command(after_help = "The page needs no network: three.js (npm `three` \
0.187.0, MIT licence) and the data are embedded. A height map is drawn as a shaded surface \
(at most 90 000 nodes: larger maps are shown as NaN-aware block means), a part map as a point \
cloud coloured by the height along the normal. Click two points on a height map for the \
profile between them: its Rz is the one `crest metrics MAP --profile line:X0,Y0,X1,Y1 \
--params Rz` prints (taken from the full map when it has at most 1 048 576 nodes, from the \
displayed block means otherwise; the page says which).")]
pub struct Args {
    /// Height map (`.csv` grid with --dx-um, `.csv`/`.xyz` point list, `.gsf`, `.sdf`, `.x3p`,
    /// an instrument's `.sur`, `.al3d`, `.gwy`, `.plu`, `.plux`, `.opd`, `.vk4`) or a
    /// part map (`.ply` from `crest simulate --map-mm`).
    pub file: PathBuf,
    /// The page to write (HTML).
    #[arg(short = 'o', long = "out", value_name = "VIEW.html")]
    pub out: PathBuf,
    /// Spacing along x, µm (needed for a grid CSV).
    #[arg(long, value_name = "D")]
    pub dx_um: Option<f64>,
    /// Spacing along y, µm (grid CSV: defaults to --dx-um).
    #[arg(long, value_name = "D")]
    pub dy_um: Option<f64>,
    /// The channel of a Gwyddion `.gwy` to read, by its title (default: the first channel
    /// with heights in a length unit).
    #[arg(long, value_name = "NAME")]
    pub channel: Option<String>,
    /// Title of the page (default: the file's name).
    #[arg(long)]
    pub title: Option<String>,
    /// For a point cloud (.ply): colour the points by this property instead of
    /// `height_um`, e.g. `Sa_um`, `scallop_um` or `lead_deg` of `crest atlas`'s cloud.
    #[arg(long, value_name = "COLUMN", alias = "color-by")]
    pub colour_by: Option<String>,
}

/// Run `crest view`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    super::check_outputs([args.out.as_path()])?;
    let file = args.file.display().to_string();
    let info = ViewInfo {
        title: args.title.clone().unwrap_or_else(|| {
            let name = args
                .file
                .file_name()
                .map_or_else(|| file.clone(), |n| n.to_string_lossy().into_owned());
            match &args.colour_by {
                Some(c) => format!("{name}: {c}"),
                None => name,
            }
        }),
        source: file.clone(),
        file: Some(file.clone()),
    };
    let is_ply = args
        .file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if args.colour_by.is_some() && !is_ply {
        return Err(miette!(
            "--colour-by picks a property of a point cloud (.ply); {file} is a height map"
        ));
    }
    let (html, what) = if is_ply {
        let column = args.colour_by.as_deref().unwrap_or("height_um");
        let points =
            crest::io::mesh::read_map_ply_column(&args.file, column).map_err(|e| miette!("{e}"))?;
        let html = view::part_map_page(&points, &info).map_err(|e| miette!("{file}: {e}"))?;
        (
            html,
            format!("point cloud, {} points, coloured by {column}", points.len()),
        )
    } else {
        let opts = ReadOptions {
            dx_um: args.dx_um,
            dy_um: args.dy_um,
            channel: args.channel.clone(),
        };
        let map = read_heightmap(&args.file, &opts).map_err(|e| miette!("{e}"))?;
        let html = view::heightmap_page(&map, &info).map_err(|e| miette!("{file}: {e}"))?;
        (html, format!("height map {} × {}", map.nx, map.ny))
    };
    crest::io::write_atomic(&args.out, |w| w.write_all(html.as_bytes()))
        .into_diagnostic()
        .wrap_err_with(|| format!("cannot write {}", args.out.display()))?;
    outln!("wrote {}: 3-D view of {file} ({what})", args.out.display());
    Ok(Outcome::Ok)
}
