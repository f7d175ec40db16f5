//! The swept cutter against a reference written here, not by crest (issue 33): synthetic
//! NX-style 5-axis exports (rapids, approach and engage moves, lead-in and lead-out arcs
//! marked with `PAINT/COLOR` as NX writes them, zig-zag passes whose tool axis turns about
//! 25° along each pass) over a freeform surface with convex and concave stretches, and the
//! surface's STL. At points of the finishing region drawn from a seeded generator, crest's
//! heights of a cutter without feed marks (`--model swept` for the ball; for the bull nose
//! the dome model with one tooth every 0.02 mm) are compared node by node with the lower
//! envelope of the cutter body swept along the same postures, measured from the exact surface along the same
//! lines: from the reference crest derives from the path alone, with `--part` (the STL's
//! facet error included), and with the derived surface written by `crest contact -o
//! derived.stl` given as `--part`. Points on the arcs are refused. Ball end D6 and bull nose
//! D16 R4 (lead 3.5-10°).
//!
//! The reference: the cutter body at a pose is every point within the corner radius rc of
//! the disk of radius rd = R − rc about `tip + rc a` perpendicular to the axis a (a ball is
//! rd = 0). Between postures the tip moves on the line and the axis is interpolated, in steps
//! of at most 10 µm (ball) or 25 µm (bull nose). Along a node's line the material left is below the lowest point at
//! which any pose's body meets the line (the body is convex, so that point is found by a
//! golden-section search for the line's closest approach and a bisection below it). The
//! design surface is met by Newton's method on the closed form.

use crate::util::{crest, output_json, tempdir, write};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

type V = [f64; 3];

fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn mul(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: V) -> V {
    mul(a, 1.0 / dot(a, a).sqrt())
}

/// The design surface z = f(x, y): along x convex for x < 9π and concave after, along y
/// convex below y = 3.5π and concave above (radii of curvature down to about 33 mm).
fn f(x: f64, y: f64) -> f64 {
    2.0 * (x / 9.0).sin() + 1.5 * (y / 7.0).cos()
}
fn grad(x: f64, y: f64) -> (f64, f64) {
    (2.0 / 9.0 * (x / 9.0).cos(), -1.5 / 7.0 * (y / 7.0).sin())
}
fn normal(x: f64, y: f64) -> V {
    let (fx, fy) = grad(x, y);
    unit([-fx, -fy, 1.0])
}

/// Cut passes along x from 0 to `X_END` at y = `Y0` + k · stepover.
const X_END: f64 = 40.0;
const Y0: f64 = 7.0;
/// Cut postures every `DX` mm along a pass (as NX's chord tolerance would space them).
const DX: f64 = 0.25;

/// A cutter: radius and corner radius, mm, and how the path is made for it.
#[derive(Clone, Copy)]
struct Tool {
    name: &'static str,
    radius: f64,
    corner: f64,
    stepover: f64,
    passes: usize,
    /// Lead (degrees, towards the feed) at the start and the end of each pass.
    lead_deg: (f64, f64),
    /// Tilt (degrees, across the feed) at the start and the end of each pass.
    tilt_deg: (f64, f64),
    /// How crest simulates it: the swept ball, or for a torus (which `--model swept` does
    /// not know) the dome model imprinting one tooth every 0.02 mm (feed marks under
    /// 0.02 µm) with a chord tolerance of 0.05 µm.
    model: &'static [&'static str],
    /// Patch side (mm) and grid spacing (µm).
    patch_mm: f64,
    grid_um: f64,
    /// The reference's largest step between poses, mm.
    step_mm: f64,
}

const BALL: Tool = Tool {
    name: "ball",
    radius: 3.0,
    corner: 3.0,
    stepover: 0.5,
    passes: 17,
    lead_deg: (12.0, 2.0),
    tilt_deg: (-6.0, 6.0),
    model: &["--model", "swept", "--teeth", "2", "--rpm", "10000"],
    patch_mm: 1.0,
    grid_um: 25.0,
    step_mm: 0.010,
};

const BULL: Tool = Tool {
    name: "bull",
    radius: 8.0,
    corner: 4.0,
    stepover: 0.8,
    passes: 11,
    lead_deg: (3.5, 10.0),
    tilt_deg: (0.0, 0.0),
    model: &[
        "--model",
        "dome",
        "--teeth",
        "1",
        "--rpm",
        "75000",
        "--chord-tol-um",
        "0.05",
    ],
    patch_mm: 1.0,
    grid_um: 50.0,
    step_mm: 0.025,
};

