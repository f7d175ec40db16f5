//! What the tool and machine records of the APT family mean to the lowering: `TLDATA`,
//! `CUTTER`, `SPINDL`, tool changes (`LOAD/TOOL`, `LOADTL`) and the records other CAM
//! systems write and NX does not (`PPRINT`, `TPRINT`, `PARTNO`, `MULTAX`, `TLAXIS`,
//! `INDIRV`, `SET/MODE`, `FINI`, `END`).
//!
//! Files of the wider APT family (CATIA, NCL, Makino FFCAM, …) have no `TOOL PATH`
//! records: their motion is one path per tool, named by `PARTNO`, with the tool of the
//! last `CUTTER`. A tool change (`LOADTL`, `CUTTER`) after motion starts the next path.

use super::{
    Lowerer, PostureSink, RAW_LIMIT, SEEN_LIMIT, check_rate, invalid, unit_as_written, vec3,
};
use crate::parse::{Arg, Numbers, RecordKind};
use crate::toolpath::{LowerError, RawRecord, ToolData};

/// Hold a tool of the file to the limits of `tool.toml` ([`crate::math::limits::tool_radius`],
/// [`crate::math::limits::corner_radius`]): D/2 in (0, 500] mm, the corner radius in [0, D/2]
/// (APT's seven-parameter shapes place their corner themselves: only finite and ≥ 0).
fn check_tool(tool: &ToolData, record: &str, line: u32, column: u32) -> Result<(), LowerError> {
    use crate::math::limits;
    let r = 0.5 * tool.diameter_mm;
    limits::tool_radius(r).map_err(|m| {
        invalid(
            line,
            column,
            &format!("a {record} radius D/2 that {m}"),
            format!("D {} mm", crate::math::limits::shown(tool.diameter_mm)),
        )
    })?;
    let bound = if tool.apt.is_some() { f64::INFINITY } else { r };
    limits::corner_radius(tool.corner_radius_mm, bound).map_err(|m| {
        invalid(
            line,
            column,
            &format!("a {record} corner radius that {m}"),
            format!("{} mm", tool.corner_radius_mm),
        )
    })?;
    Ok(())
}

impl Lowerer {
    /// Tool data of a `TLDATA` record.
    pub(super) fn tldata(
        &self,
        kind: &str,
        args: &[Arg],
        line: u32,
        column: u32,
    ) -> Result<ToolData, LowerError> {
        let nums: Vec<f64> = args
            .iter()
            .filter_map(|a| match a {
                Arg::Num(v) => Some(*v),
                Arg::Word(_) => None,
            })
            .collect();
        let s = self.scale();
        let get = |k: usize| nums.get(k).copied().unwrap_or(0.0);
        let tool = match kind {
            // NX's seven-parameter mill, `TLDATA/MILL,D,R1,L,B,A,X1,Y1`: the corner centre
            // (X1 from the axis, Y1 above the tip) makes it APT's `CUTTER/D,R1,X1,Y1,A,B,L`.
            "MILL" => ToolData {
                kind: kind.to_string(),
                diameter_mm: get(0) * s,
                corner_radius_mm: get(1) * s,
                length_mm: get(2) * s,
                taper_rad: get(3).to_radians(),
                tip_rad: get(4).to_radians(),
                apt: (nums.len() == 7).then(|| {
                    [
                        get(0) * s,
                        get(1) * s,
                        get(5) * s,
                        get(6) * s,
                        get(4).to_radians(),
                        get(3).to_radians(),
                        get(2) * s,
                    ]
                }),
            },
            "DRILL" => ToolData {
                kind: kind.to_string(),
                diameter_mm: get(0) * s,
                corner_radius_mm: get(1) * s,
                length_mm: get(2) * s,
                taper_rad: 0.0,
                tip_rad: get(3).to_radians(),
                apt: None,
            },
            _ => ToolData {
                kind: kind.to_string(),
                ..Default::default()
            },
        };
        if kind == "MILL" && nums.len() < 2 {
            return Err(invalid(
                line,
                column,
                "TLDATA/MILL with at least diameter and corner radius",
                format!("{} numbers", nums.len()),
            ));
        }
        if kind == "MILL" || kind == "DRILL" {
            check_tool(&tool, &format!("TLDATA/{kind}"), line, column)?;
        }
        Ok(tool)
    }

