//! Hostile input, second round (issue 37): every limit on every route (a CLSF's TLDATA,
//! every SPINDL and FEDRAT, MSYS, mesh vertices, height-map values, profile points), CR-only
//! line ends read like LF, located messages with real lines, and text from the input kept
//! from breaking pages, CSV files and Markdown tables.

use crate::util::{ROOT, crest, repo, write};
use std::path::Path;
use std::time::Duration;

/// Run `crest args…` in `dir` with a 10 s limit; return (exit code, stderr).
fn run(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = crest()
        .current_dir(dir)
        .args(args)
        .timeout(Duration::from_secs(10))
        .output()
        .unwrap();
    let code = out.status.code().unwrap_or(-1);
    (code, String::from_utf8_lossy(&out.stderr).into_owned())
}

fn expect_2(dir: &Path, args: &[&str], needles: &[&str]) {
    let (code, err) = run(dir, args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: {n:?} not in {err}");
    }
    // A hostile value is shown short (1e300, not its 301 digits).
    assert!(!err.contains("0000000000000"), "{args:?}: {err}");
}

/// A 20-GOTO path with `head` records after its TOOL PATH record.
fn path_with(head: &str) -> String {
    let mut s = format!("TOOL PATH/OP,TOOL,T\n{head}FEDRAT/MMPM,500\n");
    for i in 0..20 {
        s.push_str(&format!("GOTO/{i},0,0,0,0,1\n"));
    }
    s.push_str("END-OF-PATH\n");
    s
}

/// The four commands that read a path and its tool, on `f`.
fn every_route(f: &str) -> Vec<Vec<String>> {
    let v = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    vec![
        v(&["inspect", f]),
        v(&["contact", f, "--teeth", "2", "-o", "c.csv"]),
        v(&["resample", f, "--mode", "dtheta", "-o", "r.csv"]),
        v(&[
            "simulate", f, "--teeth", "2", "--window", "0,-1,5,1", "-o", "m.gsf",
        ]),
    ]
}

#[test]
fn r37_limits_hold_on_every_route() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let spindle = "TLDATA/MILL,10,5,50,0,0\nSPINDL/RPM,8000,CLW\n";
    for (name, head, at) in [
        (
            "huge.cls",
            "TLDATA/MILL,1e300,5,50,0,0\nSPINDL/RPM,8000\n",
            "huge.cls:2:",
        ),
        (
            "corner.cls",
            "TLDATA/MILL,10,50\nSPINDL/RPM,8000\n",
            "corner.cls:2:",
        ),
        (
            "spindl.cls",
            "TLDATA/MILL,10,5,50,0,0\nSPINDL/RPM,10000,CLW\nSPINDL/RPM,1e300,CLW\n",
            "spindl.cls:4:",
        ),
        (
            "fedrat.cls",
            &format!("{spindle}FEDRAT/MMPM,100\nFEDRAT/MMPM,1e300\n"),
            "fedrat.cls:5:",
        ),
        (
            "msys.cls",
            &format!("{spindle}MSYS/1e300,0,0,1,0,0,0,1,0\n"),
            "msys.cls:4:",
        ),
    ] {
        write(p, name, path_with(head));
        for args in every_route(name) {
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            expect_2(p, &args, &[at]);
        }
        for out in ["c.csv", "r.csv", "m.gsf"] {
            assert!(!p.join(out).exists(), "{name}: {out}");
        }
    }
    // Mesh vertices beyond ±100 m: every mesh format, on contact and simulate.
    write(p, "ok.cls", path_with(spindle));
    let ball = repo("samples/synth/ball-r5.toml");
    let ball = ball.to_str().unwrap();
    write(
        p,
        "far.stl",
        "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1e6 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n",
    );
    write(p, "far.obj", "v 0 0 0\nv 1 0 0\nv 0 1e30 0\nf 1 2 3\n");
    write(
        p,
        "far.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 -1e6\n3 0 1 2\n",
    );
    for (mesh, at) in [
        ("far.stl", "far.stl:5"),
        ("far.obj", "far.obj:3"),
        ("far.ply", "far.ply:12"),
    ] {
        for cmd in ["contact", "simulate"] {
            let mut args = vec![cmd, "ok.cls", "--tool", ball, "--part", mesh];
            if cmd == "contact" {
                args.extend(["-o", "c.csv"]);
            } else {
                args.extend(["--window", "0,-1,5,1", "-o", "m.gsf"]);
            }
            expect_2(p, &args, &[at, "100000"]);
        }
    }
    // Binary STL: the triangle and byte named.
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&1u32.to_le_bytes());
    for v in [0f32, 0., 1., 0., 0., 0., 1e7, 0., 0., 0., 1., 0.] {
        stl.extend_from_slice(&v.to_le_bytes());
    }
    stl.extend_from_slice(&[0, 0]);
    write(p, "far-bin.stl", stl);
    expect_2(
        p,
        &[
            "contact",
            "ok.cls",
            "--tool",
            ball,
            "--part",
            "far-bin.stl",
            "-o",
            "c.csv",
        ],
        &["far-bin.stl:triangle 1", "100000"],
    );
    // Height-map values beyond ±1 m (3e38 m overflows float32 µm): the limit, not "no
    // valid height".
    let h = "Gwyddion Simple Field 1.0\nXRes = 2\nYRes = 2\nXReal = 1e-3\nYReal = 1e-3\n";
    for (name, z) in [
        ("one.gsf", [3e38f32, 0.0, 0.0, 0.0]),
        ("all.gsf", [3e38f32; 4]),
    ] {
        let mut b = h.as_bytes().to_vec();
        b.extend(std::iter::repeat_n(0u8, 4 - h.len() % 4));
        for v in z {
            b.extend_from_slice(&v.to_le_bytes());
        }
        write(p, name, b);
        for params in [&[][..], &["--params", "Sa"][..]] {
            let mut args = vec!["metrics", name];
            args.extend_from_slice(params);
            expect_2(p, &args, &[name, "1000000"]);
        }
        expect_2(p, &["view", name, "-o", "v.html"], &[name, "1000000"]);
    }
    // profile_mm has a cap on its points, refused at once.
    let mut prof = String::from("shape = \"profile\"\nteeth = 2\nhelix_deg = 30\nprofile_mm = [");
    for i in 0..200_000 {
        prof.push_str(&format!("[{}, {}],", 1e-5 * i as f64, 1e-6 * i as f64));
    }
    prof.push_str("]\n");
    write(p, "prof.toml", prof);
    let t0 = std::time::Instant::now();
    expect_2(
        p,
        &[
            "tool",
            "--tool",
            "prof.toml",
            "--lead-deg",
            "10",
            "--ap-mm",
            "0.2",
            "--fz-mm",
            "0.05",
        ],
        &["prof.toml:", "profile_mm", "10000"],
    );
    assert!(t0.elapsed() < Duration::from_secs(5), "{:?}", t0.elapsed());
}

