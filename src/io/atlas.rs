//! The roughness atlas written as a table (`atlas.csv`, the csv crate) and as an ASCII PLY
//! point cloud (`atlas.ply`: x y z nx ny nz and every number column as a float property,
//! `nan` where a patch has none), one row or point per patch, in patch order. `crest view
//! atlas.ply --colour-by COLUMN` reads the cloud back ([`super::mesh::read_map_ply_column`]).

use crate::study::atlas::{AtlasRow, NUMBER_COLUMNS};
use std::io::Write;

/// The columns before the numbers.
pub const PLACE_COLUMNS: [&str; 11] = [
    "patch", "path", "region", "pass", "s_mm", "x", "y", "z", "nx", "ny", "nz",
];

fn number(v: f64) -> String {
    if v.is_finite() {
        // Shortest round-trip decimal: the table holds the numbers bit for bit.
        format!("{v}")
    } else {
        "nan".to_string()
    }
}

/// Write the rows as CSV: [`PLACE_COLUMNS`], [`NUMBER_COLUMNS`], `warnings` (the row's
/// warnings joined by " | "; empty when none). A number a patch did not produce is empty.
pub fn write_atlas_csv(rows: &[AtlasRow], w: &mut dyn Write) -> std::io::Result<()> {
    let mut csv = csv::Writer::from_writer(w);
    let header: Vec<&str> = PLACE_COLUMNS
        .iter()
        .chain(NUMBER_COLUMNS.iter())
        .copied()
        .chain(std::iter::once("warnings"))
        .collect();
    csv.write_record(&header)?;
    for r in rows {
        let mut rec: Vec<String> = vec![
            r.patch.to_string(),
            r.path.to_string(),
            r.region.to_string(),
            r.pass.to_string(),
            number(r.s_mm),
        ];
        rec.extend(r.point.iter().chain(r.normal.iter()).map(|v| number(*v)));
        rec.extend(r.numbers().iter().map(|v| {
            if v.is_finite() {
                number(*v)
            } else {
                String::new()
            }
        }));
        rec.push(r.warnings.join(" | "));
        csv.write_record(&rec)?;
    }
    csv.flush()
}

/// Write the rows as an ASCII PLY point cloud: x y z nx ny nz, then `patch`, `region`,
/// `warnings` (how many) and [`NUMBER_COLUMNS`] as float properties (`nan`: none).
pub fn write_atlas_ply(rows: &[AtlasRow], w: &mut dyn Write) -> std::io::Result<()> {
    writeln!(w, "ply")?;
    writeln!(w, "format ascii 1.0")?;
    writeln!(
        w,
        "comment crest roughness atlas: one point per patch; heights in µm, nan = no number"
    )?;
    writeln!(w, "element vertex {}", rows.len())?;
    for p in [
        "x", "y", "z", "nx", "ny", "nz", "patch", "region", "warnings",
    ]
    .iter()
    .chain(NUMBER_COLUMNS.iter())
    {
        writeln!(w, "property float {p}")?;
    }
    writeln!(w, "end_header")?;
    for r in rows {
        let mut v: Vec<String> = r
            .point
            .iter()
            .chain(r.normal.iter())
            .map(|v| number(*v))
            .collect();
        v.push(r.patch.to_string());
        v.push(r.region.to_string());
        v.push(r.warnings.len().to_string());
        v.extend(r.numbers().iter().map(|v| number(*v)));
        writeln!(w, "{}", v.join(" "))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_and_ply_hold_the_same_numbers() {
        let row = AtlasRow {
            patch: 1,
            path: 1,
            region: 1,
            pass: 3,
            s_mm: 2.5,
            point: [1.0, 2.0, 3.0],
            normal: [0.0, 0.0, 1.0],
            sa_um: Some(0.1),
            sq_um: Some(0.2),
            sz_um: Some(1.0 / 3.0),
            scallop_um: None,
            feed_mark_um: None,
            scallop_closed_um: None,
            feed_mark_closed_um: None,
            stepover_mm: Some(0.5),
            curvature_along_per_mm: None,
            curvature_across_per_mm: None,
            lead_deg: Some(10.0),
            tilt_deg: Some(-5.0),
            nodes: 100,
            nodes_cut: 99,
            warnings: vec!["a, b".into()],
        };
        let mut csv = Vec::new();
        write_atlas_csv(std::slice::from_ref(&row), &mut csv).unwrap_or_else(|e| panic!("{e}"));
        let text = String::from_utf8(csv).unwrap_or_default();
        assert!(text.contains("0.3333333333333333"), "{text}");
        assert!(text.ends_with(",100,99,\"a, b\"\n"), "{text}");
        let mut ply = Vec::new();
        write_atlas_ply(&[row], &mut ply).unwrap_or_else(|e| panic!("{e}"));
        let text = String::from_utf8(ply).unwrap_or_default();
        assert!(text.contains("property float Sa_um"));
        assert!(
            text.lines()
                .last()
                .unwrap_or("")
                .starts_with("1 2 3 0 0 1 1 1 1 0.1 0.2")
        );
    }
}
