//! `crest convert` and `crest inspect` end to end: round trips, bad input (exit 2, file,
//! line and column named, no output left behind).

use predicates::prelude::*;

use crate::util::{crest, external_samples, nx_sample, read, success_json, tempdir, write};

/// stderr with miette's frame characters and line wrapping removed.
fn flat(bytes: &[u8]) -> String {
    let s = String::from_utf8_lossy(bytes).replace(['│', '×'], " ");
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A contact12 file in the paper's style: blanks, a header, some NA lines, 6 decimals.
const CONTACT12: &str = "X Y Z I J K CX CY CZ NX NY NZ\n\
1.5 2.25 -3.125 0 0 1 1.5 2.25 -3.125 0 0 1\n\
2.000001 2.25 -3.1 0.1 0.0 0.994987437 2.4 2.3 -3.2 0.2 0 0.979795897\n\
3 4 5 0 0 1 NA NA NA NA NA NA\n\
4.123456 -0.5 7 0 0.6 0.8 4.2 -0.4 6.9 0 0.6 0.8\n";

#[test]
fn contact12_to_clsf_to_contact12_is_exact() {
    let dir = tempdir();
    let a = write(dir.path(), "paper.txt", CONTACT12);
    let direct = dir.path().join("direct.csv");
    let cls = dir.path().join("mid.cls");
    let back = dir.path().join("back.csv");
    crest()
        .args(["convert"])
        .arg(&a)
        .arg("-o")
        .arg(&direct)
        .arg("--all-moves")
        .assert()
        .success();
    crest()
        .args(["convert"])
        .arg(&a)
        .arg("-o")
        .arg(&cls)
        .assert()
        .success();
    crest()
        .args(["convert"])
        .arg(&cls)
        .arg("-o")
        .arg(&back)
        .arg("--all-moves")
        .assert()
        .success();
    assert_eq!(read(&direct), read(&back));
    // Every number of the input survives with its value.
    let back_text = read(&back);
    let rows: Vec<&str> = back_text.lines().skip(1).collect();
    let input_rows: Vec<&str> = CONTACT12.lines().skip(1).collect();
    assert_eq!(rows.len(), input_rows.len());
    for (got, want) in rows.iter().zip(input_rows) {
        let g: Vec<&str> = got.split(',').collect();
        let w: Vec<&str> = want.split_whitespace().collect();
        for (x, y) in g.iter().zip(w) {
            if y == "NA" {
                assert_eq!(*x, "");
            } else {
                let (x, y): (f64, f64) =
                    (x.parse().unwrap_or(f64::NAN), y.parse().unwrap_or(f64::NAN));
                assert_eq!(x, y, "{got} vs {want}");
            }
        }
    }
    // Default: cutting moves with contact data only (the NA line is dropped).
    let cut = dir.path().join("cut.csv");
    crest()
        .args(["convert"])
        .arg(&cls)
        .arg("-o")
        .arg(&cut)
        .assert()
        .success();
    assert_eq!(read(&cut).lines().count(), 1 + 3);
    assert!(read(&cut).starts_with("x,y,z,i,j,k,cx,cy,cz,nx,ny,nz\n"));
}

#[test]
fn clsf_to_contact12_to_clsf_keeps_every_goto() {
    let Some(ext) = external_samples() else {
        return;
    };
    let dir = tempdir();
    let a = dir.path().join("a.csv");
    let b = dir.path().join("b.cls");
    let c = dir.path().join("c.csv");
    let src = ext.join("nx_5axis_varcontour_ijk_small.cls");
    crest()
        .arg("convert")
        .arg(&src)
        .arg("-o")
        .arg(&a)
        .arg("--all-moves")
        .assert()
        .success();
    crest()
        .arg("convert")
        .arg(&a)
        .arg("-o")
        .arg(&b)
        .assert()
        .success();
    crest()
        .arg("convert")
        .arg(&b)
        .arg("-o")
        .arg(&c)
        .arg("--all-moves")
        .assert()
        .success();
    assert_eq!(read(&a), read(&c));
    assert_eq!(read(&a).lines().count(), 1 + 546);
    // The CSV rows carry the GOTO coordinates as written.
    let text = read(&src);
    let first_goto = text.lines().find(|l| l.starts_with("GOTO/")).unwrap_or("");
    let row1 = read(&a).lines().nth(1).unwrap_or("").to_string();
    assert!(
        row1.starts_with(first_goto.trim_start_matches("GOTO/")),
        "{row1} vs {first_goto}"
    );
}

#[test]
fn absolute_applies_msys() {
    let Some(ext) = external_samples() else {
        return;
    };
    let dir = tempdir();
    let a = dir.path().join("abs.csv");
    // MSYS/393,-297.5,3, X=(0,1,0), Y=(1,0,0): (x,y,z) -> (393+y, -297.5+x, 3-z).
    let src = ext.join("nx_circle_times_from.cls");
    crest()
        .arg("convert")
        .arg(&src)
        .arg("-o")
        .arg(&a)
        .arg("--all-moves")
        .arg("--absolute")
        .assert()
        .success();
    let row1 = read(&a).lines().nth(1).unwrap_or("").to_string();
    assert!(
        row1.starts_with("0.0000,352.5000,-961.0000,0.0000000,0.0000000,-1.0000000"),
        "{row1}"
    );
}

#[test]
fn inspect_json_has_the_contract_keys() {
    let v = success_json(
        crest()
            .arg("inspect")
            .arg(nx_sample("nx_zlevel_core_spindl.cls"))
            .arg("--json"),
    );
    let p = &v["paths"][0];
    assert_eq!(p["name"], "ZLEVEL_FOLLOW_CORE");
    assert_eq!(p["tool"]["name"], "MILL");
    assert_eq!(p["tool"]["diameter_mm"], 30.0);
    assert_eq!(p["gotos"], 3130);
    assert_eq!(p["circles"], 614);
    assert_eq!(p["rapids"], 356);
    assert!(
        p["length_mm"].as_f64().unwrap_or(0.0) > p["cutting_length_mm"].as_f64().unwrap_or(0.0)
    );
    assert_eq!(p["feeds_mm_min"], serde_json::json!([250.0]));
    assert_eq!(p["spindles_rpm"], serde_json::json!([1000.0]));
    assert!(v["warnings"].as_array().is_some_and(|w| w.is_empty()));
}

#[test]
fn inspect_text_lists_warnings() {
    let dir = tempdir();
    let f = write(
        dir.path(),
        "u.cls",
        "TOOL PATH/A,TOOL,T\nCOOLNT/ON\nGOTO/1,2,3\nEND-OF-PATH\n",
    );
    crest()
        .arg("inspect")
        .arg(&f)
        .assert()
        .success()
        .stdout(predicate::str::contains(
            "line 2, column 1: unknown record COOLNT kept raw",
        ));
}

/// Malformed inputs: (text, line, column, expected fragment).
const BAD: &[(&str, u32, u32, &str)] = &[
    (
        "TOOL PATH/A,TOOL,T\nGOTO/1,2\nEND-OF-PATH\n",
        2,
        9,
        "3, 6, 9 or 12 numbers",
    ),
    (
        "TOOL PATH/A,TOOL,T\r\nFEDRAT/MMPM,250\r\nGOTO/1.0,2.0,3.0x\r\n",
        3,
        17,
        "end of record, found `x`",
    ),
    (
        "$$ header\nTOOL PATH/A,TOOL,T\n  GOTO/1,2,3\nCIRCLE/0,0,0,0,0,1\n",
        4,
        19,
        "7 to 11 numbers",
    ),
    (
        "TOOL PATH/A,TOOL,T\nMSYS/0,0,0,1,0,0,0,1\n",
        2,
        21,
        "9 numbers in MSYS",
    ),
    ("TOOL PATH/A,TOOL,T\nGOTO/1,$\n 2,three\n", 3, 4, "a number"),
    (
        "TOOL PATH/A,TOOL,T\nUNITS/FEET\n",
        2,
        7,
        "MM, INCH or INCHES",
    ),
    (
        "TOOL PATH/A,TOOL,T\nGOTO/1,2,3,0,0,0\n",
        2,
        1,
        "a unit vector",
    ),
];

#[test]
fn malformed_input_names_file_line_and_column_and_leaves_no_output() {
    let dir = tempdir();
    for (k, (text, line, column, expected)) in BAD.iter().enumerate() {
        let name = format!("bad{k}.cls");
        let f = write(dir.path(), &name, text);
        let out = dir.path().join(format!("out{k}.csv"));
        let assert = crest()
            .arg("convert")
            .arg(&f)
            .arg("-o")
            .arg(&out)
            .assert()
            .code(2);
        let stderr = flat(&assert.get_output().stderr);
        let place = format!("{name}:{line}:{column}: expected ");
        assert!(stderr.contains(&place), "case {k}: {stderr}");
        assert!(stderr.contains(expected), "case {k}: {stderr}");
        assert!(!out.exists(), "case {k}: output left behind");
        let again = crest().arg("inspect").arg(&f).assert().code(2);
        assert!(
            flat(&again.get_output().stderr).contains(&place),
            "case {k}"
        );
    }
    // No temporary files either.
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap_or_else(|e| panic!("{e}"))
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(".crest-"))
        .collect();
    assert!(left.is_empty());
}