#[test]
fn r37_cr_only_and_crlf_read_as_lf() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    for (sample, out_ext) in [
        ("samples/clsf/ball_lead15_contact.cls", "txt"),
        ("samples/clsf/ball_lead15_contact12.txt", "cls"),
    ] {
        let text = std::fs::read_to_string(repo(sample)).unwrap();
        let lf = text.replace("\r\n", "\n");
        let ext = Path::new(sample).extension().unwrap().to_str().unwrap();
        let mut outs = Vec::new();
        for (name, body) in [
            ("lf", lf.clone()),
            ("crlf", lf.replace('\n', "\r\n")),
            ("cr", lf.replace('\n', "\r")),
        ] {
            // The same file name in a folder per line end (names reach the outputs).
            let dir = p.join(format!("{name}-{ext}"));
            std::fs::create_dir(&dir).unwrap();
            let input = format!("in.{ext}");
            write(&dir, &input, &body);
            let output = format!("out.{out_ext}");
            let (code, err) = run(&dir, &["convert", &input, "-o", &output]);
            assert_eq!(code, 0, "{name} {input}: {err}");
            outs.push(std::fs::read(dir.join(&output)).unwrap());
            let o = crest()
                .current_dir(&dir)
                .args(["inspect", &input, "--json"])
                .output()
                .unwrap();
            assert!(o.status.success(), "{input}");
            let j = crate::util::json(&o.stdout);
            outs.push(j["paths"].to_string().into_bytes());
        }
        assert!(outs[0].len() > 1000, "{sample}");
        assert!(outs[0] == outs[2], "{sample}: CRLF");
        assert!(outs[0] == outs[4], "{sample}: CR only");
        assert!(outs[1] == outs[3], "{sample}: CRLF inspect");
        assert!(outs[1] == outs[5], "{sample}: CR only inspect");
    }
}

#[test]
fn r37_located_messages_have_real_lines() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let m = std::fs::read_to_string(repo("samples/machines/table1_ac.toml"))
        .unwrap()
        .replacen(
            "lookahead_blocks = 0 ",
            "lookahead_blocks = 99999999999999999999 ",
            1,
        );
    let line = m
        .lines()
        .position(|l| l.starts_with("lookahead_blocks"))
        .unwrap()
        + 1;
    write(p, "m.toml", m);
    let cls = repo("samples/clsf/ball_lead15_contact.cls");
    let (code, err) = run(p, &["feed", cls.to_str().unwrap(), "--machine", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains(&format!("m.toml:{line}:20")), "{err}");
    assert!(!err.contains(":0:"), "{err}");
    // A binary PLY whose first face names vertex 7 of 3.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
        ply.extend_from_slice(&v.to_le_bytes());
    }
    ply.push(3);
    for i in [0i32, 1, -7] {
        ply.extend_from_slice(&i.to_le_bytes());
    }
    write(p, "bad.ply", ply);
    write(
        p,
        "ok.cls",
        path_with("TLDATA/MILL,10,5,50,0,0\nSPINDL/RPM,8000\n"),
    );
    let ball = repo("samples/synth/ball-r5.toml");
    let (code, err) = run(
        p,
        &[
            "contact",
            "ok.cls",
            "--tool",
            ball.to_str().unwrap(),
            "--part",
            "bad.ply",
            "-o",
            "c.csv",
        ],
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.ply:face 1 (byte "), "{err}");
    assert!(!err.contains(":0:"), "{err}");
}

#[test]
fn r37_view_page_keeps_markup_out_of_its_data() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    write(p, "m.csv", "0,1,2\n1,2,3\n2,3,4\n");
    let title = "<!--<script> a & b </script>";
    let (code, err) = run(
        p,
        &[
            "view", "m.csv", "--dx-um", "10", "--title", title, "-o", "v.html",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let page = std::fs::read_to_string(p.join("v.html")).unwrap();
    assert!(!page.contains("<!--"), "raw <!-- in the page");
    assert!(!page.contains("<script> a"), "raw <script> from the title");
    assert!(page.contains("\\u003c!--\\u003cscript\\u003e a \\u0026 b"));
    let _ = ROOT;
}
