//! Run-out identification that reproduces itself (issue 34 §4): profiles simulated from a
//! known run-out with crest's own forward model (ball R 5 mm, helix 0, fz 0.05 mm, the
//! marks' normal deviations of `tool::normal_deviation_mm`, arcs of radius R + Δ_j as in
//! `study::regression::crest_model`), resampled at irregular 2-6 µm steps with white noise of
//! 5 % of Rz (standard deviation), identified, the `[runout]` table written into a
//! `tool.toml`, read back and re-simulated.
//!
//! What is asserted, and when ("identifiable", decided from the truth, not from the
//! identification):
//!
//! * always: the re-simulated Rz within 5 % of the profile's, both noise-free and evaluated
//!   alike (five sampling lengths of the profile's λc as `crest_model` chooses it, averaged
//!   over where the sections start);
//! * the teeth that cut, exactly (as a pattern in cutting order: a profile cannot tell which
//!   physical tooth is tooth 1), and the written tool cutting with the same teeth, when
//!   every tooth's margin is at least [`MARGIN_OF_RZ`] of Rz (a cutting tooth reaches that
//!   far below the envelope of the others, a silent one stays that far above it: a tooth
//!   that cuts by a hair under noise of 5 % of Rz is not told from one that touches), unless
//!   the identified pattern explains the noisy profile at least as well as the true run-out
//!   does (then the profile cannot tell the two apart: a shallow tooth trimming the crest of
//!   a wide gap from one mark position or the next);
//! * offset within 5 % and phase within 5° when, besides, at least three teeth cut at a lead
//!   of 15° or more (with fewer, the levels cannot separate an offset from per-tooth
//!   deviations; at lead 0 a radial offset does not move the surface).

use crest::math::rng::Rng;
use crest::study::identify::{Identification, identify, identify_profiles};
use crest::study::identify_fit::{Marks, margins};
use crest::study::measured::Side;
use crest::study::regression::crest_model;
use crest::tool::{
    Cutter, FeedProfile, Rule, Shape, generating_height_mm, mark_positions_mm, normal_deviation_mm,
};

const R: f64 = 5.0;
const FZ: f64 = 0.05;
/// Margin of every tooth, as a fraction of Rz, for the cutting teeth to be identifiable.
const MARGIN_OF_RZ: f64 = 0.05;
/// Length of a profile, mm.
const LENGTH_MM: f64 = 8.0;

struct Truth {
    cutter: Cutter,
    /// Normal deviation Δ_j, mm.
    dev: Vec<f64>,
    pos: Vec<f64>,
    cuts: Vec<bool>,
    rz_um: f64,
    /// The sampling length crest_model evaluates Rz over (ISO 4288 from the marks' RSm), mm.
    lambda_c_mm: f64,
    lead_deg: f64,
    /// Smallest margin over the teeth, mm (infinite when one tooth cuts alone and no other
    /// comes near).
    margin_mm: f64,
}

fn truth(teeth: usize, e_um: f64, phase_deg: f64, lead_deg: f64) -> Truth {
    let mut cutter = Cutter::new(Shape::Ball, R, teeth, 0.0);
    cutter.runout.offset_mm = e_um * 1e-3;
    cutter.runout.offset_phase_rad = phase_deg.to_radians();
    surface_of(cutter, lead_deg)
}

/// The marks, the teeth that cut and Rz of `cutter` at `lead_deg`.
fn surface_of(cutter: Cutter, lead_deg: f64) -> Truth {
    let teeth = cutter.teeth();
    let lead = lead_deg.to_radians();
    let zc = generating_height_mm(&cutter, lead);
    let dev: Vec<f64> = (0..teeth)
        .map(|j| normal_deviation_mm(&cutter, j, zc, lead))
        .collect();
    let pos = mark_positions_mm(&cutter, FZ);
    let a = crest::tool::analyse(&cutter, lead_deg, 0.4, FZ, Rule::Exact).unwrap();
    let cuts: Vec<bool> = a.teeth.iter().map(|t| t.participates_exact).collect();
    let model = crest_model(&cutter, lead_deg, 0.4, FZ, Rule::Exact, Side::Plane, None).unwrap();
    let (rz_um, lambda_c_mm) = (model.rz_um, model.sampling_length_mm);
    let marks = Marks {
        profile: FeedProfile::Circle { radius_mm: R },
        pos_mm: pos.clone(),
        period_mm: teeth as f64 * FZ,
        span_mm: FZ,
    };
    let levels: Vec<f64> = dev.iter().map(|d| -d).collect();
    let margin_mm = margins(&marks, &levels, &cuts)
        .into_iter()
        .flatten()
        .fold(f64::INFINITY, f64::min);
    Truth {
        cutter,
        dev,
        pos,
        cuts,
        rz_um,
        lambda_c_mm,
        lead_deg,
        margin_mm,
    }
}

