//! The 3-D viewer: a height map or a part map as one self-contained HTML page (three.js, the
//! page's script and the data embedded; nothing is fetched when it is viewed).
//!
//! A height map is drawn as a shaded surface of at most [`DISPLAY_NODES`] nodes: the map is
//! block-averaged over `f × f` nodes, NaN-aware (a block's value is the mean of its valid
//! nodes, NaN when it has none), each block drawn at the centre of its nodes. The full map
//! (f64, as read) is embedded too when it has at most [`FULL_NODES`] nodes, and the profile
//! picked by two clicks is then taken from it exactly as `crest metrics --profile
//! line:X0,Y0,X1,Y1 --params Rz` takes it (same sampling, bilinear rule, mean line and five
//! sampling lengths, so the same Rz to the last bit; the page prints that command). A larger
//! map's profile is taken from the displayed block averages, and the page says so.
//!
//! A part map (`crest simulate --map-mm`, PLY) is drawn as a point cloud coloured by the
//! height along the normal; at most [`DISPLAY_POINTS`] points are drawn (every k-th).
//!
//! The key parameters are computed here by [`crate::metrics`] and embedded.

use crate::io::tables::json_number;
use crate::metrics::{self, ParamSet};
use crate::surface::{HeightMap, MapPoint};
use std::fmt::Write as _;

/// three.js, the parts the page uses bundled and minified (see `assets/viewer/NOTICE.md`).
const THREE_JS: &str = include_str!("../../assets/viewer/three.min.js");
/// The page's own script.
const VIEWER_JS: &str = include_str!("../../assets/viewer/viewer.js");
/// The page's style sheet.
const VIEWER_CSS: &str = include_str!("../../assets/viewer/viewer.css");

/// The version of three.js embedded in the page (npm `three`, MIT licence).
pub const THREE_VERSION: &str = "0.187.0";
/// Most nodes of the displayed surface.
pub const DISPLAY_NODES: usize = 90_000;
/// Most nodes of a map embedded at full resolution for the profile.
pub const FULL_NODES: usize = 1 << 20;
/// Most points of a part map drawn.
pub const DISPLAY_POINTS: usize = 400_000;

/// The areal parameters shown beside a height map.
const AREAL: &str = "Sa,Sq,Sp,Sv,Sz,Ssk,Sku,Sdq,Sdr";

/// What the page says about its data.
#[derive(Debug, Clone)]
pub struct ViewInfo {
    /// Title shown at the top of the page.
    pub title: String,
    /// Where the data came from (a file name, a command).
    pub source: String,
    /// The file holding exactly the embedded heights, if any: the page shows the `crest
    /// metrics FILE --profile line:…` command that reproduces a clicked profile's Rz.
    pub file: Option<String>,
}

/// The block factor that brings `nx × ny` nodes to at most `max_nodes`.
pub fn block_factor(nx: usize, ny: usize, max_nodes: usize) -> usize {
    let mut f = 1;
    while nx.div_ceil(f) * ny.div_ceil(f) > max_nodes.max(1) {
        f += 1;
    }
    f
}

/// A map block-averaged over `f × f` nodes (the last block of a row or column may be
/// smaller), NaN-aware, with the centre of each block's nodes, µm from node (0, 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Blocks {
    /// Blocks along x and y.
    pub nx: usize,
    /// Blocks along y.
    pub ny: usize,
    /// Block centres along x, µm.
    pub xs_um: Vec<f64>,
    /// Block centres along y, µm.
    pub ys_um: Vec<f64>,
    /// Mean of each block's valid heights, µm, rows of blocks y ascending (NaN: none valid).
    pub z_um: Vec<f64>,
}

/// Block-average `map` over `f × f` nodes (see [`Blocks`]).
pub fn block_average(map: &HeightMap, f: usize) -> Blocks {
    let f = f.max(1);
    let (bx, by) = (map.nx.div_ceil(f), map.ny.div_ceil(f));
    let centre = |k: usize, n: usize, d: f64| {
        let last = ((k + 1) * f).min(n) - 1;
        (k * f + last) as f64 / 2.0 * d
    };
    let mut z = vec![0.0; bx * by];
    let mut count = vec![0usize; bx * by];
    for r in 0..map.ny {
        for (c, &v) in map.row(r).iter().enumerate() {
            if v.is_finite() {
                let b = (r / f) * bx + c / f;
                z[b] += v;
                count[b] += 1;
            }
        }
    }
    for (v, &n) in z.iter_mut().zip(&count) {
        *v = if n == 0 { f64::NAN } else { *v / n as f64 };
    }
    Blocks {
        nx: bx,
        ny: by,
        xs_um: (0..bx).map(|k| centre(k, map.nx, map.dx_um)).collect(),
        ys_um: (0..by).map(|k| centre(k, map.ny, map.dy_um)).collect(),
        z_um: z,
    }
}

/// Why a viewer page could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// The parameters shown on the page could not be computed.
    #[error("{0}")]
    Parameters(String),
    /// A part map without points.
    #[error("the part map has no points")]
    NoPoints,
    /// The page of a regression's case.
    #[error("case {0}: {1}")]
    Case(usize, Box<ViewError>),
    /// A part map whose heights are all NaN.
    #[error("no point of the part map was reached (every height is NaN)")]
    NotReached,
}

