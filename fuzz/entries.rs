//! The fuzz targets' bodies, shared by `fuzz/fuzz_targets/*.rs` (cargo-fuzz) and the
//! integration test that replays the committed corpora on the stable toolchain: each feeds
//! arbitrary bytes to one reader of untrusted input and must return (an error is fine; a
//! panic, an abort or a hang is a bug).

use std::path::Path;

/// CLSF text through the reader and the lowering.
pub fn clsf(data: &[u8]) {
    read(data, crest::io::toolpath::InputKind::Clsf, None);
}

/// contact12 text through the reader and the lowering.
pub fn contact12(data: &[u8]) {
    read(data, crest::io::toolpath::InputKind::Contact12, None);
}

/// G-code through the reader and the Table I machine's forward kinematics.
pub fn gcode(data: &[u8]) {
    let machine =
        crest::kinematics::Machine::from_toml_str(crest::kinematics::machine::TABLE_I_AC_TOML).ok();
    read(data, crest::io::toolpath::InputKind::Gcode, machine);
}

fn read(
    data: &[u8],
    kind: crest::io::toolpath::InputKind,
    machine: Option<crest::kinematics::Machine>,
) {
    let opts = crest::io::toolpath::ReadOptions {
        machine,
        ..Default::default()
    };
    let mut sink = |_: &crest::toolpath::Toolpath, _: &crest::toolpath::Posture| Ok(());
    let _ = crest::io::toolpath::stream_from(Path::new("fuzz"), kind, data, opts, &mut sink);
}

/// Height maps: the first byte picks the format (CSV grid, x,y,z, GSF, SDF).
pub fn heightmap(data: &[u8]) {
    use crest::io::{HeightMapFormat, ReadOptions, parse_heightmap};
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let format = match pick % 12 {
        0 => HeightMapFormat::Csv,
        1 => HeightMapFormat::Xyz,
        2 => HeightMapFormat::Gsf,
        3 => HeightMapFormat::Sdf,
        4 => HeightMapFormat::X3p,
        5 => HeightMapFormat::Sur,
        6 => HeightMapFormat::Al3d,
        7 => HeightMapFormat::Gwy,
        8 => HeightMapFormat::Plu,
        9 => HeightMapFormat::Plux,
        10 => HeightMapFormat::Opd,
        _ => HeightMapFormat::Vk4,
    };
    let opts = ReadOptions {
        dx_um: if pick % 12 < 4 { Some(1.0) } else { None },
        ..Default::default()
    };
    if let Ok(map) = parse_heightmap(rest, format, &opts) {
        let set = crest::metrics::ParamSet::all(false);
        let _ = crest::metrics::areal_parameters(&map, &set);
    }
}

/// TOML configs: the first byte picks the schema (tool, process, machine, design, run-out
/// study, regression study).
pub fn config(data: &[u8]) {
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    match pick % 6 {
        0 => drop(crest::config::load_tool_toml(text)),
        1 => drop(crest::config::ProcessConfig::parse(text, "fuzz")),
        2 => drop(crest::kinematics::Machine::from_toml_str(text)),
        3 => drop(crest::config::design::parse_design(text, "fuzz")),
        4 => drop(crest::config::runout::parse_study(text)),
        _ => drop(crest::config::regression::parse_study(text, "fuzz")),
    }
}

/// The measured-table reader.
pub fn measured(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data)
        && let Ok(table) = crest::io::measured::parse_measured(text, "fuzz")
    {
        let _ = crest::study::measured::summarize(&table);
    }
}

/// Meshes: the first byte picks the format (STL, OBJ, PLY).
pub fn mesh(data: &[u8]) {
    use crest::io::mesh::{MeshFormat, part_from_bytes};
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let format = match pick % 3 {
        0 => MeshFormat::Stl,
        1 => MeshFormat::Obj,
        _ => MeshFormat::Ply,
    };
    let _ = part_from_bytes(rest, format, "fuzz");
}