/// The surface height at `x` (mm): the lowest mark, each an arc of radius R + Δ_j lowered
/// by Δ_j.
fn height_mm(t: &Truth, x: f64) -> f64 {
    let p = t.pos.len() as f64 * FZ;
    let mut best = f64::INFINITY;
    for (j, (&c, &d)) in t.pos.iter().zip(&t.dev).enumerate() {
        let _ = j;
        let k = ((x - c) / p).floor();
        for kk in [k - 1.0, k, k + 1.0, k + 2.0] {
            let u = x - c - kk * p;
            let rr = R + d;
            if u.abs() < rr {
                best = best.min(u * u / (rr + (rr * rr - u * u).sqrt()) - d);
            }
        }
    }
    best
}

/// Rz (µm) of the surface `t` over five sampling lengths of `lambda_c_mm`, sampled every
/// 0.25 µm, averaged over 12 starts across one revolution's feed. The profile and its
/// re-simulation are judged over the same evaluation: with crest_model's own choice a tooth
/// more or less changes the mark spacing and so λc, and a sampling length shorter than the
/// revolution makes Rz depend on where the sections start against the marks (the written
/// tool puts its tooth 1 elsewhere than the truth's).
fn rz_over(t: &Truth, lambda_c_mm: f64) -> f64 {
    let p = t.pos.len() as f64 * FZ;
    let n = (5.0 * lambda_c_mm / 0.00025).round() as usize;
    let starts = 12;
    (0..starts)
        .map(|s| {
            let x0 = p * s as f64 / starts as f64;
            let h: Vec<f64> = (0..=n)
                .map(|i| height_mm(t, x0 + i as f64 * 0.00025) * 1e3)
                .collect();
            crest::metrics::rz_ra(&h).0
        })
        .sum::<f64>()
        / starts as f64
}

/// A profile of `revs` revolutions from `x_start`, at irregular 2-6 µm steps, with white
/// noise of 5 % of Rz.
fn profile(t: &Truth, rng: &mut Rng, x_start: f64, revs: f64) -> (Vec<f64>, Vec<f64>) {
    let p = t.pos.len() as f64 * FZ;
    let sigma = 0.05 * t.rz_um;
    let (mut xs, mut zs) = (Vec::new(), Vec::new());
    let mut x = x_start;
    while x < x_start + revs * p {
        xs.push(x);
        zs.push(height_mm(t, x) * 1e3 + sigma * rng.normal());
        x += 0.002 + 0.004 * rng.uniform();
    }
    (xs, zs)
}

/// RMS of the noisy profile about the true surface, µm.
fn residual_of(t: &Truth, xs: &[f64], zs: &[f64]) -> f64 {
    let s: f64 = xs
        .iter()
        .zip(zs)
        .map(|(x, z)| (z - height_mm(t, *x) * 1e3).powi(2))
        .sum();
    (s / xs.len() as f64).sqrt()
}

