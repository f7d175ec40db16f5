//! `crest metrics`: profile and ISO 25178 areal parameters of a height map, after optional
//! form removal and Gaussian S-/L-filtering; ISO 21920-2 profile parameters of a measured
//! profile (a `.csv` with the header `x_mm,z_um`, as `runout identify` reads it).

use std::path::PathBuf;

use miette::miette;

use super::Outcome;
use crest::io::tables::json_number;
use crest::io::{GsfRows, HeightMapFormat, ReadOptions, open_gsf_rows, read_heightmap};
use crest::metrics::{
    EndEffects, Level, ParamSet, Preprocess, ProfileSpec, RowStream, areal_parameters,
    extract_profile, preprocess_map, preprocess_profile, profile_from_points, profile_parameters,
};
use crest::surface::HeightMap;

/// Border handling of the Gaussian filters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Ends {
    /// Symmetric reflection at the borders, every node kept (as surfalize).
    Reflect,
    /// Reflection, then discard λ/2 of the largest nesting index at each border (ISO 4288).
    Trim,
}

/// Options of `crest metrics`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Heights and lateral lengths are µm, angles degrees, Sdr and Smr1/Smr2 %, \
volumes µm³/µm². Missing (NaN) nodes are excluded, never taken as zero.\n\
Processing order: form removal (--level), S-filter (--lambda-s-um), L-filter (--lambda-c-um), \
then the end zones are cut off with --ends trim.\n\
Std is measured counter-clockwise from +x with y = row index ascending (surfalize, which draws \
row 0 at the top, reports 180 - Std). Str is null when the autocorrelation does not decay in \
some direction (any 1-D lay). Sbi, Sci and Svi are not computed."
)]
pub struct Args {
    /// Height map: `.csv` grid (rows = y ascending, µm; needs --dx-um), `.xyz`/`.txt` or a
    /// `.csv` with an `x,y,z` header (point list, µm), Gwyddion `.gsf`, ISO 25178-71 `.sdf`, ISO 25178-72 `.x3p` (OpenGPS),
    /// or an instrument's own file: `.sur`, `.al3d`, `.gwy`, `.plu`, `.plux`, `.opd`, `.vk4`;
    /// or a measured profile, a `.csv` whose header is `x_mm,z_um` (its profile parameters;
    /// unevenly spaced points are resampled at the median step).
    pub file: PathBuf,
    /// Spacing along x, µm (needed for grid CSV; checked against the other formats).
    #[arg(long, value_name = "D")]
    pub dx_um: Option<f64>,
    /// Spacing along y, µm (grid CSV: defaults to --dx-um).
    #[arg(long, value_name = "D")]
    pub dy_um: Option<f64>,
    /// The channel of a Gwyddion `.gwy` to read, by its title (default: the first channel
    /// with heights in a length unit).
    #[arg(long, value_name = "NAME")]
    pub channel: Option<String>,
    /// Form removal before the parameters: `none`, `plane` or `poly:N` (least-squares
    /// polynomial of total degree N; Marin et al. 2023 use poly:5). Default `none`: heights
    /// are only referred to their mean plane, nothing is re-levelled silently.
    #[arg(long, default_value = "none", value_parser = Level::parse, value_name = "none|plane|poly:N")]
    pub level: Level,
    /// S-filter nesting index λs, µm (Gaussian low-pass, ISO 16610-21/61).
    #[arg(long, value_name = "L")]
    pub lambda_s_um: Option<f64>,
    /// L-filter nesting index λc, µm (Gaussian high-pass: z − lowpass(z)).
    #[arg(long, value_name = "L")]
    pub lambda_c_um: Option<f64>,
    /// End effects of the filters.
    #[arg(long, value_enum, default_value = "reflect")]
    pub ends: Ends,
    /// Profile instead of areal parameters: `row:K`, `col:K` (0-based), `angle:DEG` (a line
    /// through the map centre, CCW from +x) or `line:X0,Y0,X1,Y1` (the segment between two
    /// points, µm from the node of column 0, row 0; what `crest view` picks by two clicks).
    #[arg(long, value_parser = ProfileSpec::parse, value_name = "row:K|col:K|angle:DEG|line:X0,Y0,X1,Y1")]
    pub profile: Option<ProfileSpec>,
    /// Number of sampling lengths for Rp, Rv, Rz.
    #[arg(long, default_value_t = 5, value_name = "N")]
    pub sections: usize,
    /// Comma list of ISO symbols to compute (e.g. `Sa,Sq,Sdr` or `Ra,Rz`); default all of the
    /// kind. Only what is listed is computed.
    #[arg(long, value_name = "LIST")]
    pub params: Option<String>,
    /// Print one JSON object (keys = ISO symbols; null for undefined values).
    #[arg(long)]
    pub json: bool,
    /// Most memory the parameters may take, GB (estimated from the nodes before computing;
    /// refused beyond it with the `--params` that fit).
    #[arg(long, default_value_t = 4.0, value_name = "GB")]
    pub max_memory_gb: f64,
}