/// A posture as the file holds it (rounded as written): tip and unit axis.
#[derive(Clone, Copy)]
struct Pose {
    tip: V,
    axis: V,
}

/// Round as `GOTO/…` writes: 4 decimals for the tip, 7 for the axis.
fn rounded(tip: V, axis: V) -> Pose {
    let r = |v: f64, d: f64| (v * d).round() / d + 0.0;
    Pose {
        tip: tip.map(|v| r(v, 1e4)),
        axis: unit(axis.map(|v| r(v, 1e7))),
    }
}

/// The cut postures of pass `k` in cutting order, and its feed direction (±x).
fn pass(tool: &Tool, k: usize) -> (Vec<Pose>, f64) {
    let y = Y0 + k as f64 * tool.stepover;
    let dir = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    let n_pts = (X_END / DX).round() as usize;
    let mut out = Vec::with_capacity(n_pts + 1);
    for i in 0..=n_pts {
        let s = i as f64 / n_pts as f64;
        let x = if dir > 0.0 {
            s * X_END
        } else {
            X_END - s * X_END
        };
        let (fx, _) = grad(x, y);
        let n = normal(x, y);
        let t = unit([dir, 0.0, dir * fx]);
        let b = cross(n, t);
        let lead = (tool.lead_deg.0 + s * (tool.lead_deg.1 - tool.lead_deg.0)).to_radians();
        let tilt = (tool.tilt_deg.0 + s * (tool.tilt_deg.1 - tool.tilt_deg.0)).to_radians();
        let a = unit(add(n, add(mul(t, lead.tan()), mul(b, tilt.tan()))));
        let cc = [x, y, f(x, y)];
        out.push(rounded(tip_of(tool, cc, n, a), a));
    }
    (out, dir)
}

/// The tip that puts the cutter on `cc` with surface normal `n` and axis `a`: the corner
/// centre is `cc + rc n`, the disk centre is that less rd along the radial of −n.
fn tip_of(tool: &Tool, cc: V, n: V, a: V) -> V {
    let rc = tool.corner;
    let rd = tool.radius - rc;
    let o = add(cc, mul(n, rc));
    let m = sub(mul(a, dot(n, a)), n);
    let w = if dot(m, m).sqrt() > 1e-12 {
        unit(m)
    } else {
        [0.0; 3]
    };
    sub(sub(o, mul(w, rd)), mul(a, rc))
}

/// An arc of `ARC_GOTOS` points from the tip `p` (θ = 0) back along −`t` and up along `n`
/// to θ = 90° (radius `ARC_R`), in the order given.
const ARC_R: f64 = 3.0;
const ARC_GOTOS: usize = 8;
/// Each point with whether it is on the upper half of the arc (θ ≥ 45°, 0.9 mm and more
/// above the tip).
fn arc(p: V, t: V, n: V, down: bool) -> Vec<(V, bool)> {
    (0..=ARC_GOTOS)
        .map(|j| {
            let deg = 90.0 * j as f64 / ARC_GOTOS as f64;
            let th = if down { 90.0 - deg } else { deg };
            let r = th.to_radians();
            let q = add(
                p,
                add(mul(t, ARC_R * r.sin()), mul(n, ARC_R * (1.0 - r.cos()))),
            );
            (q, th >= 45.0)
        })
        .collect()
}

fn goto(s: &mut String, p: Pose) {
    let _ = writeln!(
        s,
        "GOTO/{:.4},{:.4},{:.4},{:.7},{:.7},{:.7}",
        p.tip[0], p.tip[1], p.tip[2], p.axis[0], p.axis[1], p.axis[2]
    );
}