/// The tool written by `--write-tool` for `id`, read back.
fn written(id: &Identification, teeth: usize, helix_deg: f64) -> Cutter {
    let base =
        format!("shape = \"ball\"\nradius_mm = {R}\nteeth = {teeth}\nhelix_deg = {helix_deg}\n");
    let offset = id.runout.offset_um.zip(id.runout.offset_phase_deg);
    let text =
        crest::config::tool::with_runout(&base, offset, &id.runout.tooth_radius_deviation_um);
    crest::config::tool::load_tool_toml(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// The rotation r (identified tooth k = true tooth r + k) that best matches the identified
/// pattern and levels.
fn rotation(t: &Truth, id: &Identification) -> usize {
    let nt = t.dev.len();
    let cuts = &id.identifiable.tooth_deviation;
    let cost = |r: usize| -> f64 {
        (0..nt)
            .map(|k| {
                let j = (r + k) % nt;
                let miss = if cuts[k] != t.cuts[j] { 1.0 } else { 0.0 };
                let level = if cuts[k] && t.cuts[j] {
                    let want = (t.dev[j] - t.dev[r]) * 1e3;
                    (want - id.tooth_deviation_um[k]).powi(2)
                } else {
                    0.0
                };
                miss * 1e3 + level
            })
            .sum()
    };
    (0..nt)
        .min_by(|&a, &b| cost(a).total_cmp(&cost(b)))
        .unwrap()
}

#[derive(Default, Debug)]
struct Seen {
    cases: usize,
    teeth_asserted: usize,
    offset_asserted: usize,
}

/// Check one case whose true run-out leaves the residual `residual_true_um` on the noisy
/// profile; returns (teeth asserted, offset asserted).
fn check(t: &Truth, id: &Identification, residual_true_um: f64, what: &str) -> (bool, bool) {
    let nt = t.dev.len();
    let re = written(id, nt, t.cutter.helix_rad.to_degrees());
    let rz_re = rz_over(&surface_of(re.clone(), t.lead_deg), t.lambda_c_mm);
    let rz = rz_over(t, t.lambda_c_mm);
    assert!(
        (rz_re / rz - 1.0).abs() < 0.05,
        "{what}: re-simulated Rz {rz_re} against the profile's {rz} (margin {} µm)\n{id:#?}",
        t.margin_mm * 1e3
    );
    let teeth_ok = t.margin_mm >= MARGIN_OF_RZ * t.rz_um * 1e-3;
    if !teeth_ok {
        return (false, false);
    }
    let r = rotation(t, id);
    let want: Vec<bool> = (0..nt).map(|k| t.cuts[(r + k) % nt]).collect();
    if id.identifiable.tooth_deviation != want && id.residual_um <= residual_true_um {
        // Another pattern explains the profile at least as well as the truth: the profile
        // cannot tell them apart (a shallow tooth trimming the crest of a wide gap from one
        // mark position or the next), so the teeth are not identifiable here.
        return (false, false);
    }
    assert_eq!(
        id.identifiable.tooth_deviation,
        want,
        "{what}: teeth that cut (margin {} µm)\n{id:#?}",
        t.margin_mm * 1e3
    );
    // The written tool cuts with the same teeth.
    let a = crest::tool::analyse(&re, t.lead_deg, 0.4, FZ, Rule::Exact).unwrap();
    let re_cuts: Vec<bool> = a.teeth.iter().map(|t| t.participates_exact).collect();
    assert_eq!(
        re_cuts, want,
        "{what}: the written tool's cutting teeth\n{id:#?}"
    );
    let ncut = t.cuts.iter().filter(|c| **c).count();
    if ncut < 3 || t.lead_deg < 15.0 {
        return (true, false);
    }
    let e_true = t.cutter.runout.offset_mm * 1e3;
    let e = id
        .offset_um
        .unwrap_or_else(|| panic!("{what}: offset not identified\n{id:#?}"));
    assert!(
        (e / e_true - 1.0).abs() < 0.05,
        "{what}: offset {e} µm against {e_true}\n{id:#?}"
    );
    // True phase in the identified labels: φ + pitch of the true tooth that is tooth 1.
    let phase_true = (t.cutter.runout.offset_phase_rad + t.cutter.pitch_rad[r]).to_degrees();
    let phase = id.phase_deg.unwrap();
    let diff = (phase - phase_true + 540.0).rem_euclid(360.0) - 180.0;
    assert!(
        diff.abs() < 5.0,
        "{what}: phase {phase}° against {phase_true}°\n{id:#?}"
    );
    (true, true)
}

/// The grid: 2, 3, 4 and 6 teeth; offsets 0.3-20 µm at seeded random phases; leads 0, 15
/// and 30°; irregular sampling and noise of 5 % of Rz.
#[test]
fn identification_reproduces_itself_over_the_grid() {
    let mut rng = Rng::new(
        std::env::var("RUNOUT_GRID_SEED")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(34),
    );
    let mut seen = std::collections::BTreeMap::<usize, Seen>::new();
    let mut failed = Vec::new();
    for teeth in [2usize, 3, 4, 6] {
        for e_um in [0.3, 0.6, 2.0, 5.0, 10.0, 20.0] {
            for lead_deg in [0.0, 15.0, 30.0] {
                for _ in 0..2 {
                    let phase_deg = 360.0 * rng.uniform();
                    let t = truth(teeth, e_um, phase_deg, lead_deg);
                    let start = 0.1 + rng.uniform();
                    let (xs, zs) = profile(&t, &mut rng, start, LENGTH_MM / (teeth as f64 * FZ));
                    let id = identify(
                        &xs,
                        &zs,
                        &Cutter::new(Shape::Ball, R, teeth, 0.0),
                        FZ,
                        lead_deg,
                    )
                    .unwrap();
                    let what = format!(
                        "Z {teeth}, e {e_um} µm at {phase_deg:.1}°, lead {lead_deg}° (cut {:?})",
                        t.cuts
                    );
                    let residual_true = residual_of(&t, &xs, &zs);
                    let Ok((a, b)) =
                        std::panic::catch_unwind(|| check(&t, &id, residual_true, &what))
                    else {
                        failed.push(what);
                        continue;
                    };
                    let s = seen.entry(teeth).or_default();
                    s.cases += 1;
                    s.teeth_asserted += usize::from(a);
                    s.offset_asserted += usize::from(b);
                }
            }
        }
    }
    eprintln!("{seen:?}");
    assert!(
        failed.is_empty(),
        "{} cases failed:\n{}",
        failed.len(),
        failed.join("\n")
    );
    for teeth in [2usize, 3, 4, 6] {
        let s = &seen[&teeth];
        assert!(s.teeth_asserted * 2 >= s.cases, "Z {teeth}: {s:?}");
        if teeth >= 3 {
            assert!(s.offset_asserted >= 3, "Z {teeth}: {s:?}");
        }
    }
}

/// The issue's two cases (4 teeth, lead 15°, phase 20°): 10 µm (one tooth cuts) and 0.6 µm
/// (all four cut); marks 0.05 mm apart are reported as such.
#[test]
fn the_issue_cases_reproduce_themselves() {
    let mut rng = Rng::new(7);
    for (e_um, ncut) in [(10.0, 1usize), (0.6, 4)] {
        let t = truth(4, e_um, 20.0, 15.0);
        assert_eq!(t.cuts.iter().filter(|c| **c).count(), ncut);
        let (xs, zs) = profile(&t, &mut rng, 0.0, 20.0);
        let id = identify(&xs, &zs, &Cutter::new(Shape::Ball, R, 4, 0.0), FZ, 15.0).unwrap();
        let what = format!("e {e_um}");
        check(&t, &id, residual_of(&t, &xs, &zs), &what);
        assert_eq!(id.teeth_cutting.len(), ncut, "{id:#?}");
        assert!((id.revolution_mm - 0.2).abs() < 1e-12);
        assert!(
            (id.mark_spacing_mm - 0.2 / ncut as f64).abs() < 1e-12,
            "{id:#?}"
        );
        assert!((id.period_mm - 0.2).abs() < 1e-12, "{id:#?}");
    }
}

/// With a helix the phase is still `offset_phase_deg`'s: the helix lag at the generating
/// height is taken out, so the written tool (with the same helix) gives the same marks.
#[test]
fn the_phase_takes_the_helix_lag_out() {
    let mut rng = Rng::new(5);
    for (helix_deg, lead_deg) in [(30.0f64, 15.0), (45.0, 30.0)] {
        let mut cutter = Cutter::new(Shape::Ball, R, 4, helix_deg.to_radians());
        cutter.runout.offset_mm = 0.6e-3;
        cutter.runout.offset_phase_rad = 20f64.to_radians();
        let t = surface_of(cutter, lead_deg);
        let (xs, zs) = profile(&t, &mut rng, 0.2, 40.0);
        let tool = Cutter::new(Shape::Ball, R, 4, helix_deg.to_radians());
        let id = identify(&xs, &zs, &tool, FZ, lead_deg).unwrap();
        let what = format!("helix {helix_deg}°, lead {lead_deg}°");
        check(&t, &id, residual_of(&t, &xs, &zs), &what);
        let e = id.offset_um.expect("offset identified");
        assert!((e / 0.6 - 1.0).abs() < 0.05, "{what}: offset {e}");
        let r = rotation(&t, &id);
        let phase_true = (20f64.to_radians() + t.cutter.pitch_rad[r]).to_degrees();
        let diff = (id.phase_deg.unwrap() - phase_true + 540.0).rem_euclid(360.0) - 180.0;
        assert!(
            diff.abs() < 5.0,
            "{what}: phase {:?} against {phase_true}",
            id.phase_deg
        );
    }
}

/// Several profiles of the same surface, each starting elsewhere, are averaged.
#[test]
fn several_profiles_are_averaged() {
    let mut rng = Rng::new(11);
    let t = truth(6, 0.6, 130.0, 30.0);
    let profiles: Vec<(Vec<f64>, Vec<f64>)> = (0..5)
        .map(|i| profile(&t, &mut rng, 0.37 * i as f64, 4.0))
        .collect();
    let refs: Vec<(&[f64], &[f64])> = profiles
        .iter()
        .map(|(x, z)| (x.as_slice(), z.as_slice()))
        .collect();
    let id =
        identify_profiles(&refs, &Cutter::new(Shape::Ball, R, 6, 0.0), FZ, 30.0, false).unwrap();
    assert_eq!(id.profiles, 5);
    let (teeth, offset) = check(&t, &id, f64::INFINITY, "six teeth, five profiles");
    assert!(teeth && offset, "{id:#?}");
}

/// Stepover of the passes across the feed, mm (scallops of 1 µm: stronger than the marks, so
/// that the spectrum's strongest peak lies across the feed).
const STEPOVER_MM: f64 = 0.2;

/// A measured map of the surface `t`: the marks along the feed direction `feed_deg`, the
/// scallops of parallel passes across it, white noise of 5 % of Rz; 2 µm nodes over
/// 1.2 mm square.
fn map_of(t: &Truth, feed_deg: f64, rng: &mut Rng) -> crest::surface::HeightMap {
    let (n, d) = (601usize, 2.0);
    let mut map = crest::surface::HeightMap::new_nan(n, n, d, d);
    let (s, c) = feed_deg.to_radians().sin_cos();
    let half = 0.5 * (n - 1) as f64 * d;
    let sigma = 0.05 * t.rz_um;
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (j as f64 * d - half, i as f64 * d - half);
            // Along the feed u, across v, mm.
            let (u, v) = ((x * c + y * s) * 1e-3, (-x * s + y * c) * 1e-3);
            let w = v - STEPOVER_MM * (v / STEPOVER_MM).round();
            let scallop = w * w / (2.0 * R);
            map.z_um[i * n + j] = (height_mm(t, u + 1.0) + scallop) * 1e3 + sigma * rng.normal();
        }
    }
    map
}