fn spec_label(s: ProfileSpec) -> String {
    match s {
        ProfileSpec::Row(k) => format!("row:{k}"),
        ProfileSpec::Col(k) => format!("col:{k}"),
        ProfileSpec::Angle(a) => format!("angle:{a}"),
        ProfileSpec::Line {
            x0_um,
            y0_um,
            x1_um,
            y1_um,
        } => format!("line:{x0_um},{y0_um},{x1_um},{y1_um}"),
    }
}

/// The map as read: a [`HeightMap`], or, when only plain-pass parameters are asked for
/// without preprocessing, a `.gsf` streamed in pieces of rows (a few rows of memory, the same
/// values): its grid, its parameters and its number of valid nodes.
enum Loaded {
    Map(HeightMap),
    Streamed {
        dims: (usize, usize, f64, f64),
        values: Vec<(crest::metrics::Param, f64)>,
        valid: usize,
    },
}

impl Loaded {
    fn dims(&self) -> (usize, usize, f64, f64) {
        match self {
            Loaded::Map(m) => (m.nx, m.ny, m.dx_um, m.dy_um),
            Loaded::Streamed { dims, .. } => *dims,
        }
    }
}

/// Bytes of heights per piece of a streamed `.gsf` (whole rows; a few of these are in
/// memory at once, small enough to stay in the caches: the kernel's copy into a piece and
/// the kernels reading it then hit the cache; 4 MiB pieces cost ~20 % more CPU time).
const PIECE_BYTES: usize = 256 << 10;

/// The plain-pass parameters of a streamed `.gsf` and its number of valid nodes.
fn streamed(
    rows: &GsfRows,
    set: &ParamSet,
) -> miette::Result<(Vec<(crest::metrics::Param, f64)>, usize)> {
    let file = rows.path().display().to_string();
    let s = RowStream::<f32>::new(rows.nx, rows.ny, rows.dx_um, rows.dy_um, set)
        .map_err(|e| miette!("{file}: {e}"))?;
    let k = s.rows_per_piece(PIECE_BYTES);
    // One range of rows per thread, each read and reduced on its own thread.
    let s = s
        .by_parts(rayon::current_num_threads(), |range, each| {
            rows.read_row_range(range, k, each)
        })
        .map_err(|e| miette!("{e}"))?;
    let valid = s.valid();
    let values = s.finish().map_err(|e| miette!("{file}: {e}"))?;
    Ok((values, valid))
}

fn preprocess(args: &Args) -> Preprocess {
    Preprocess {
        level: args.level,
        lambda_s_um: args.lambda_s_um,
        lambda_c_um: args.lambda_c_um,
        ends: match args.ends {
            Ends::Reflect => EndEffects::Reflect,
            Ends::Trim => EndEffects::Trim,
        },
    }
}

/// `crest metrics PROFILE.csv`: the profile parameters of a measured `x_mm,z_um` profile,
/// evenly sampled ([`profile_from_points`]), through the same form removal and filters as
/// a profile taken from a map.
fn run_profile(args: &Args, xs: &[f64], zs: &[f64]) -> miette::Result<Outcome> {
    let file = args.file.display().to_string();
    for (given, flag) in [
        (args.profile.is_some(), "--profile"),
        (args.channel.is_some(), "--channel"),
        (
            args.dx_um.is_some() || args.dy_um.is_some(),
            "--dx-um/--dy-um",
        ),
    ] {
        if given {
            return Err(miette!(
                "{file}: {flag} is for height maps; this is a measured profile (x_mm,z_um), whose spacing comes from its x"
            ));
        }
    }
    let set = match &args.params {
        Some(list) => ParamSet::parse(list, true),
        None => Ok(ParamSet::all(true)),
    }
    .map_err(|e| miette!("{e}"))?;
    if set.params().is_empty() {
        return Err(miette!("--params lists no parameter"));
    }
    let pp = preprocess(args);
    let (raw, resampled) = profile_from_points(xs, zs).map_err(|e| miette!("{file}: {e}"))?;
    let prof = preprocess_profile(&raw, &pp).map_err(|e| miette!("{file}: {e}"))?;
    let values =
        profile_parameters(&prof, &set, args.sections).map_err(|e| miette!("{file}: {e}"))?;
    if args.json {
        let mut info = serde_json::Map::new();
        info.insert("file".into(), file.clone().into());
        info.insert("format".into(), "profile".into());
        info.insert("points".into(), xs.len().into());
        info.insert(
            "profile".into(),
            serde_json::json!({
                "samples": prof.z.len(),
                "step_um": prof.step_um,
                "evaluation_length_um": prof.z.len() as f64 * prof.step_um,
                "sections": args.sections,
                "resampled": resampled,
            }),
        );
        info.insert("level".into(), pp.level.label().into());
        info.insert(
            "lambda_s_um".into(),
            pp.lambda_s_um.map_or(serde_json::Value::Null, json_number),
        );
        info.insert(
            "lambda_c_um".into(),
            pp.lambda_c_um.map_or(serde_json::Value::Null, json_number),
        );
        let mut units = serde_json::Map::new();
        for (p, v) in &values {
            info.insert(p.symbol().into(), json_number(*v));
            units.insert(p.symbol().into(), p.unit().into());
        }
        info.insert("units".into(), units.into());
        outln!("{}", serde_json::Value::Object(info));
    } else {
        outln!(
            "{file}: measured profile, {} points, {} samples every {} µm{}, level {}, {} sampling lengths",
            xs.len(),
            prof.z.len(),
            prof.step_um,
            if resampled {
                " (resampled: the points are not evenly spaced)"
            } else {
                ""
            },
            pp.level.label(),
            args.sections
        );
        print_values(&values)?;
    }
    Ok(Outcome::Ok)
}

