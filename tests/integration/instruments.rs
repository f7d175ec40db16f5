//! The instruments' own height-map files (issue 34): `.sur`, `.al3d`, `.gwy`, `.plu`,
//! `.plux`, `.opd`, `.vk4`, each written byte by byte here from its format's layout (as
//! surfalize and Gwyddion read it), read back to the exact heights, spacing and missing
//! nodes; every format told by content; truncated and damaged files refused, never a panic;
//! the command line exits 2 naming the file and the field and writes nothing; `.datx`
//! refused by name.

use std::io::Write;

use crest::io::{HeightMapFormat, ReadOptions, parse_heightmap, read_heightmap};

use crate::util::{crest, tempdir, write};

// ---- writers of each layout ----

fn put(b: &mut [u8], at: usize, v: &[u8]) {
    b[at..at + v.len()].copy_from_slice(v);
}

/// A `.sur` object: 512-byte header, a comment, then the points (plain or one zlib stream).
#[allow(clippy::too_many_arguments)]
fn sur_object(
    compressed: bool,
    n_objects: i16,
    studiable: i16,
    (nx, ny): (i32, i32),
    step: [f32; 3],
    units: [&str; 3],
    offset: [f32; 3],
    (bits, min_point, non_measured): (i16, i32, i16),
    points: &[i32],
) -> Vec<u8> {
    let mut h = vec![0u8; 512];
    put(
        &mut h,
        0,
        if compressed {
            b"DSCOMPRESSED"
        } else {
            b"DIGITAL SURF"
        },
    );
    put(&mut h, 14, &n_objects.to_le_bytes());
    put(&mut h, 16, &1i16.to_le_bytes());
    put(&mut h, 18, &studiable.to_le_bytes());
    put(&mut h, 86, &non_measured.to_le_bytes());
    put(&mut h, 98, &bits.to_le_bytes());
    put(&mut h, 100, &min_point.to_le_bytes());
    put(&mut h, 104, &i32::MAX.to_le_bytes());
    put(&mut h, 108, &nx.to_le_bytes());
    put(&mut h, 112, &ny.to_le_bytes());
    put(&mut h, 116, &(nx * ny).to_le_bytes());
    for k in 0..3 {
        put(&mut h, 120 + 4 * k, &step[k].to_le_bytes());
        put(&mut h, 180 + 16 * k, units[k].as_bytes());
        put(&mut h, 228 + 16 * k, units[k].as_bytes());
        put(&mut h, 466 + 4 * k, &offset[k].to_le_bytes());
    }
    let comment = b"made by hand";
    put(&mut h, 334, &(comment.len() as i16).to_le_bytes());
    let mut raw = Vec::new();
    for &p in points {
        if bits == 16 {
            raw.extend_from_slice(&(p as i16).to_le_bytes());
        } else {
            raw.extend_from_slice(&p.to_le_bytes());
        }
    }
    let mut data = Vec::new();
    if compressed {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&raw).unwrap();
        let zipped = z.finish().unwrap();
        data.extend_from_slice(&1u32.to_le_bytes());
        data.extend_from_slice(&(raw.len() as u32).to_le_bytes());
        data.extend_from_slice(&(zipped.len() as u32).to_le_bytes());
        data.extend_from_slice(&zipped);
        put(&mut h, 324, &(data.len() as u32).to_le_bytes());
    } else {
        data = raw;
    }
    let mut out = h;
    out.extend_from_slice(comment);
    out.extend_from_slice(&data);
    out
}

fn sur_simple(compressed: bool, bits: i16) -> Vec<u8> {
    let min = if bits == 16 { -30000 } else { i32::MIN + 2 };
    sur_object(
        compressed,
        1,
        2,
        (3, 2),
        [0.5, 0.25, 0.001],
        ["µm", "µm", "µm"],
        [1000.0, -500.0, 0.5],
        (bits, min, 1),
        &[100, -200, 300, min - 2, 0, 32000],
    )
}