/// The export as NX writes a variable-contour operation: rapid (186), per pass an
/// approach rapid (211), an engage arc (42) at 500 mm/min, the cut (31) at 1500 mm/min, a
/// retract arc (37) at 500 mm/min; a departure (211) at the end. Returns the text, the cut
/// postures of each pass and the arcs' points.
fn export(tool: &Tool) -> (String, Vec<Vec<Pose>>, Vec<V>) {
    let mut s = format!(
        "TOOL PATH/VARIABLE_CONTOUR,TOOL,{}\nTLDATA/MILL,{:.4},{:.4},60.0000,0.0000,0.0000\n$$ centerline data\nPAINT/PATH\nPAINT/SPEED,10\nLOAD/TOOL,1,ADJUST,1\nSELECT/TOOL,1\nPAINT/COLOR,186\nRAPID\nGOTO/0.0000,0.0000,40.0000,0.0000000,0.0000000,1.0000000\n",
        tool.name.to_uppercase(),
        2.0 * tool.radius,
        tool.corner
    );
    let mut cuts = Vec::new();
    let mut arcs = Vec::new();
    for k in 0..tool.passes {
        let (poses, dir) = pass(tool, k);
        let (first, last) = (poses[0], poses[poses.len() - 1]);
        let t_in = unit(sub(poses[1].tip, first.tip));
        let t_out = unit(sub(last.tip, poses[poses.len() - 2].tip));
        let up = |p: &Pose| unit(cross(cross([dir, 0.0, 0.0], p.axis), [dir, 0.0, 0.0]));
        let engage = arc(first.tip, mul(t_in, -1.0), up(&first), true);
        let retract = arc(last.tip, t_out, up(&last), false);
        s.push_str("PAINT/COLOR,211\nRAPID\n");
        let above = add(engage[0].0, [0.0, 0.0, 10.0]);
        goto(&mut s, rounded(above, first.axis));
        goto(&mut s, rounded(engage[0].0, first.axis));
        s.push_str("PAINT/COLOR,42\nFEDRAT/MMPM,500.0000\n");
        for &(p, high) in &engage[1..engage.len() - 1] {
            goto(&mut s, rounded(p, first.axis));
            if high {
                arcs.push(p);
            }
        }
        s.push_str("PAINT/COLOR,31\nFEDRAT/MMPM,1500.0000\n");
        for p in &poses {
            goto(&mut s, *p);
        }
        s.push_str("PAINT/COLOR,37\nFEDRAT/MMPM,500.0000\n");
        for &(p, high) in &retract[1..] {
            goto(&mut s, rounded(p, last.axis));
            if high {
                arcs.push(p);
            }
        }
        s.push_str("PAINT/COLOR,211\nRAPID\n");
        let above = add(retract[retract.len() - 1].0, [0.0, 0.0, 10.0]);
        goto(&mut s, rounded(above, last.axis));
        cuts.push(poses);
    }
    s.push_str("PAINT/SPEED,10\nPAINT/TOOL,NOMORE\nEND-OF-PATH\n");
    (s, cuts, arcs)
}