    /// Tool data of `CUTTER/d[,r[,e,f,a,b[,h]]]`: diameter, corner radius, then the corner
    /// centre (e from the axis, f above the tip), the end angle a, the side angle b and
    /// the height h. All seven are kept in [`ToolData::apt`].
    fn cutter_tool(&self, n: &Numbers, line: u32, column: u32) -> Result<ToolData, LowerError> {
        let s = self.scale();
        let v = n.as_slice();
        let get = |k: usize| v.get(k).copied().unwrap_or(0.0);
        let apt = (v.len() == 7).then(|| {
            [
                get(0) * s,
                get(1) * s,
                get(2) * s,
                get(3) * s,
                get(4).to_radians(),
                get(5).to_radians(),
                get(6) * s,
            ]
        });
        let tool = ToolData {
            kind: "MILL".to_string(),
            diameter_mm: get(0) * s,
            corner_radius_mm: get(1) * s,
            length_mm: get(6) * s,
            taper_rad: get(5).to_radians(),
            tip_rad: get(4).to_radians(),
            apt,
        };
        check_tool(&tool, "CUTTER", line, column)?;
        Ok(tool)
    }

    /// A tool change. In a path of its own (`TOOL PATH`) it changes nothing; in an APT
    /// file, a change after motion ends the path, and the next motion starts a new one.
    pub(super) fn load_tool(
        &mut self,
        number: f64,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        if self.opened_by_record {
            return Ok(());
        }
        self.apt = true;
        if self.moved() {
            self.end_path(sink)?;
        }
        let label = if number.fract() == 0.0 && number.abs() < 1e9 {
            format!("T{}", number as i64)
        } else {
            format!("T{number}")
        };
        // A TPRINT of this tool names it better than its number.
        let label = self.tool_label.clone().unwrap_or(label);
        if let Some(p) = self.path.as_mut()
            && p.tool_name.is_empty()
        {
            p.tool_name = label.clone();
        }
        self.tool_label = Some(label);
        Ok(())
    }

    /// The records of the wider APT family (see the module docs).
    pub(super) fn push_apt(
        &mut self,
        kind: &RecordKind,
        line: u32,
        column: u32,
        sink: &mut PostureSink<'_>,
    ) -> Result<(), LowerError> {
        match kind {
            RecordKind::Print { word, text } => {
                let rec = RawRecord {
                    line,
                    text: format!("{word}/{text}"),
                };
                if word == "TPRINT" {
                    self.apt = true;
                    let moved = self.moved();
                    match self.path.as_mut() {
                        Some(p) if !self.opened_by_record && !moved => {
                            p.tool_name = text.clone();
                        }
                        _ => {}
                    }
                    if !self.opened_by_record {
                        self.tool_label = Some(text.clone());
                    }
                }
                match self.path.as_mut() {
                    Some(p) => {
                        if p.prints.len() < RAW_LIMIT {
                            p.prints.push(rec);
                        }
                    }
                    None => {
                        if self.notes.len() < RAW_LIMIT {
                            self.notes.push(rec);
                        }
                    }
                }
            }
            RecordKind::Partno(text) => {
                self.apt = true;
                if let Some(p) = self.path.as_mut()
                    && p.name.is_empty()
                {
                    p.name = text.clone();
                }
                self.partno = Some(text.clone());
            }
            RecordKind::Multax(_) | RecordKind::Indirv(_) | RecordKind::End => {
                // MULTAX: every GOTO says by its own count whether it carries an axis.
                // INDIRV: a direction hint of APT source, no posture. END: a program stop.
                self.apt = true;
            }
            RecordKind::Cutter(n) => {
                self.apt = true;
                let tool = self.cutter_tool(n, line, column)?;
                self.cutter = Some(tool.clone());
                let moved = self.moved();
                if self.path.is_some() && !self.opened_by_record && moved {
                    // A new cutter after motion: the next tool's path.
                    self.end_path(sink)?;
                } else if let Some(p) = self.path.as_mut() {
                    p.tool = Some(tool);
                }
            }
            RecordKind::Tlaxis(v) => {
                self.apt = true;
                self.axis = unit_as_written(vec3(*v)).ok_or_else(|| {
                    invalid(
                        line,
                        column,
                        "a unit vector",
                        format!("({}, {}, {})", v[0], v[1], v[2]),
                    )
                })?;
            }
            RecordKind::SetMode { absolute } => {
                self.apt = true;
                self.incremental = !absolute;
            }
            RecordKind::Fini => {
                self.apt = true;
                if self.path.is_some() {
                    if self.opened_by_record {
                        self.warn("no-end", line, column, "FINI before END-OF-PATH".into());
                    }
                    self.end_path(sink)?;
                }
            }
            _ => {}
        }
        Ok(())
    }