/// One line per parameter: symbol, value (six decimals, or "undefined"), unit.
fn print_values(values: &[(crest::metrics::Param, f64)]) -> miette::Result<()> {
    for (p, v) in values {
        let shown = if v.is_finite() {
            format!("{v:.6}")
        } else {
            "undefined".into()
        };
        outln!("{:<5} {:>14} {}", p.symbol(), shown, p.unit());
    }
    Ok(())
}

/// Run `crest metrics`.
pub fn run(args: Args) -> miette::Result<Outcome> {
    if let Some((xs, zs)) = crest::io::profile_csv::read_if_profile(&args.file)? {
        return run_profile(&args, &xs, &zs);
    }
    let file = args.file.display().to_string();
    let opts = ReadOptions {
        dx_um: args.dx_um,
        dy_um: args.dy_um,
        channel: args.channel.clone(),
    };
    let pp = preprocess(&args);
    let profile_mode = args.profile.is_some();
    let set = match &args.params {
        Some(list) => ParamSet::parse(list, profile_mode),
        None => Ok(ParamSet::all(profile_mode)),
    }
    .map_err(|e| miette!("{e}"))?;
    if set.params().is_empty() {
        return Err(miette!("--params lists no parameter"));
    }
    let filtered = pp.lambda_s_um.is_some() || pp.lambda_c_um.is_some();
    let as_stored = HeightMapFormat::from_path(&args.file) == Some(HeightMapFormat::Gsf)
        && crest::io::input::is_regular(&args.file)
        && !profile_mode
        && pp.level.degree() == 0
        && !filtered
        && set.passes_only();
    // The memory of the parameters on a map in memory, up front where the header gives
    // the nodes (a regular .gsf), and again once the map is read (missing nodes cost more).
    let preprocessed = pp.level.degree() != 0 || filtered;
    if !as_stored
        && !profile_mode
        && HeightMapFormat::from_path(&args.file) == Some(HeightMapFormat::Gsf)
        && crest::io::input::is_regular(&args.file)
        && let Ok(rows) = open_gsf_rows(&args.file, &opts)
    {
        check_memory(&file, (rows.nx, rows.ny), &set, false, preprocessed, &args)?;
    }
    let loaded = if as_stored {
        let rows = open_gsf_rows(&args.file, &opts).map_err(|e| miette!("{e}"))?;
        let (values, valid) = streamed(&rows, &set)?;
        Loaded::Streamed {
            dims: (rows.nx, rows.ny, rows.dx_um, rows.dy_um),
            values,
            valid,
        }
    } else {
        Loaded::Map(read_heightmap(&args.file, &opts).map_err(|e| miette!("{e}"))?)
    };
    let (nx, ny, dx_um, dy_um) = loaded.dims();
    let mut info = serde_json::Map::new();
    info.insert("file".into(), file.clone().into());
    let format = HeightMapFormat::from_path(&args.file).map(|f| format!("{f:?}").to_lowercase());
    info.insert("format".into(), format.into());
    info.insert("nx".into(), nx.into());
    info.insert("ny".into(), ny.into());
    info.insert("dx_um".into(), json_number(dx_um));
    info.insert("dy_um".into(), json_number(dy_um));
    let known = match &loaded {
        Loaded::Map(m) => m.known(),
        Loaded::Streamed { valid, .. } => *valid,
    };
    info.insert("valid_nodes".into(), known.into());
    info.insert("level".into(), pp.level.label().into());
    info.insert(
        "lambda_s_um".into(),
        pp.lambda_s_um.map_or(serde_json::Value::Null, json_number),
    );
    info.insert(
        "lambda_c_um".into(),
        pp.lambda_c_um.map_or(serde_json::Value::Null, json_number),
    );
    info.insert(
        "end_effects".into(),
        if filtered {
            pp.ends.describe()
        } else {
            "no filter applied"
        }
        .into(),
    );
    info.insert("trimmed_um".into(), json_number(pp.trim_um()));

    let values = match (&loaded, args.profile) {
        (Loaded::Streamed { values, .. }, _) => {
            info.insert("evaluated_nx".into(), nx.into());
            info.insert("evaluated_ny".into(), ny.into());
            values.clone()
        }
        (Loaded::Map(map), Some(spec)) => {
            let raw = extract_profile(map, spec).map_err(|e| miette!("{file}: {e}"))?;
            let prof = preprocess_profile(&raw, &pp).map_err(|e| miette!("{file}: {e}"))?;
            info.insert(
                "profile".into(),
                serde_json::json!({
                    "spec": spec_label(spec),
                    "samples": prof.z.len(),
                    "step_um": prof.step_um,
                    "evaluation_length_um": prof.z.len() as f64 * prof.step_um,
                    "sections": args.sections,
                }),
            );
            profile_parameters(&prof, &set, args.sections).map_err(|e| miette!("{file}: {e}"))?
        }
        (Loaded::Map(map), None) => {
            let missing = map.known() < map.z_um.len();
            check_memory(&file, (map.nx, map.ny), &set, missing, preprocessed, &args)?;
            // Without form removal or filters the map is used as read (no copy of a large map).
            let processed;
            let m = if pp.level.degree() == 0 && !filtered {
                map
            } else {
                processed = preprocess_map(map, &pp).map_err(|e| miette!("{file}: {e}"))?;
                &processed
            };
            info.insert("evaluated_nx".into(), m.nx.into());
            info.insert("evaluated_ny".into(), m.ny.into());
            areal_parameters(m, &set).map_err(|e| miette!("{file}: {e}"))?
        }
    };

    if args.json {
        let mut units = serde_json::Map::new();
        for (p, v) in &values {
            info.insert(p.symbol().into(), json_number(*v));
            units.insert(p.symbol().into(), p.unit().into());
        }
        info.insert("units".into(), units.into());
        outln!("{}", serde_json::Value::Object(info));
    } else {
        outln!(
            "{file}: {}×{} nodes, dx {} µm, dy {} µm, level {}",
            nx,
            ny,
            dx_um,
            dy_um,
            pp.level.label()
        );
        if filtered {
            outln!(
                "filters: λs {:?} µm, λc {:?} µm; {}",
                pp.lambda_s_um,
                pp.lambda_c_um,
                pp.ends.describe()
            );
        }
        if let Some(spec) = args.profile {
            outln!(
                "profile {} ({} sampling lengths)",
                spec_label(spec),
                args.sections
            );
        }
        print_values(&values)?;
    }
    Ok(Outcome::Ok)
}