const TOOL_Z4: &str = "shape = \"ball\"\nradius_mm = 5\nteeth = 4\nhelix_deg = 0\n";

/// `crest runout identify --map`: a map of a known run-out, written as .x3p along x and as
/// .sdf rotated by 30°, gives back the feed direction, the teeth that cut, the offset and
/// phase, and a tool that reproduces Rz.
#[test]
fn a_map_of_a_known_runout_is_identified_along_its_feed() {
    let dir = crate::util::tempdir();
    let tool = crate::util::write(dir.path(), "tool.toml", TOOL_Z4);
    let mut rng = Rng::new(21);
    for (feed_deg, name) in [(0.0, "m.x3p"), (30.0, "m.sdf"), (-60.0, "m2.x3p")] {
        let t = truth(4, 0.6, 20.0, 15.0);
        let map = map_of(&t, feed_deg, &mut rng);
        let path = dir.path().join(name);
        crest::io::write_heightmap(&path, &map).unwrap();
        let out = dir.path().join(format!("{name}.toml"));
        let v = crate::util::success_json(crate::util::crest().args([
            "runout",
            "identify",
            "--map",
            path.to_str().unwrap(),
            "--tool",
            tool.to_str().unwrap(),
            "--fz-mm",
            "0.05",
            "--lead-deg",
            "15",
            "--json",
            "--write-tool",
            out.to_str().unwrap(),
        ]));
        let what = format!("{name} at {feed_deg}°: {v}");
        let found = v["feed_deg"].as_f64().unwrap();
        assert!((found - feed_deg).abs() < 0.5, "{what}");
        assert!(v["profiles"].as_u64().unwrap() >= 5, "{what}");
        for key in ["mark_spacing_mm", "period_mm", "revolution_mm", "runout"] {
            assert!(v.get(key).is_some(), "no {key}: {what}");
        }
        assert_eq!(
            v["teeth_cutting"],
            serde_json::json!([1, 2, 3, 4]),
            "{what}"
        );
        assert!(
            (v["mark_spacing_mm"].as_f64().unwrap() - 0.05).abs() < 1e-12,
            "{what}"
        );
        assert!(
            (v["period_mm"].as_f64().unwrap() - 0.2).abs() < 1e-12,
            "{what}"
        );
        // The written tool reproduces the marks.
        let re = crest::config::tool::load_tool_toml(&crate::util::read(&out)).unwrap();
        let rz_re = rz_over(&surface_of(re, 15.0), t.lambda_c_mm);
        let rz = rz_over(&t, t.lambda_c_mm);
        assert!(
            (rz_re / rz - 1.0).abs() < 0.05,
            "Rz {rz_re} against {rz}: {what}"
        );
        // Offset and phase (tooth 1 = the deepest: the true tooth 1 here, phase 20°).
        let e = v["offset_um"].as_f64().unwrap();
        assert!((e / 0.6 - 1.0).abs() < 0.05, "offset {e}: {what}");
        let phase = v["phase_deg"].as_f64().unwrap();
        let diff = (phase - 20.0 + 540.0).rem_euclid(360.0) - 180.0;
        assert!(diff.abs() < 5.0, "phase {phase}: {what}");
    }
}