#[test]
fn malformed_contact12_names_the_field() {
    let dir = tempdir();
    let f = write(
        dir.path(),
        "bad.csv",
        "x,y,z,i,j,k,cx,cy,cz,nx,ny,nz\n1,2,3,0,0,1,1,2,3,0,0,1\n1,2,3,0,0,1,1,2,3,0,zero,1\n",
    );
    let a = crest().arg("inspect").arg(&f).assert().code(2);
    let msg = flat(&a.get_output().stderr);
    assert!(
        msg.contains("bad.csv:3:21: expected a number, NA, N/A or an empty field, found `zero`"),
        "{msg}"
    );
}

#[test]
fn missing_file_is_exit_2() {
    crest()
        .arg("inspect")
        .arg("/nonexistent/x.cls")
        .assert()
        .code(2)
        .stderr(predicate::str::contains("cannot open"));
}

/// A 5-axis CLSF with contact data.
const CONTACT_SAMPLE: &str = "samples/clsf/ball_lead15_contact.cls";

/// [`CONTACT_SAMPLE`] converted to contact12 in a file of `dir`: its text.
fn converted_to_a_file(dir: &std::path::Path) -> String {
    let file = dir.join("whole.csv");
    crest()
        .arg("convert")
        .arg(crate::util::repo(CONTACT_SAMPLE))
        .arg("-o")
        .arg(&file)
        .assert()
        .success();
    read(&file)
}