fn al3d(nx: usize, ny: usize, depths: &[f32], invalid: Option<&str>) -> Vec<u8> {
    let mut tags: Vec<(&str, String)> = vec![
        ("Cols", nx.to_string()),
        ("Rows", ny.to_string()),
        ("PixelSizeXMeter", "2e-06".into()),
        ("PixelSizeYMeter", "3e-06".into()),
        ("NumberOfPlanes", "0".into()),
        ("TextureImageOffset", "0".into()),
    ];
    if let Some(v) = invalid {
        tags.push(("InvalidPixelValue", v.into()));
    }
    let header = 17 + 52 * (tags.len() + 3);
    tags.push(("DepthImageOffset", header.to_string()));
    let mut out = b"AliconaImaging\x00\r\n".to_vec();
    let tag = |out: &mut Vec<u8>, k: &str, v: &str| {
        let mut t = [0u8; 52];
        put(&mut t, 0, k.as_bytes());
        put(&mut t, 20, v.as_bytes());
        put(&mut t, 50, b"\r\n");
        out.extend_from_slice(&t);
    };
    tag(&mut out, "Version", "1");
    tag(&mut out, "TagCount", &tags.len().to_string());
    for (k, v) in &tags {
        tag(&mut out, k, v);
    }
    assert_eq!(out.len(), header);
    let stride = (nx * 4).div_ceil(8) * 8;
    for i in 0..ny {
        let mut row = vec![0u8; stride];
        for j in 0..nx {
            put(&mut row, 4 * j, &depths[i * nx + j].to_le_bytes());
        }
        out.extend_from_slice(&row);
    }
    out
}

pub(crate) fn gwy_comp(name: &str, ty: u8, payload: &[u8]) -> Vec<u8> {
    let mut c = name.as_bytes().to_vec();
    c.push(0);
    c.push(ty);
    c.extend_from_slice(payload);
    c
}

pub(crate) fn gwy_obj(name: &str, comps: &[Vec<u8>]) -> Vec<u8> {
    let body: Vec<u8> = comps.concat();
    let mut o = name.as_bytes().to_vec();
    o.push(0);
    o.extend_from_slice(&(body.len() as u32).to_le_bytes());
    o.extend_from_slice(&body);
    o
}

pub(crate) fn gwy_str(s: &str) -> Vec<u8> {
    let mut v = s.as_bytes().to_vec();
    v.push(0);
    v
}

pub(crate) fn gwy_field(
    nx: i32,
    ny: i32,
    real: (f64, f64),
    off: f64,
    units: (&str, &str),
    z: &[f64],
) -> Vec<u8> {
    let unit = |u: &str| gwy_obj("GwySIUnit", &[gwy_comp("unitstr", b's', &gwy_str(u))]);
    let mut data = (z.len() as u32).to_le_bytes().to_vec();
    for v in z {
        data.extend_from_slice(&v.to_le_bytes());
    }
    gwy_obj(
        "GwyDataField",
        &[
            gwy_comp("xres", b'i', &nx.to_le_bytes()),
            gwy_comp("yres", b'i', &ny.to_le_bytes()),
            gwy_comp("xreal", b'd', &real.0.to_le_bytes()),
            gwy_comp("yreal", b'd', &real.1.to_le_bytes()),
            gwy_comp("xoff", b'd', &off.to_le_bytes()),
            gwy_comp("si_unit_xy", b'o', &unit(units.0)),
            gwy_comp("si_unit_z", b'o', &unit(units.1)),
            gwy_comp("data", b'D', &data),
        ],
    )
}

/// Two channels: 0 "Intensity" (no length unit), 1 "Height" (nm) with a mask, 2 "Height
/// copy" (mm).
fn gwy() -> Vec<u8> {
    let z = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
    let mut out = b"GWYP".to_vec();
    out.extend_from_slice(&gwy_obj(
        "GwyContainer",
        &[
            gwy_comp(
                "/0/data",
                b'o',
                &gwy_field(3, 2, (3e-6, 2e-6), 0.0, ("m", ""), &z),
            ),
            gwy_comp("/0/data/title", b's', &gwy_str("Intensity")),
            gwy_comp(
                "/1/data",
                b'o',
                &gwy_field(3, 2, (6e-6, 1e-6), 1e-3, ("m", "nm"), &z),
            ),
            gwy_comp("/1/data/title", b's', &gwy_str("Height")),
            gwy_comp(
                "/1/mask",
                b'o',
                &gwy_field(
                    3,
                    2,
                    (6e-6, 1e-6),
                    0.0,
                    ("m", ""),
                    &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
                ),
            ),
            gwy_comp(
                "/2/data",
                b'o',
                &gwy_field(3, 2, (3e-6, 3e-6), 0.0, ("m", "mm"), &z),
            ),
            gwy_comp("/2/data/title", b's', &gwy_str("Height copy")),
            gwy_comp("/filename", b's', &gwy_str("made by hand")),
        ],
    ));
    out
}