/// The viewer page of a height map.
pub fn heightmap_page(map: &HeightMap, info: &ViewInfo) -> Result<String, ViewError> {
    let set = ParamSet::parse(AREAL, false).map_err(|e| ViewError::Parameters(e.to_string()))?;
    let params =
        metrics::areal_parameters(map, &set).map_err(|e| ViewError::Parameters(e.to_string()))?;
    let f = block_factor(map.nx, map.ny, DISPLAY_NODES);
    let blocks = block_average(map, f);
    let full = map.nx * map.ny <= FULL_NODES;
    let mut data = serde_json::json!({
        "kind": "heightmap",
        "title": info.title,
        "source": info.source,
        "file": info.file,
        "nx": map.nx,
        "ny": map.ny,
        "dx_um": map.dx_um,
        "dy_um": map.dy_um,
        "x0_mm": map.x0_mm,
        "y0_mm": map.y0_mm,
        "valid": map.known(),
        "factor": f,
        "display": {
            "nx": blocks.nx,
            "ny": blocks.ny,
            "xs_um": blocks.xs_um,
            "ys_um": blocks.ys_um,
            "z_f32": base64_f32(&blocks.z_um),
        },
        "params": params
            .iter()
            .map(|(p, v)| serde_json::json!([p.symbol(), json_number(*v), p.unit()]))
            .collect::<Vec<_>>(),
    });
    if full {
        data["full_f64"] = base64_f64(&map.z_um).into();
    }
    Ok(page(&info.title, &data))
}

/// The viewer page of a part map (a point cloud, heights along the normal).
pub fn part_map_page(points: &[MapPoint], info: &ViewInfo) -> Result<String, ViewError> {
    if points.is_empty() {
        return Err(ViewError::NoPoints);
    }
    let heights: Vec<f64> = points.iter().map(|p| p.height_um).collect();
    let stats = metrics::height_stats(&heights).ok_or(ViewError::NotReached)?;
    let stride = points.len().div_ceil(DISPLAY_POINTS).max(1);
    let shown: Vec<&MapPoint> = points.iter().step_by(stride).collect();
    let mut xyz = Vec::with_capacity(shown.len() * 3);
    let mut normals = Vec::with_capacity(shown.len() * 3);
    for p in &shown {
        xyz.extend([p.point.x, p.point.y, p.point.z]);
        normals.extend([p.normal.x, p.normal.y, p.normal.z]);
    }
    let h: Vec<f64> = shown.iter().map(|p| p.height_um).collect();
    let reached = 100.0 * stats.n as f64 / points.len() as f64;
    let data = serde_json::json!({
        "kind": "partmap",
        "title": info.title,
        "source": info.source,
        "points": points.len(),
        "stride": stride,
        "shown": shown.len(),
        "xyz_mm_f64": base64_f64(&xyz),
        "n_f32": base64_f32(&normals),
        "h_f32": base64_f32(&h),
        "params": [
            ["points reached", json_number(reached), "%"],
            ["mean height", json_number(stats.mean), "µm"],
            ["Sa (about the mean)", json_number(stats.sa), "µm"],
            ["Sq", json_number(stats.sq), "µm"],
            ["Sz (max − min)", json_number(stats.sz()), "µm"],
            ["lowest", json_number(stats.min), "µm"],
            ["highest", json_number(stats.max), "µm"],
        ],
    });
    Ok(page(&info.title, &data))
}

/// The viewer pages of a regression's simulated windows (`model = "simulate"`), one per
/// case, named `view-N.html` (N = the case's 1-based number); none for the crest model.
pub fn regression_pages(
    reg: &crate::study::compare::Regression,
) -> Result<Vec<(String, Vec<u8>)>, ViewError> {
    let mut out = Vec::new();
    for (i, c) in reg.cases.iter().enumerate() {
        let Some(z) = &c.zmap else { continue };
        let info = ViewInfo {
            title: format!(
                "case {}: lead {}°, {}, simulated window (Rz {:.4} µm on its centre row)",
                i + 1,
                c.lead_deg,
                c.side.name(),
                z.rz_um
            ),
            source: format!("{} case {}", reg.study_file, i + 1),
            file: None,
        };
        let html =
            heightmap_page(&z.map, &info).map_err(|e| ViewError::Case(i + 1, Box::new(e)))?;
        out.push((format!("view-{}.html", i + 1), html.into_bytes()));
    }
    Ok(out)
}