/// Converting into a FIFO streams the rows (no temporary file): when the input fails part
/// way, the rows before the bad line have reached the reader (as before the contact12
/// writer collected rows itself; 128 KiB of them were lost for a while), and the command
/// still exits 2 naming the line.
#[cfg(unix)]
#[test]
fn a_failed_convert_into_a_fifo_hands_on_every_row_before_the_bad_line() {
    let dir = tempdir();
    let good = std::fs::read_to_string(crate::util::repo(CONTACT_SAMPLE)).unwrap();
    // The whole path converted to a file: the rows the FIFO must get.
    let expected = converted_to_a_file(dir.path());
    assert!(expected.lines().count() > 100);
    // The same path with a bad GOTO after its last one.
    let cut = good.rfind("RAPID\n").unwrap();
    let bad_line = good[..cut].lines().count() + 1;
    let bad = write(
        dir.path(),
        "bad.cls",
        format!("{}GOTO/1.0,2.0,abc\n{}", &good[..cut], &good[cut..]),
    );
    let fifo = dir.path().join("rows.fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let out = crest()
        .arg("convert")
        .arg(&bad)
        .arg("-o")
        .arg(&fifo)
        .output()
        .unwrap();
    let got = reader.join().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = flat(&out.stderr);
    assert!(err.contains(&format!("bad.cls:{bad_line}")), "{err}");
    // Every row but the last good GOTO's: the lowering holds a posture until the next
    // record (here the bad one) settles how it ends.
    let last = expected.trim_end_matches('\n').rfind('\n').unwrap() + 1;
    assert!(
        got == expected[..last],
        "{} lines through the FIFO, {} expected",
        got.lines().count(),
        expected[..last].lines().count()
    );
}

/// `-o /dev/stdout` with stdout a pipe (`crest convert … -o /dev/stdout | …`): the rows go
/// down the pipe. `/dev/stdout` links to `/proc/self/fd/1`, which links to `pipe:[…]`, no
/// path: following the links to the end looked for a temporary file in `/proc/self/fd`.
#[cfg(target_os = "linux")]
#[test]
fn output_to_dev_stdout_as_a_pipe_goes_down_the_pipe() {
    let dir = tempdir();
    let expected = converted_to_a_file(dir.path());
    let out = crest()
        .arg("convert")
        .arg(crate::util::repo(CONTACT_SAMPLE))
        .args(["-o", "/dev/stdout"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(String::from_utf8(out.stdout).unwrap(), expected);
}