/// Bad input exits 2 and writes nothing: a missing map, a map in an unknown format, a
/// profile and a map at once, a lead beyond 90°, a map too small to hold two revolutions.
#[test]
fn bad_map_input_exits_2_and_writes_nothing() {
    let dir = crate::util::tempdir();
    let tool = crate::util::write(dir.path(), "tool.toml", TOOL_Z4);
    let out = dir.path().join("out.toml");
    let small = dir.path().join("small.sdf");
    let mut map = crest::surface::HeightMap::new_nan(40, 40, 1.0, 1.0);
    for (k, z) in map.z_um.iter_mut().enumerate() {
        *z = ((k % 40) as f64 * 0.7).sin();
    }
    crest::io::write_heightmap(&small, &map).unwrap();
    let unknown = crate::util::write(dir.path(), "m.abc", "1 2 3\n");
    let missing = dir.path().join("nothing.x3p");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--map", missing.to_str().unwrap()], "nothing.x3p"),
        (vec!["--map", unknown.to_str().unwrap()], "m.abc"),
        (vec!["--map", small.to_str().unwrap()], "small.sdf"),
        (
            vec!["--map", small.to_str().unwrap(), "--profile", "p.csv"],
            "cannot be used with",
        ),
    ];
    for (args, says) in cases {
        let assert = crate::util::crest()
            .args(["runout", "identify", "--tool", tool.to_str().unwrap()])
            .args(["--fz-mm", "0.05", "--lead-deg", "15"])
            .args(["--write-tool", out.to_str().unwrap()])
            .args(&args)
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
        assert!(err.contains(says), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} wrote {}", out.display());
    }
    let assert = crate::util::crest()
        .args(["runout", "identify", "--tool", tool.to_str().unwrap()])
        .args(["--fz-mm", "0.05", "--channel", "Height"])
        .args(["--map", small.to_str().unwrap()])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(err.contains("small.sdf"), "--channel on an .sdf: {err}");
    let assert = crate::util::crest()
        .args(["runout", "identify", "--tool", tool.to_str().unwrap()])
        .args(["--fz-mm", "0.05", "--lead-deg", "95"])
        .args(["--map", small.to_str().unwrap()])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(err.contains("--lead-deg"), "{err}");
}