fn page(title: &str, data: &serde_json::Value) -> String {
    // No `<`, `>` or `&` in the data's script element (`</script>`, `<!--<script>` would
    // end it or switch the HTML parser's script state): written `\u003c`, `\u003e`,
    // `\u0026`, the same JSON (they occur only inside strings).
    let json = data
        .to_string()
        .replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026");
    let mut s = String::with_capacity(THREE_JS.len() + json.len() + VIEWER_JS.len() + 4096);
    let _ = write!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"generator\" content=\"crest {} with three.js {THREE_VERSION}\">\n\
         <title>{}</title>\n<style>{VIEWER_CSS}</style>\n</head>\n<body>\n",
        env!("CARGO_PKG_VERSION"),
        escape(title)
    );
    s.push_str(
        "<div id=\"app\"><div id=\"view\"><canvas id=\"gl\"></canvas>\
         <div id=\"hint\">drag: orbit · wheel: zoom · right- or shift-drag: pan · \
         click two points: profile</div></div>\
         <aside id=\"side\"><h1 id=\"title\"></h1><p id=\"source\"></p>\
         <div id=\"scale\"><canvas id=\"bar\" width=\"240\" height=\"18\"></canvas>\
         <div id=\"ticks\"></div><div id=\"unit\"></div></div>\
         <label id=\"exag-label\">vertical exaggeration <span id=\"exag-value\"></span>\
         <input id=\"exag\" type=\"range\" min=\"-1\" max=\"1\" step=\"0.01\" value=\"0\"></label>\
         <table id=\"params\"></table>\
         <div id=\"profile\"><h2>Profile</h2><p id=\"profile-text\"></p>\
         <canvas id=\"chart\" width=\"300\" height=\"150\"></canvas><p id=\"profile-cmd\"></p></div>\
         </aside></div>\n<pre id=\"crest-test\" hidden></pre>\n",
    );
    let _ = writeln!(
        s,
        "<script type=\"application/json\" id=\"crest-data\">{json}</script>"
    );
    // The error trap comes first so that any error of the library or the page is recorded.
    s.push_str(
        "<script>window.crestErrors=[];window.addEventListener('error',e=>crestErrors.push(String(e.message)));\
         window.addEventListener('unhandledrejection',e=>crestErrors.push(String(e.reason)));\
         (function(){const f=console.error;console.error=function(...a){crestErrors.push(a.map(String).join(' '));f.apply(console,a);};})();</script>\n",
    );
    let _ = write!(
        s,
        "<script>{THREE_JS}</script>\n<script>{VIEWER_JS}</script>\n"
    );
    s.push_str("</body>\n</html>\n");
    s
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn base64_f64(v: &[f64]) -> String {
    let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    base64(&bytes)
}

fn base64_f32(v: &[f64]) -> String {
    let bytes: Vec<u8> = v.iter().flat_map(|x| (*x as f32).to_le_bytes()).collect();
    base64(&bytes)
}

/// Standard base64 with padding (RFC 4648), what the browser's `atob` reads.
fn base64(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (raw, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(raw.as_bytes()), enc);
        }
    }

    #[test]
    fn block_average_skips_nan_and_centres_partial_blocks() {
        // 5 × 3 nodes at dx 2, dy 1; blocks of 2: 3 × 2 blocks, the last ones partial.
        let mut z: Vec<f64> = (0..15).map(f64::from).collect();
        z[0] = f64::NAN;
        let m = HeightMap::from_rows(5, 3, 2.0, 1.0, z).unwrap();
        let b = block_average(&m, 2);
        assert_eq!((b.nx, b.ny), (3, 2));
        assert_eq!(b.xs_um, vec![1.0, 5.0, 8.0]);
        assert_eq!(b.ys_um, vec![0.5, 2.0]);
        // Block (0, 0): nodes 1, 5, 6 (node 0 is NaN).
        assert_eq!(b.z_um[0], 4.0);
        // Block (2, 0): nodes 4 and 9; block (2, 1): node 14 alone.
        assert_eq!(b.z_um[2], 6.5);
        assert_eq!(b.z_um[5], 14.0);
        let all_nan = HeightMap::new_nan(3, 3, 1.0, 1.0);
        assert!(block_average(&all_nan, 2).z_um.iter().all(|v| v.is_nan()));
    }

    #[test]
    fn block_factor_bounds_the_node_count() {
        assert_eq!(block_factor(300, 300, 90_000), 1);
        assert_eq!(block_factor(301, 300, 90_000), 2);
        assert_eq!(block_factor(501, 301, 90_000), 2);
        let f = block_factor(4001, 3000, 90_000);
        assert!(4001usize.div_ceil(f) * 3000usize.div_ceil(f) <= 90_000);
        assert!(4001usize.div_ceil(f - 1) * 3000usize.div_ceil(f - 1) > 90_000);
    }

    #[test]
    fn page_embeds_data_library_and_escapes_the_title() {
        let z: Vec<f64> = (0..400).map(|k| ((k % 20) as f64 * 0.7).sin()).collect();
        let m = HeightMap::from_rows(20, 20, 1.0, 1.0, z).unwrap();
        let info = ViewInfo {
            title: "a </script> & b".into(),
            source: "test".into(),
            file: None,
        };
        let html = heightmap_page(&m, &info).unwrap();
        assert!(html.contains("<title>a &lt;/script&gt; &amp; b</title>"));
        assert!(html.contains("\"full_f64\""));
        // Nothing is fetched: no external script, style sheet or module.
        assert!(
            !html.contains("src=\"http") && !html.contains("<link") && !html.contains("import(")
        );
        // Only the page's own script elements close.
        assert_eq!(html.matches("</script>").count(), 4);
    }
}