/// The surface as a binary STL over the passes and 3 mm around, facets of 0.1 mm (facet
/// error under 0.05 µm at these curvatures).
fn stl(tool: &Tool) -> Vec<u8> {
    let (x0, x1) = (-3.0, X_END + 3.0);
    let (y0, y1) = (
        Y0 - 3.0,
        Y0 + (tool.passes - 1) as f64 * tool.stepover + 3.0,
    );
    let h = 0.1;
    let nx = ((x1 - x0) / h).round() as usize;
    let ny = ((y1 - y0) / h).round() as usize;
    let p = |i: usize, j: usize| {
        let (x, y) = (x0 + i as f64 * h, y0 + j as f64 * h);
        [x, y, f(x, y)]
    };
    let mut out = vec![0u8; 80];
    out.extend_from_slice(&((2 * nx * ny) as u32).to_le_bytes());
    let mut tri = |a: V, b: V, c: V| {
        let n = unit(cross(sub(b, a), sub(c, a)));
        for v in [n, a, b, c] {
            for x in v {
                out.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    };
    for j in 0..ny {
        for i in 0..nx {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            tri(a, b, c);
            tri(a, c, d);
        }
    }
    out
}

/// Distance from `p` to the cutter's core disk at `pose` (the body is where this is at
/// most rc).
fn core_distance(tool: &Tool, pose: &Pose, p: V) -> f64 {
    let rc = tool.corner;
    let rd = tool.radius - rc;
    let c = add(pose.tip, mul(pose.axis, rc));
    let d = sub(p, c);
    let h = dot(d, pose.axis);
    let rho = (dot(d, d) - h * h).max(0.0).sqrt();
    if rho <= rd {
        h.abs()
    } else {
        ((rho - rd).powi(2) + h * h).sqrt()
    }
}

/// Every pose the reference sweeps: the cut postures, with the tip on the line between
/// neighbours and the axis interpolated, at most `step` apart.
fn swept_poses(cuts: &[Vec<Pose>], step: f64) -> Vec<Pose> {
    let mut out = Vec::new();
    for pass in cuts {
        for w in pass.windows(2) {
            let len = dot(sub(w[1].tip, w[0].tip), sub(w[1].tip, w[0].tip)).sqrt();
            let steps = (len / step).ceil().max(1.0) as usize;
            for s in 0..steps {
                let t = s as f64 / steps as f64;
                out.push(Pose {
                    tip: add(w[0].tip, mul(sub(w[1].tip, w[0].tip), t)),
                    axis: unit(add(mul(w[0].axis, 1.0 - t), mul(w[1].axis, t))),
                });
            }
        }
        out.push(pass[pass.len() - 1]);
    }
    out
}

/// The lowest t at which the body at `pose` meets the line `p + t w`, if it does.
fn lowest_meet(tool: &Tool, pose: &Pose, p: V, w: V) -> Option<f64> {
    let c = add(pose.tip, mul(pose.axis, tool.corner));
    let t_c = dot(sub(c, p), w);
    if tool.corner >= tool.radius {
        // A ball: the sphere about c.
        let d = sub(c, p);
        let lateral2 = dot(d, d) - t_c * t_c;
        let r2 = tool.radius * tool.radius;
        return (lateral2 <= r2).then(|| t_c - (r2 - lateral2).sqrt());
    }
    let reach = tool.radius;
    let d = |t: f64| core_distance(tool, pose, add(p, mul(w, t)));
    // Closest approach (the distance is convex along the line).
    let (mut a, mut b) = (t_c - reach, t_c + reach);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (d(x1), d(x2));
    for _ in 0..48 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = d(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = d(x2);
        }
    }
    let t_min = 0.5 * (a + b);
    if d(t_min) > tool.corner {
        return None;
    }
    let (mut lo, mut hi) = (t_c - reach - tool.corner, t_min);
    for _ in 0..44 {
        let mid = 0.5 * (lo + hi);
        if d(mid) > tool.corner {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(hi)
}

/// Where the line `p + t w` meets the design surface (Newton from t = 0).
fn surface_t(p: V, w: V) -> f64 {
    let mut t = 0.0;
    for _ in 0..50 {
        let q = add(p, mul(w, t));
        let g = q[2] - f(q[0], q[1]);
        let (fx, fy) = grad(q[0], q[1]);
        let dg = w[2] - fx * w[0] - fy * w[1];
        let step = g / dg;
        t -= step;
        if step.abs() < 1e-13 {
            break;
        }
    }
    t
}

/// The reference height (µm) at the node line `p + t w`: the material left, from the
/// surface along the line; `None` where no pose reaches the line.
fn reference_um(tool: &Tool, poses: &[Pose], p: V, w: V) -> Option<f64> {
    let ts = surface_t(p, w);
    let (rc, rd) = (tool.corner, tool.radius - tool.corner);
    // The poses that can meet the line (the body lies within R of its disk centre), each
    // with a lower bound of where it can: the body reaches below its disk centre along w by
    // at most rc + rd·|w × a|. They are tried from the lowest bound up.
    let mut near: Vec<(f64, &Pose)> = poses
        .iter()
        .filter_map(|pose| {
            let c = add(pose.tip, mul(pose.axis, rc));
            let d = sub(c, p);
            let along = dot(d, w);
            let lateral2 = dot(d, d) - along * along;
            let aw = dot(pose.axis, w);
            let bound = along - rc - rd * (1.0 - aw * aw).max(0.0).sqrt();
            (lateral2 <= tool.radius * tool.radius).then_some((bound, pose))
        })
        .collect();
    near.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::INFINITY;
    for (bound, pose) in near {
        if bound >= best {
            break;
        }
        if let Some(t) = lowest_meet(tool, pose, p, w) {
            best = best.min(t);
        }
    }
    best.is_finite().then_some((best - ts) * 1e3)
}

/// A seeded generator (SplitMix64) for the points: the same points on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The number of points and the seed: `CREST_SWEPT_POINTS` and `CREST_SWEPT_SEED` override
/// them (to try more points than the suite does).
fn points_and_seed(default: usize) -> (usize, u64) {
    let n = std::env::var("CREST_SWEPT_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default);
    let seed = std::env::var("CREST_SWEPT_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(33);
    (n, seed)
}

struct Files {
    _dir: tempfile::TempDir,
    cls: PathBuf,
    stl: PathBuf,
    cuts: Vec<Vec<Pose>>,
    arcs: Vec<V>,
}

fn files(tool: &Tool) -> Files {
    let dir = tempdir();
    let (text, cuts, arcs) = export(tool);
    let cls = write(dir.path(), &format!("{}.cls", tool.name), text);
    let stl = write(dir.path(), &format!("{}.stl", tool.name), stl(tool));
    // To look at the files: CREST_SWEPT_KEEP=DIR copies them there.
    if let Ok(keep) = std::env::var("CREST_SWEPT_KEEP") {
        for f in [&cls, &stl] {
            let to = Path::new(&keep).join(f.file_name().unwrap_or_default());
            std::fs::copy(f, to).unwrap_or_else(|e| panic!("{e}"));
        }
    }
    Files {
        _dir: dir,
        cls,
        stl,
        cuts,
        arcs,
    }
}

/// crest's swept heights on a patch near `at`: (exit code, JSON, heights by row, stderr).
fn simulate(
    tool: &Tool,
    cls: &Path,
    at: V,
    extra: &[&str],
) -> (i32, serde_json::Value, Vec<Vec<f64>>, String) {
    let dir = cls.parent().unwrap_or_else(|| panic!("parent"));
    let out_csv = dir.join("patch.csv");
    let _ = std::fs::remove_file(&out_csv);
    let out = crest()
        .arg("simulate")
        .arg(cls)
        .args(tool.model)
        .args(["--grid-um", &tool.grid_um.to_string()])
        .args(["--patch-mm", &format!("{0},{0}", tool.patch_mm)])
        .args(["--patch-near", &format!("{},{},{}", at[0], at[1], at[2])])
        .arg("-o")
        .arg(&out_csv)
        .arg("--json")
        .args(extra)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let code = out.status.code().unwrap_or(-1);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if code != 0 {
        return (code, serde_json::Value::Null, Vec::new(), stderr);
    }
    let j = output_json(&out);
    let text = std::fs::read_to_string(&out_csv).unwrap_or_else(|e| panic!("{e}"));
    let rows = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse::<f64>().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    (code, j, rows, stderr)
}

fn v3(j: &serde_json::Value) -> V {
    let a = |i: usize| j[i].as_f64().unwrap_or_else(|| panic!("not a vector: {j}"));
    [a(0), a(1), a(2)]
}

/// The largest |crest − reference| over every node of a patch near `at` (µm), and the
/// number of nodes compared. Every node crest reached must be reached by the reference
/// and the other way round.
fn worst_difference(
    tool: &Tool,
    fl: &Files,
    poses: &[Pose],
    at: V,
    extra: &[&str],
) -> (f64, usize) {
    let (code, j, rows, stderr) = simulate(tool, &fl.cls, at, extra);
    assert_eq!(code, 0, "{} at {at:?} {extra:?}: {stderr}", tool.name);
    let origin = v3(&j["origin"]["wcs_mm"]);
    let (u, v, w) = (
        v3(&j["origin"]["u"]),
        v3(&j["origin"]["v"]),
        v3(&j["origin"]["w"]),
    );
    let dx = j["dx_um"].as_f64().unwrap_or(f64::NAN) * 1e-3;
    let dy = j["dy_um"].as_f64().unwrap_or(f64::NAN) * 1e-3;
    let (nx, ny) = (
        j["nx"].as_u64().unwrap_or(0) as usize,
        j["ny"].as_u64().unwrap_or(0) as usize,
    );
    assert_eq!(rows.len(), ny, "rows");
    let mut worst = 0.0f64;
    let mut compared = 0;
    for (r, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), nx, "columns");
        for (c, &h) in row.iter().enumerate() {
            let p = add(origin, add(mul(u, c as f64 * dx), mul(v, r as f64 * dy)));
            let want = reference_um(tool, poses, p, w);
            match want {
                Some(want) => {
                    assert!(
                        h.is_finite(),
                        "{} at {at:?} {extra:?}: node ({c}, {r}) not reached by crest, reference {want:.3} µm",
                        tool.name
                    );
                    worst = worst.max((h - want).abs());
                    compared += 1;
                }
                None => assert!(
                    !h.is_finite(),
                    "{} at {at:?}: node ({c}, {r}) not reached by the reference, crest {h}",
                    tool.name
                ),
            }
        }
    }
    (worst, compared)
}

/// Random points of the finishing region, away from the pass ends and the outer passes.
fn finishing_points(tool: &Tool, n: usize, seed: u64) -> Vec<V> {
    let mut rng = Rng(seed);
    let y_span = (tool.passes - 1) as f64 * tool.stepover;
    let margin_y = 2.0 * tool.stepover + 1.0;
    (0..n)
        .map(|_| {
            let x = 8.0 + rng.next() * (X_END - 16.0);
            let y = Y0 + margin_y + rng.next() * (y_span - 2.0 * margin_y);
            [x, y, f(x, y)]
        })
        .collect()
}

fn check_tool(tool: &Tool, default_points: usize, derived_tol: f64, part_tol: f64) {
    let fl = files(tool);
    let poses = swept_poses(&fl.cuts, tool.step_mm);
    let (n, seed) = points_and_seed(default_points);
    let part = fl.stl.display().to_string();
    // The surface crest derives, written as a mesh by `crest contact -o`, given as --part.
    let mesh = fl.cls.with_file_name("derived.stl");
    let out = crest()
        .arg("contact")
        .arg(&fl.cls)
        .args(["--teeth", "1", "--json", "-o"])
        .arg(&mesh)
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    let j = output_json(&out);
    assert!(
        j["triangles"].as_u64().unwrap_or(0) > 1000,
        "{}: {j}",
        tool.name
    );
    let mesh = mesh.display().to_string();
    // The derived mesh is flat between passes: its facets lie off the surface by up to the
    // chord error κ s² / 8 across a stepover s at the largest curvature κ (1.5/49 mm⁻¹ across
    // the passes here), on top of the derived reference's own error.
    let kappa = 1.5 / 49.0;
    let mesh_tol = derived_tol + kappa * tool.stepover.powi(2) / 8.0 * 1e3;
    let mut report = String::new();
    let mut failed = false;
    for at in finishing_points(tool, n, seed) {
        let (derived, nodes) = worst_difference(tool, &fl, &poses, at, &[]);
        let (with_part, _) = worst_difference(tool, &fl, &poses, at, &["--part", &part]);
        let (with_mesh, _) = worst_difference(tool, &fl, &poses, at, &["--part", &mesh]);
        let _ = writeln!(
            report,
            "{} at ({:.3}, {:.3}, {:.3}): {nodes} nodes, worst derived {derived:.3} µm, with --part {with_part:.3} µm, with the derived surface's STL {with_mesh:.3} µm",
            tool.name, at[0], at[1], at[2]
        );
        failed |= derived > derived_tol || with_part > part_tol || with_mesh > mesh_tol;
    }
    eprint!("{report}");
    assert!(
        !failed,
        "{}: heights off the reference by more than {derived_tol} µm (derived), {mesh_tol:.3} µm (its STL) or {part_tol} µm (--part):\n{report}",
        tool.name
    );
    // A point on an engage or retract arc, 1-3 mm above the surface, is refused.
    let mut rng = Rng(seed ^ 0xA5);
    for _ in 0..2 {
        let p = fl.arcs[(rng.next() * fl.arcs.len() as f64) as usize % fl.arcs.len()];
        let (code, _, _, stderr) = simulate(tool, &fl.cls, p, &[]);
        assert_eq!(
            code, 2,
            "{}: a patch on an arc at {p:?}: {stderr}",
            tool.name
        );
        assert!(
            stderr.contains("mm from the surface") && stderr.contains("in the air"),
            "{}: the refusal names no distance: {stderr}",
            tool.name
        );
    }
}

#[test]
fn swept_ball_on_a_freeform_5_axis_export_matches_the_reference() {
    check_tool(&BALL, 4, 0.5, 0.3);
}

#[test]
fn swept_bull_nose_on_a_freeform_5_axis_export_matches_the_reference() {
    check_tool(&BULL, 4, 0.5, 0.3);
}