/// A Gwyddion `.gwy` with two height channels, "Form" (a plane) first and "Topography" (the
/// map of a known run-out, fed along 20°): `--channel Topography` identifies from the second.
#[test]
fn a_gwy_channel_is_read_by_its_title() {
    use crate::instruments::{gwy_comp, gwy_field, gwy_obj, gwy_str};
    let dir = crate::util::tempdir();
    let tool = crate::util::write(dir.path(), "tool.toml", TOOL_Z4);
    let mut rng = Rng::new(8);
    let t = truth(4, 0.6, 20.0, 15.0);
    let map = map_of(&t, 20.0, &mut rng);
    let n = map.nx as i32;
    let real = (
        map.nx as f64 * map.dx_um * 1e-6,
        map.ny as f64 * map.dy_um * 1e-6,
    );
    let topo: Vec<f64> = map.z_um.iter().map(|z| z * 1e-6).collect();
    let form: Vec<f64> = (0..map.z_um.len())
        .map(|k| (k % map.nx) as f64 * 1e-9)
        .collect();
    let mut bytes = b"GWYP".to_vec();
    bytes.extend_from_slice(&gwy_obj(
        "GwyContainer",
        &[
            gwy_comp(
                "/0/data",
                b'o',
                &gwy_field(n, n, real, 0.0, ("m", "m"), &form),
            ),
            gwy_comp("/0/data/title", b's', &gwy_str("Form")),
            gwy_comp(
                "/1/data",
                b'o',
                &gwy_field(n, n, real, 0.0, ("m", "m"), &topo),
            ),
            gwy_comp("/1/data/title", b's', &gwy_str("Topography")),
        ],
    ));
    let path = crate::util::write(dir.path(), "m.gwy", bytes);
    let v = crate::util::success_json(crate::util::crest().args([
        "runout",
        "identify",
        "--map",
        path.to_str().unwrap(),
        "--channel",
        "Topography",
        "--tool",
        tool.to_str().unwrap(),
        "--fz-mm",
        "0.05",
        "--lead-deg",
        "15",
        "--json",
    ]));
    assert!((v["feed_deg"].as_f64().unwrap() - 20.0).abs() < 0.5, "{v}");
    assert_eq!(v["teeth_cutting"], serde_json::json!([1, 2, 3, 4]), "{v}");
    let e = v["offset_um"].as_f64().unwrap();
    assert!((e / 0.6 - 1.0).abs() < 0.05, "{v}");
}

