//! `crest view` and the viewer pages of `simulate --view`: the page opened in a real browser
//! (Debian's headless Chromium): no console errors, a drawn canvas whose colours span the
//! scale, and the Rz of a scripted two-click profile equal to `crest metrics --profile line:…`.
//!
//! The browser tests skip (saying so on stderr) when no `chromium` is installed, unless
//! `CREST_REQUIRE_CHROMIUM` is set (`.ci/run` installs Chromium and sets it).

use crate::util::{ROOT, crest, read, stdout_json, tempdir};
use crest::io::write_heightmap;
use crest::surface::{HeightMap, MapPoint};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Width of the page's side panel, CSS px (`assets/viewer/viewer.css`): the canvas is the rest.
const SIDE_PX: u32 = 320;
const WINDOW: (u32, u32) = (1280, 800);

/// The Chromium binary, or `None` (with a message) when it is not installed here.
fn chromium() -> Option<PathBuf> {
    let found = ["chromium", "chromium-browser"].iter().find_map(|name| {
        std::env::var_os("PATH").and_then(|paths| {
            std::env::split_paths(&paths)
                .map(|d| d.join(name))
                .find(|p| p.is_file())
        })
    });
    if found.is_none() {
        assert!(
            std::env::var_os("CREST_REQUIRE_CHROMIUM").is_none(),
            "CREST_REQUIRE_CHROMIUM is set but no chromium is on PATH"
        );
        eprintln!(
            "skipping the browser test: no `chromium` on PATH (apt-get install chromium; .ci/run does)"
        );
    }
    found
}

/// Run headless Chromium on `page` with `query`, with a fresh profile, and one mode
/// (`--dump-dom` or `--screenshot=…`); returns stdout and stderr.
fn browse(chrome: &Path, page: &Path, query: &str, mode: &str) -> (String, String) {
    let profile = tempdir();
    let url = format!("file://{}?{query}", page.display());
    let out = Command::new(chrome)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1))
        .arg(mode)
        .arg(&url)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", chrome.display()));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "chromium failed: {stderr}");
    // A JavaScript exception anywhere in the page is logged as `Uncaught …`.
    assert!(!stderr.contains("Uncaught"), "console error: {stderr}");
    (stdout, stderr)
}