fn plu(nx: u32, ny: u32, z: &[f32]) -> Vec<u8> {
    let mut out = vec![0u8; 500];
    put(&mut out, 0, b"01/02/2024 10:20:30");
    let c = 388;
    put(&mut out, c, &ny.to_le_bytes());
    put(&mut out, c + 4, &nx.to_le_bytes());
    put(&mut out, c + 16, &0.5f32.to_le_bytes());
    put(&mut out, c + 20, &0.75f32.to_le_bytes());
    for v in z {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

fn plux(nx: u32, ny: u32, z: &[f32]) -> Vec<u8> {
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    w.start_file("index.xml", o).unwrap();
    write!(
        w,
        "<?xml version=\"1.0\"?><xml><GENERAL><DATE>01/02/2024 10:20:30</DATE><IMAGE_SIZE_X>{nx}</IMAGE_SIZE_X><IMAGE_SIZE_Y>{ny}</IMAGE_SIZE_Y><FOV_X>0.345</FOV_X><FOV_Y>0.5</FOV_Y></GENERAL></xml>"
    )
    .unwrap();
    w.start_file("LAYER_0.raw", o).unwrap();
    for v in z {
        w.write_all(&v.to_le_bytes()).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// An `.opd`: RAW_DATA int16 `nx` × `ny` stored `ny` fastest, Wavelength 632.8 nm, Mult
/// 2, Pixel_size 0.002 mm, Aspect 1.5.
fn opd(nx: u16, ny: u16, raw: &[i16]) -> Vec<u8> {
    let mut blocks: Vec<(&str, i16, Vec<u8>)> = Vec::new();
    let mut a = Vec::new();
    for v in [nx, ny, 2] {
        a.extend_from_slice(&v.to_le_bytes());
    }
    for v in raw {
        a.extend_from_slice(&v.to_le_bytes());
    }
    blocks.push(("RAW_DATA", 3, a));
    blocks.push(("Wavelength", 7, 632.8f32.to_le_bytes().to_vec()));
    blocks.push(("Mult", 6, 2i16.to_le_bytes().to_vec()));
    blocks.push(("Pixel_size", 7, 0.002f32.to_le_bytes().to_vec()));
    blocks.push(("Aspect", 7, 1.5f32.to_le_bytes().to_vec()));
    let mut out = vec![1u8, 0];
    let entry = |out: &mut Vec<u8>, name: &str, ty: i16, size: i32| {
        let mut e = [0u8; 24];
        put(&mut e, 0, name.as_bytes());
        put(&mut e, 16, &ty.to_le_bytes());
        put(&mut e, 18, &size.to_le_bytes());
        out.extend_from_slice(&e);
    };
    entry(&mut out, "Directory", 1, 24 * (blocks.len() as i32 + 1));
    for (n, t, d) in &blocks {
        entry(&mut out, n, *t, d.len() as i32);
    }
    for (_, _, d) in &blocks {
        out.extend_from_slice(d);
    }
    out
}

fn vk4(nx: u32, ny: u32, z: &[u16]) -> Vec<u8> {
    let conds = 84usize;
    let strings = conds + 304;
    let layer = strings + 8;
    let mut out = vec![0u8; layer + 796 + 2 * z.len()];
    put(&mut out, 0, b"VK4_");
    put(&mut out, 12, &(conds as u32).to_le_bytes());
    put(&mut out, 36, &(layer as u32).to_le_bytes());
    put(&mut out, 76, &(strings as u32).to_le_bytes());
    put(&mut out, conds, &304u32.to_le_bytes());
    for (k, v) in [2024u32, 1, 2].iter().enumerate() {
        put(&mut out, conds + 4 + 4 * k, &v.to_le_bytes());
    }
    put(&mut out, conds + 168, &138_000u32.to_le_bytes());
    put(&mut out, conds + 172, &139_000u32.to_le_bytes());
    put(&mut out, conds + 176, &1_000u32.to_le_bytes());
    for (k, v) in [nx, ny, 16, 0, 2 * nx * ny].iter().enumerate() {
        put(&mut out, layer + 4 * k, &v.to_le_bytes());
    }
    for (k, v) in z.iter().enumerate() {
        put(&mut out, layer + 796 + 2 * k, &v.to_le_bytes());
    }
    out
}

// ---- reading ----

fn read(bytes: &[u8], f: HeightMapFormat) -> crest::surface::HeightMap {
    parse_heightmap(bytes, f, &ReadOptions::default()).unwrap_or_else(|e| panic!("{f:?}: {e}"))
}

fn same(got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len());
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g.is_nan() && w.is_nan()) || g == w,
            "node {k}: {g} against {w} ({got:?})"
        );
    }
}