    pub(super) fn spindl(
        &mut self,
        args: &[Arg],
        line: u32,
        column: u32,
    ) -> Result<(), LowerError> {
        let speed = args.iter().find_map(|a| match a {
            Arg::Num(v) => Some(*v),
            Arg::Word(_) => None,
        });
        if args.iter().any(|a| a.is_word("OFF")) {
            self.spindle_rpm = None;
            return Ok(());
        }
        let Some(mut v) = speed else {
            return Ok(()); // SPINDL/ON keeps the last speed.
        };
        if v < 0.0 {
            self.warn(
                "spindle-sign",
                line,
                column,
                format!(
                    "spindle speed {v}: the sign is taken as the direction, speed {}",
                    -v
                ),
            );
            v = -v;
        }
        let diameter = self
            .path
            .as_ref()
            .and_then(|p| p.tool.as_ref())
            .map(|t| t.diameter_mm);
        let surface = if args.iter().any(|a| a.is_word("SMM")) {
            Some(1000.0)
        } else if args.iter().any(|a| a.is_word("SFM")) {
            Some(304.8)
        } else {
            None
        };
        let rpm = match (surface, diameter) {
            (None, _) => Some(v),
            (Some(mm_per_unit), Some(d)) if d > 0.0 => {
                Some(v * mm_per_unit / (std::f64::consts::PI * d))
            }
            (Some(_), _) => {
                self.warn(
                    "spindle-surface",
                    line,
                    column,
                    "surface speed without a tool diameter: spindle speed unknown".into(),
                );
                None
            }
        };
        if let Some(r) = rpm {
            check_rate(
                "spindle speed",
                "rpm",
                r,
                crate::math::limits::RPM,
                line,
                column,
            )?;
        }
        self.spindle_rpm = rpm;
        if let Some(fr) = self.feed_mm_rev {
            self.feed_mm_min = rpm.map(|r| fr * r);
            if let Some(f) = self.feed_mm_min {
                let feed = crate::math::limits::FEED_MM_MIN;
                check_rate("feed", "mm/min", f, feed, line, column)?;
                self.note_feed(f);
            }
        }
        if let Some(r) = rpm {
            let st = &mut self.path_mut().stats;
            if !st.spindles_rpm.contains(&r) && st.spindles_rpm.len() < SEEN_LIMIT {
                st.spindles_rpm.push(r);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::math::{Point3, Vec3};
    use crate::parse::clsf::parse_str;
    use crate::toolpath::{LowerOptions, MotionKind, Program, lower_records};
    use approx::assert_relative_eq;

    fn lower(text: &str) -> Program {
        let recs = parse_str(text).unwrap_or_else(|e| panic!("{e}"));
        lower_records(&recs, LowerOptions::default()).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn an_apt_file_without_tool_path_records() {
        let p = lower(
            "$$*CATIA0\nPARTNO BLADE\nPPRINT/ OPERATION NAME : Sweeping.1\nMULTAX\n\
             CUTTER/ 10.000000, 5.000000, 0.000000, 5.000000, 0.000000, 0.000000, 50.000000\n\
             TPRINT/T1 BALL D10\nLOADTL/1\nSPINDL/ 8000.0000,RPM,CLW\nFEDRAT/ 1000.0000,MMPM\n\
             GOTO  / 0.0, 0.0, 10.0, 0.0, 0.0, 1.0\nGOTO / 5.0, 0.0, 0.0, 0.6, 0.0, 0.8\n\
             TLAXIS/ 0.0, 0.0, 1.0\nGOTO/5,5,0\nEND\n\
             CUTTER/ 6.0, 0.5\nLOADTL/2\nSET/MODE,INCR\nGOTO/1,0,0\nGOTO/1,0,0\nSET/MODE,ABSOL\nFINI\n",
        );
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        assert_eq!(p.paths.len(), 2);
        let a = &p.paths[0];
        assert_eq!(
            (a.name.as_str(), a.tool_name.as_str()),
            ("BLADE", "T1 BALL D10")
        );
        let t = a.tool.as_ref().unwrap_or_else(|| panic!("tool"));
        assert_eq!(
            (t.diameter_mm, t.corner_radius_mm, t.length_mm),
            (10.0, 5.0, 50.0)
        );
        assert_eq!(t.apt, Some([10.0, 5.0, 0.0, 5.0, 0.0, 0.0, 50.0]));
        assert_eq!(a.prints.len(), 2);
        assert_eq!(a.stats.gotos, 3);
        assert_eq!(a.postures[0].spindle_rpm, Some(8000.0));
        assert_eq!(a.postures[1].feed_mm_min, Some(1000.0));
        assert_eq!(a.postures[1].axis, Vec3::new(0.6, 0.0, 0.8));
        assert_eq!(a.postures[2].axis, Vec3::z());
        let b = &p.paths[1];
        assert_eq!(b.tool_name, "T2");
        let tb = b.tool.as_ref().unwrap_or_else(|| panic!("tool"));
        assert_eq!(
            (tb.diameter_mm, tb.corner_radius_mm, tb.apt),
            (6.0, 0.5, None)
        );
        // Incremental GOTOs from the last position of the path before (5, 5, 0).
        assert_eq!(b.postures[1].position, Point3::new(2.0, 0.0, 0.0));
        assert_eq!(b.postures[1].motion, MotionKind::Cut);
    }

    #[test]
    fn feeds_and_spindle_value_first_and_per_rev() {
        let p = lower(
            "PARTNO P\nSPINDL/ 2000,RPM,CLW\nFEDRAT/ 0.1,MMPR\nGOTO/0,0,0\nFEDRAT/PERMIN,300\nGOTO/1,0,0\nFINI\n",
        );
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        let ps = &p.paths[0].postures;
        assert_relative_eq!(ps[0].feed_mm_min.unwrap_or(0.0), 200.0, epsilon = 1e-9);
        assert_eq!(ps[1].feed_mm_min, Some(300.0));
    }

    #[test]
    fn nx_paths_keep_their_tools_and_warn_on_unknown_records() {
        let p = lower(
            "TOOL PATH/OP,TOOL,T\nTLDATA/MILL,10,5,50,0,0\nLOAD/TOOL,1\nGOTO/0,0,0\nCUTTER/8,4\nGOTO/1,0,0\nCOOLNT/ON\nEND-OF-PATH\n",
        );
        assert_eq!(p.paths.len(), 1);
        assert_eq!(p.paths[0].tool_name, "T");
        assert_eq!(p.paths[0].tool.as_ref().map(|t| t.diameter_mm), Some(8.0));
        assert_eq!(p.warnings.len(), 1, "{:?}", p.warnings);
        assert!(p.warnings[0].message.contains("COOLNT"));
    }

    #[test]
    fn bad_cutters_and_axes_name_their_line() {
        for text in ["PARTNO P\nCUTTER/-1,0\n", "PARTNO P\nTLAXIS/0,0,0\n"] {
            let recs = parse_str(text).unwrap_or_else(|e| panic!("{e}"));
            let e = lower_records(&recs, LowerOptions::default())
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(e.starts_with("line 2, column 1: expected"), "{e}");
        }
    }
}