/// The JSON the page's test hook wrote into `#crest-test`, from a `--dump-dom`.
fn test_result(dom: &str) -> serde_json::Value {
    let start = dom
        .find("id=\"crest-test\"")
        .unwrap_or_else(|| panic!("no #crest-test in the page: {dom:.2000}"));
    let text = &dom[start..];
    let text = &text[text.find('>').unwrap() + 1..text.find("</pre>").unwrap()];
    let text = text
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// Hue (degrees), saturation and value of an RGB pixel.
fn hsv(r: u8, g: u8, b: u8) -> (f64, f64, f64) {
    let (r, g, b) = (f64::from(r), f64::from(g), f64::from(b));
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let d = max - min;
    let s = if max > 0.0 { d / max } else { 0.0 };
    let h = if d == 0.0 {
        0.0
    } else if max == r {
        (60.0 * (g - b) / d).rem_euclid(360.0)
    } else if max == g {
        60.0 * ((b - r) / d + 2.0)
    } else {
        60.0 * ((r - g) / d + 4.0)
    };
    (h, s, max / 255.0)
}

/// What the canvas part of a screenshot shows: the share of pixels that are not the clear
/// colour, and the counts of strongly coloured pixels at the low end of the colour scale
/// (blue, hue 224-245°, the bottom few % of the scale), in its middle (green, 100-150°) and
/// at its high end (red, hue ≤ 10° or ≥ 355°, the top few %).
struct Shot {
    drawn: f64,
    low: usize,
    mid: usize,
    high: usize,
}

fn read_shot(png: &Path) -> Shot {
    let pix = resvg::tiny_skia::Pixmap::load_png(png)
        .unwrap_or_else(|e| panic!("{}: {e}", png.display()));
    assert_eq!((pix.width(), pix.height()), WINDOW, "screenshot size");
    let (mut drawn, mut all, mut low, mut mid, mut high) = (0usize, 0usize, 0, 0, 0);
    for y in 0..pix.height() {
        for x in 0..pix.width() - SIDE_PX {
            let p = pix.pixel(x, y).unwrap().demultiply();
            let (r, g, b) = (p.red(), p.green(), p.blue());
            all += 1;
            // The clear colour is #eef1f4.
            if (i32::from(r) - 0xee).abs()
                + (i32::from(g) - 0xf1).abs()
                + (i32::from(b) - 0xf4).abs()
                > 24
            {
                drawn += 1;
            }
            let (h, s, v) = hsv(r, g, b);
            if s < 0.35 || v < 0.15 {
                continue;
            }
            if (224.0..=245.0).contains(&h) {
                low += 1;
            } else if (100.0..=150.0).contains(&h) {
                mid += 1;
            } else if h <= 10.0 || h >= 355.0 {
                high += 1;
            }
        }
    }
    Shot {
        drawn: drawn as f64 / all as f64,
        low,
        mid,
        high,
    }
}

/// A synthetic height map: crossed waves with a lay at 45° and a missing corner, 601 × 401
/// nodes (so the page shows 2 × 2 block means but takes profiles from the full map).
fn synthetic_map() -> HeightMap {
    let (nx, ny, d) = (601, 401, 2.5);
    let tau = std::f64::consts::TAU;
    let mut z = Vec::with_capacity(nx * ny);
    for r in 0..ny {
        for c in 0..nx {
            let (x, y) = (c as f64 * d, r as f64 * d);
            let v = 1.5 * (tau * x / 180.0).sin()
                + 0.8 * (tau * y / 110.0).cos()
                + 0.3 * (tau * (x + y) / 37.0).sin();
            z.push(if r < 40 && c < 60 { f64::NAN } else { v });
        }
    }
    HeightMap::from_rows(nx, ny, d, d, z).unwrap()
}

#[test]
fn view_writes_one_self_contained_page_and_names_bad_input() {
    let dir = tempdir();
    let map = dir.path().join("wave.gsf");
    write_heightmap(&map, &synthetic_map()).unwrap();
    let page = dir.path().join("wave.html");
    crest()
        .args(["view"])
        .arg(&map)
        .arg("-o")
        .arg(&page)
        .assert()
        .success();
    let html = read(&page);
    assert!(html.contains("three.js 0.187.0"));
    assert!(html.contains("\"full_f64\""), "the full map is embedded");
    assert!(html.contains("\"factor\":2"), "shown as 2 × 2 block means");
    assert!(!html.contains("<script src") && !html.contains("<link"));
    let missing = dir.path().join("nope.gsf");
    let out = crest()
        .args(["view"])
        .arg(&missing)
        .arg("-o")
        .arg(dir.path().join("x.html"))
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
    assert!(err.contains("nope.gsf"), "{err}");
    assert!(!dir.path().join("x.html").exists());
}

#[test]
fn simulate_view_writes_the_viewer_beside_the_map() {
    let dir = tempdir();
    let out = dir.path().join("t3.gsf");
    let view = dir.path().join("t3.html");
    let assert = crest()
        .current_dir(ROOT)
        .args([
            "simulate",
            "samples/synth/plane-trial3.cls",
            "--tool",
            "samples/synth/torus-r5-rc1.5.toml",
            "--model",
            "dome",
            "--grid-um",
            "10",
            "--window",
            "0,0,0.27,0.2",
            "--json",
            "-o",
        ])
        .arg(&out)
        .arg("--view")
        .arg(&view)
        .assert()
        .success();
    let v = stdout_json(&assert);
    assert_eq!(v["view"], view.display().to_string());
    let html = read(&view);
    assert!(
        html.contains("\"nx\":28") && html.contains("\"ny\":21"),
        "the 28 × 21 map"
    );
    assert!(html.contains("\"Sa\""), "the key parameters are embedded");
}

#[test]
fn viewer_in_chromium_draws_the_scale_and_a_clicked_profile_has_the_cli_rz() {
    let Some(chrome) = chromium() else {
        return;
    };
    let dir = tempdir();
    let map = dir.path().join("wave.gsf");
    write_heightmap(&map, &synthetic_map()).unwrap();
    let page = dir.path().join("wave.html");
    crest()
        .args(["view"])
        .arg(&map)
        .arg("-o")
        .arg(&page)
        .assert()
        .success();
    // Two clicks across the surface, as fractions of the canvas.
    let query = "crest-test=click:0.3,0.55,0.7,0.45";
    let (dom, _) = browse(&chrome, &page, query, "--dump-dom");
    let r = test_result(&dom);
    assert_eq!(r["errors"], serde_json::json!([]), "console errors: {r}");
    assert!(r["triangles"].as_u64().unwrap() > 100_000, "{r}");
    let profile = &r["profile"];
    let line = profile["line"]
        .as_str()
        .unwrap_or_else(|| panic!("the clicks picked no profile: {r}"));
    let rz_page: f64 = profile["rz"].as_str().unwrap().parse().unwrap();
    assert!(
        profile["samples"].as_u64().unwrap() > 100,
        "a long line: {r}"
    );
    let cli = stdout_json(
        &crest()
            .args(["metrics"])
            .arg(&map)
            .args(["--profile", line, "--params", "Rz", "--json"])
            .assert()
            .success(),
    );
    let rz_cli = cli["Rz"].as_f64().unwrap();
    assert!(rz_cli > 0.5, "{cli}");
    assert_eq!(
        rz_page.to_bits(),
        rz_cli.to_bits(),
        "page Rz {rz_page} against crest metrics {rz_cli} on {line}"
    );
    assert_eq!(cli["profile"]["samples"], profile["samples"]);

    // The screenshot: drawn, with both ends and the middle of the colour scale on the canvas.
    let png = dir.path().join("shot.png");
    browse(
        &chrome,
        &page,
        query,
        &format!("--screenshot={}", png.display()),
    );
    let shot = read_shot(&png);
    assert!(shot.drawn > 0.2, "canvas mostly blank: {:.3}", shot.drawn);
    assert!(
        shot.low >= 20 && shot.mid >= 20 && shot.high >= 20,
        "colours do not span the scale: low {}, mid {}, high {}",
        shot.low,
        shot.mid,
        shot.high
    );
}

#[test]
fn part_map_viewer_in_chromium_draws_the_point_cloud() {
    let Some(chrome) = chromium() else {
        return;
    };
    let dir = tempdir();
    // A spherical cap of radius 20 mm, heights rising from −3 to 3 µm across it, a few
    // points not reached.
    let mut points = Vec::new();
    for i in 0..120 {
        for j in 0..120 {
            let (x, y) = (-6.0 + 0.1 * i as f64, -6.0 + 0.1 * j as f64);
            let z = (400.0 - x * x - y * y).sqrt() - 20.0;
            let n = crest::math::Vec3::new(x, y, z + 20.0) / 20.0;
            let h = if (i + j) % 97 == 0 { f64::NAN } else { x / 2.0 };
            points.push(MapPoint {
                point: crest::math::Point3::new(x, y, z),
                normal: n,
                height_um: h,
            });
        }
    }
    let ply = dir.path().join("part.ply");
    let mut bytes = Vec::new();
    crest::io::mesh::write_map_ply(&points, &mut bytes).unwrap();
    std::fs::write(&ply, bytes).unwrap();
    let page = dir.path().join("part.html");
    crest()
        .args(["view"])
        .arg(&ply)
        .arg("-o")
        .arg(&page)
        .assert()
        .success();
    let (dom, _) = browse(&chrome, &page, "crest-test=none", "--dump-dom");
    let r = test_result(&dom);
    assert_eq!(r["errors"], serde_json::json!([]), "console errors: {r}");
    let png = dir.path().join("part.png");
    browse(
        &chrome,
        &page,
        "crest-test=none",
        &format!("--screenshot={}", png.display()),
    );
    let shot = read_shot(&png);
    assert!(shot.drawn > 0.1, "canvas mostly blank: {:.3}", shot.drawn);
    assert!(
        shot.low >= 20 && shot.high >= 20,
        "colours do not span the scale: low {}, high {}",
        shot.low,
        shot.high
    );
}

#[test]
fn report_view_writes_a_page_per_simulated_case_and_refuses_the_crest_model() {
    let dir = tempdir();
    crate::util::write(
        dir.path(),
        "t.csv",
        "lead_deg,side,sample,Ra_um,Rz_um\n15,concave,S1,0.418,2.20\n15,concave,S2,0.437,2.59\n",
    );
    let study = |model: &str| {
        format!(
            "title = \"simulate\"\ntool = \"{ROOT}/samples/tools/ball-r5-z4.toml\"\nmodel = \"{model}\"\n\
             fz_mm = 0.05\nap_mm = 0.4\nrule = \"paper\"\n[simulate]\nsurface_model = \"dome\"\ngrid_um = 2.0\n\
             [[case]]\nlead_deg = 15.0\nside = \"concave\"\n"
        )
    };
    crate::util::write(dir.path(), "s.toml", study("simulate"));
    crate::util::write(dir.path(), "c.toml", study("crest"));
    let out = dir.path().join("out");
    let run = |s: &str, out: &Path| {
        crest()
            .current_dir(dir.path())
            .args(["report", "--measured", "t.csv", "--study", s, "-o"])
            .arg(out)
            .args(["--tolerance-pct", "1000", "--view"])
            .assert()
    };
    run("s.toml", &out).success();
    let html = read(&out.join("view-1.html"));
    assert!(
        html.contains("case 1: lead 15°, concave"),
        "the case in the title"
    );
    assert!(out.join("report.html").is_file());
    let crest_out = dir.path().join("crest-out");
    let a = run("c.toml", &crest_out).code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(err.contains("--view needs model = \"simulate\""), "{err}");
    assert!(!crest_out.exists(), "nothing written");
}