/// An uneven pitch: the teeth keep the tool's order (x0 is searched over the revolution) and
/// the written tool, with the same pitch, gives the profile's Rz.
#[test]
fn an_uneven_pitch_keeps_the_tools_order() {
    let mut rng = Rng::new(12);
    let pitch = [0.0, 85.0, 180.0, 265.0];
    for (e_um, phase_deg) in [(0.6, 20.0), (3.0, 200.0)] {
        let mut cutter = Cutter::with_pitch_deg(Shape::Ball, R, &pitch, 0.0);
        cutter.runout.offset_mm = e_um * 1e-3;
        cutter.runout.offset_phase_rad = f64::to_radians(phase_deg);
        let t = surface_of(cutter, 15.0);
        let (xs, zs) = profile(&t, &mut rng, 0.35, 40.0);
        let tool = Cutter::with_pitch_deg(Shape::Ball, R, &pitch, 0.0);
        let id = identify(&xs, &zs, &tool, FZ, 15.0).unwrap();
        let base = format!(
            "shape = \"ball\"\nradius_mm = {R}\nteeth = 4\nhelix_deg = 0\ntooth_pitch_deg = [0, 85, 180, 265]\n"
        );
        let r = &id.runout;
        let text = crest::config::tool::with_runout(
            &base,
            r.offset_um.zip(r.offset_phase_deg),
            &r.tooth_radius_deviation_um,
        );
        let re = crest::config::tool::load_tool_toml(&text).unwrap();
        let (rz_re, rz) = (
            rz_over(&surface_of(re, 15.0), t.lambda_c_mm),
            rz_over(&t, t.lambda_c_mm),
        );
        let what = format!("e {e_um} at {phase_deg}°: {id:#?}");
        assert!(
            (rz_re / rz - 1.0).abs() < 0.05,
            "Rz {rz_re} against {rz}, {what}"
        );
        // This pitch looks the same from tooth 3 (180° on): tooth 1 is the deeper of 1 and 3.
        let r = [0usize, 2]
            .into_iter()
            .find(|&r| {
                (0..4).all(|k| id.identifiable.tooth_deviation[k] == t.cuts[(r + k) % 4])
                    && (0..4).all(|k| {
                        !t.cuts[(r + k) % 4]
                            || ((t.dev[(r + k) % 4] - t.dev[r]) * 1e3 - id.tooth_deviation_um[k])
                                .abs()
                                < 0.05
                    })
            })
            .unwrap_or_else(|| panic!("teeth that cut {:?}, {what}", t.cuts));
        if let (Some(e), true) = (id.offset_um, t.cuts.iter().filter(|c| **c).count() >= 3) {
            assert!((e / e_um - 1.0).abs() < 0.05, "{what}");
            let want = phase_deg + pitch[r];
            let diff = (id.phase_deg.unwrap() - want + 540.0).rem_euclid(360.0) - 180.0;
            assert!(diff.abs() < 5.0, "{what}");
        }
    }
}