#[test]
fn sur_plain_compressed_16_and_32_bit() {
    for compressed in [false, true] {
        for bits in [16, 32] {
            let m = read(&sur_simple(compressed, bits), HeightMapFormat::Sur);
            assert_eq!((m.nx, m.ny), (3, 2));
            assert_eq!((m.dx_um, m.dy_um), (0.5, 0.25));
            assert_eq!((m.x0_mm, m.y0_mm), (1.0, -0.5));
            let dz = f64::from(0.001f32);
            let want: Vec<f64> = [100.0, -200.0, 300.0, f64::NAN, 0.0, 32000.0]
                .iter()
                .map(|v: &f64| v * dz + 0.5)
                .collect();
            same(&m.z_um, &want);
        }
    }
}

#[test]
fn sur_units_and_the_height_layer_of_several() {
    // nm heights, mm spacing.
    let b = sur_object(
        false,
        1,
        2,
        (2, 1),
        [0.002, 0.003, 2.0],
        ["mm", "mm", "nm"],
        [0.0; 3],
        (32, 0, 0),
        &[5, -7],
    );
    let m = read(&b, HeightMapFormat::Sur);
    assert_eq!(
        (m.dx_um, m.dy_um),
        (f64::from(0.002f32) * 1e3, f64::from(0.003f32) * 1e3)
    );
    same(&m.z_um, &[10.0 * 1e-3, -14.0 * 1e-3]);
    // An intensity layer (no length unit) first, then the heights.
    let mut two = sur_object(
        false,
        2,
        2,
        (2, 1),
        [1.0, 1.0, 1.0],
        ["µm", "µm", ""],
        [0.0; 3],
        (16, 0, 0),
        &[9, 9],
    );
    two.extend(sur_object(
        true,
        2,
        2,
        (2, 1),
        [1.0, 1.0, 1.0],
        ["µm", "µm", "µm"],
        [0.0; 3],
        (16, 0, 0),
        &[3, 4],
    ));
    same(&read(&two, HeightMapFormat::Sur).z_um, &[3.0, 4.0]);
    // Unknown z unit everywhere: refused, the unit named.
    let bad = sur_object(
        false,
        1,
        2,
        (2, 1),
        [1.0, 1.0, 1.0],
        ["µm", "µm", "V"],
        [0.0; 3],
        (16, 0, 0),
        &[1, 2],
    );
    let e = parse_heightmap(&bad, HeightMapFormat::Sur, &ReadOptions::default()).unwrap_err();
    assert!(e.message.contains("\"V\""), "{e}");
    // A lying point count.
    let mut lying = sur_simple(false, 32);
    put(&mut lying, 116, &7i32.to_le_bytes());
    let e = parse_heightmap(&lying, HeightMapFormat::Sur, &ReadOptions::default()).unwrap_err();
    assert!(e.message.contains("n_total_points"), "{e}");
    // A corrupt zlib stream.
    let mut corrupt = sur_simple(true, 32);
    let n = corrupt.len();
    corrupt[n - 8] ^= 0xff;
    let e = parse_heightmap(&corrupt, HeightMapFormat::Sur, &ReadOptions::default()).unwrap_err();
    assert!(e.message.contains("zlib"), "{e}");
}