/// Refuse, before computing, parameters whose memory estimate
/// ([`ParamSet::bytes_per_node`]) exceeds `--max-memory-gb`, naming the estimate and the
/// `--params` that fit.
fn check_memory(
    file: &str,
    (nx, ny): (usize, usize),
    set: &ParamSet,
    missing: bool,
    preprocessed: bool,
    args: &Args,
) -> miette::Result<()> {
    let max = args.max_memory_gb;
    if !(max.is_finite() && max > 0.0) {
        return Err(miette!("--max-memory-gb must be positive, got {max}"));
    }
    let nodes = nx as u64 * ny as u64;
    let need = nodes * set.bytes_per_node(missing, preprocessed);
    let limit = max * 1e9;
    if (need as f64) <= limit {
        return Ok(());
    }
    let per_node = (limit / nodes.max(1) as f64) as u64;
    let fit = set.within(per_node, missing, preprocessed);
    let list: Vec<&str> = fit.params().iter().map(|p| p.symbol()).collect();
    let hint = if list.is_empty() {
        "raise --max-memory-gb or cut the map".to_string()
    } else {
        format!(
            "give --params {} (about {:.2} GB) or raise --max-memory-gb",
            list.join(","),
            (nodes * fit.bytes_per_node(missing, preprocessed)) as f64 / 1e9
        )
    };
    Err(miette!(
        "{file}: these parameters of {nx}×{ny} nodes need about {:.2} GB of memory, more than --max-memory-gb {max}: {hint}",
        need as f64 / 1e9
    ))
}