#[test]
fn al3d_depths_in_metres_and_invalid_points() {
    let d = [1e-6f32, -2.5e-6, 3e15, f32::NAN, 0.0, 7.25e-6];
    for invalid in [None, Some("3e15"), Some("nan")] {
        let m = read(&al3d(3, 2, &d, invalid), HeightMapFormat::Al3d);
        assert_eq!((m.nx, m.ny), (3, 2));
        assert_eq!((m.dx_um, m.dy_um), (2e-6 * 1e6, 3e-6 * 1e6));
        let want: Vec<f64> = d
            .iter()
            .map(|&v| {
                if v < 3e15 {
                    f64::from(v) * 1e6
                } else {
                    f64::NAN
                }
            })
            .collect();
        same(&m.z_um, &want);
    }
    let e = parse_heightmap(
        &al3d(2, 1, &[5e15, 5e15], None),
        HeightMapFormat::Al3d,
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(e.message.contains("every height"), "{e}");
}

#[test]
fn gwy_first_height_channel_named_channel_mask_and_units() {
    let b = gwy();
    let m = read(&b, HeightMapFormat::Gwy);
    // Channel 0 has no length unit: channel 1 (nm) is the first height channel.
    assert_eq!((m.nx, m.ny), (3, 2));
    assert_eq!(m.dx_um, 6e-6 / 3.0 * 1e6);
    assert_eq!(m.dy_um, 1e-6 / 2.0 * 1e6);
    assert_eq!(m.x0_mm, 1e-3 * 1e6 * 1e-3);
    same(&m.z_um, &[1e-3, f64::NAN, 3e-3, 4e-3, 5e-3, 6e-3]);
    let opts = ReadOptions {
        channel: Some("Height copy".into()),
        ..Default::default()
    };
    let m = parse_heightmap(&b, HeightMapFormat::Gwy, &opts).unwrap();
    same(&m.z_um, &[1e3, 2e3, 3e3, 4e3, 5e3, 6e3]);
    let opts = ReadOptions {
        channel: Some("Phase".into()),
        ..Default::default()
    };
    let e = parse_heightmap(&b, HeightMapFormat::Gwy, &opts).unwrap_err();
    assert!(
        e.message.contains("Phase") && e.message.contains("Height copy"),
        "{e}"
    );
    // --channel on another format is refused.
    let e = parse_heightmap(&sur_simple(false, 16), HeightMapFormat::Sur, &opts).unwrap_err();
    assert!(e.message.contains("‹channel›"), "{e}");
}

#[test]
fn plu_plux_opd_vk4() {
    let z = [1.5f32, -2.25, 1_000_001.0, 4.0, f32::NAN, 6.0];
    let m = read(&plu(3, 2, &z), HeightMapFormat::Plu);
    assert_eq!((m.dx_um, m.dy_um), (0.5, 0.75));
    same(&m.z_um, &[1.5, -2.25, f64::NAN, 4.0, f64::NAN, 6.0]);

    let m = read(&plux(3, 2, &z), HeightMapFormat::Plux);
    assert_eq!((m.dx_um, m.dy_um), (0.345, 0.5));
    same(&m.z_um, &[1.5, -2.25, f64::NAN, 4.0, f64::NAN, 6.0]);

    // Stored nx = 3 lines of ny = 2: a[j][k] = raw[j * 2 + k]; map[i][j] = a[j][1 - i].
    let raw = [10i16, 20, 30, 32767, 50, -60];
    let m = read(&opd(3, 2, &raw), HeightMapFormat::Opd);
    assert_eq!((m.nx, m.ny), (3, 2));
    let px = f64::from(0.002f32) * 1000.0;
    assert_eq!((m.dx_um, m.dy_um), (px, px * 1.5));
    let s = f64::from(632.8f32) * 0.001 / 2.0;
    same(
        &m.z_um,
        &[20.0 * s, f64::NAN, -60.0 * s, 10.0 * s, 30.0 * s, 50.0 * s],
    );

    let m = read(&vk4(3, 2, &[0, 1, 2, 3, 65535, 7]), HeightMapFormat::Vk4);
    assert_eq!((m.dx_um, m.dy_um), (138_000.0 * 1e-6, 139_000.0 * 1e-6));
    let s = 1e-6 * 1000.0;
    same(&m.z_um, &[0.0, s, 2.0 * s, 3.0 * s, 65535.0 * s, 7.0 * s]);
}

/// Every file of every format and where its format is told: by content (with a magic).
fn every_file() -> Vec<(&'static str, HeightMapFormat, Vec<u8>)> {
    let z = [1.5f32, -2.25, 3.0, 4.0];
    vec![
        ("sur", HeightMapFormat::Sur, sur_simple(false, 32)),
        ("sur", HeightMapFormat::Sur, sur_simple(true, 16)),
        (
            "al3d",
            HeightMapFormat::Al3d,
            al3d(2, 2, &[1e-6, 2e-6, 3e-6, 4e-6], None),
        ),
        ("gwy", HeightMapFormat::Gwy, gwy()),
        ("plu", HeightMapFormat::Plu, plu(2, 2, &z)),
        ("plux", HeightMapFormat::Plux, plux(2, 2, &z)),
        ("opd", HeightMapFormat::Opd, opd(2, 2, &[1, 2, 3, 4])),
        ("vk4", HeightMapFormat::Vk4, vk4(2, 2, &[1, 2, 3, 4])),
    ]
}

#[test]
fn formats_are_told_by_content() {
    for (ext, f, b) in every_file() {
        assert_eq!(
            HeightMapFormat::from_path(std::path::Path::new(&format!("a.{ext}"))),
            Some(f)
        );
        if f != HeightMapFormat::Plu {
            assert_eq!(HeightMapFormat::sniff(&b), f, "{ext}");
        }
    }
    // A file without extension is read by its content, and so is a file whose extension
    // names another format than its content (its errors say what the content is).
    let dir = tempdir();
    let p = write(dir.path(), "measured", sur_simple(false, 32));
    let m = read_heightmap(&p, &ReadOptions::default()).unwrap();
    assert_eq!((m.nx, m.ny), (3, 2));
    let p = write(dir.path(), "misnamed.sur", gwy());
    let m = read_heightmap(&p, &ReadOptions::default()).unwrap();
    assert_eq!((m.nx, m.ny, m.dx_um), (3, 2, 2.0));
    let mut bad = al3d(2, 2, &[1e-6, 2e-6, 3e-6, 4e-6], None);
    bad.truncate(bad.len() - 3);
    let p = write(dir.path(), "misnamed.opd", bad);
    let e = read_heightmap(&p, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("misnamed.opd") && e.contains("content is a .al3d"),
        "{e}"
    );
}

/// Every cut of every file is an error (never a panic), and so is or reads every file with
/// any one byte changed.
#[test]
fn truncated_and_damaged_files_are_errors_not_panics() {
    for (ext, f, b) in every_file() {
        for cut in 0..b.len() {
            let r = parse_heightmap(&b[..cut], f, &ReadOptions::default());
            assert!(r.is_err(), "{ext} cut at {cut} of {} read", b.len());
        }
        for k in 0..b.len() {
            for x in [0x01u8, 0x80, 0xff] {
                let mut d = b.clone();
                d[k] ^= x;
                let _ = parse_heightmap(&d, f, &ReadOptions::default());
            }
        }
    }
}

#[test]
fn the_command_line_refuses_bad_files_naming_file_and_field_and_writes_nothing() {
    let dir = tempdir();
    let mut lying = sur_simple(false, 32);
    put(&mut lying, 112, &1000i32.to_le_bytes());
    let p = write(dir.path(), "lying.sur", &lying);
    let out = dir.path().join("out.csv");
    let a = crest()
        .args(["convert", p.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(
        err.contains("lying.sur") && err.contains("n_lines"),
        "{err}"
    );
    assert!(!out.exists());

    let p = write(dir.path(), "m.datx", b"\x89HDF\r\n\x1a\n\0\0\0\0");
    let a = crest()
        .args(["metrics", p.to_str().unwrap()])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("m.datx") && err.contains("HDF5"), "{err}");

    // A good file converts, and --channel picks a .gwy channel.
    let g = write(dir.path(), "m.gwy", gwy());
    let x3p = dir.path().join("m.x3p");
    crest()
        .args(["convert", g.to_str().unwrap(), "-o", x3p.to_str().unwrap()])
        .args(["--channel", "Height copy"])
        .assert()
        .success();
    let m = read_heightmap(&x3p, &ReadOptions::default()).unwrap();
    assert_eq!(m.z_um[1], 2e3);
    // Instruments' formats are not written.
    crest()
        .args(["convert", x3p.to_str().unwrap(), "-o"])
        .arg(dir.path().join("m2.sur"))
        .assert()
        .code(2);
    assert!(!dir.path().join("m2.sur").exists());
}
