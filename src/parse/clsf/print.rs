//! Printing CLSF records: the canonical text, which parses back to the same record.

use super::record::{Arg, LengthUnit, RecordKind};
use std::fmt;

fn write_nums(f: &mut fmt::Formatter<'_>, v: &[f64]) -> fmt::Result {
    for (k, x) in v.iter().enumerate() {
        if k > 0 {
            f.write_str(",")?;
        }
        write!(f, "{x}")?;
    }
    Ok(())
}

fn write_args(f: &mut fmt::Formatter<'_>, a: &[Arg]) -> fmt::Result {
    for (k, x) in a.iter().enumerate() {
        if k > 0 {
            f.write_str(",")?;
        }
        match x {
            Arg::Num(v) => write!(f, "{v}")?,
            Arg::Word(w) => f.write_str(w)?,
        }
    }
    Ok(())
}

impl fmt::Display for RecordKind {
    /// The record as CLSF text (numbers in the shortest form that reads back exactly).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RecordKind::ToolPath { name, tool } => {
                write!(f, "TOOL PATH/{name}")?;
                if !tool.is_empty() {
                    write!(f, ",TOOL,{tool}")?;
                }
                Ok(())
            }
            RecordKind::Tldata {
                kind,
                subtype,
                args,
            } => {
                write!(f, "TLDATA/{kind}")?;
                if let Some(s) = subtype {
                    write!(f, ",{s}")?;
                }
                if !args.is_empty() {
                    f.write_str(",")?;
                    write_args(f, args)?;
                }
                Ok(())
            }
            RecordKind::Msys(m) => {
                f.write_str("MSYS/")?;
                write_nums(f, m)
            }
            RecordKind::Comment(t) => write!(f, "$$ {t}"),
            RecordKind::Contact(n) => {
                f.write_str("CONTACT/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::Paint(a) => {
                f.write_str("PAINT/")?;
                write_args(f, a)
            }
            RecordKind::Fedrat { unit, value } => match unit {
                Some(u) => write!(f, "FEDRAT/{},{value}", u.word()),
                None => write!(f, "FEDRAT/{value}"),
            },
            RecordKind::Rapid => f.write_str("RAPID"),
            RecordKind::Goto(n) => {
                f.write_str("GOTO/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::From(n) => {
                f.write_str("FROM/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::GoHome(n) => {
                f.write_str("GOHOME/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::Circle { numbers, times } => {
                f.write_str("CIRCLE/")?;
                write_nums(f, numbers.as_slice())?;
                if let Some(t) = times {
                    write!(f, ",TIMES,{t}")?;
                }
                Ok(())
            }
            RecordKind::Nurbs => f.write_str("NURBS/"),
            RecordKind::Knot(v) => {
                f.write_str("KNOT/")?;
                write_nums(f, v)
            }
            RecordKind::Cntrl(p) => {
                f.write_str("CNTRL/")?;
                write_nums(f, p)
            }
            RecordKind::LoadTool { number, args } => {
                write!(f, "LOAD/TOOL,{number}")?;
                if !args.is_empty() {
                    f.write_str(",")?;
                    write_args(f, args)?;
                }
                Ok(())
            }
            RecordKind::SelectTool { number } => write!(f, "SELECT/TOOL,{number}"),
            RecordKind::Spindl(a) => {
                f.write_str("SPINDL/")?;
                write_args(f, a)
            }
            RecordKind::Cutcom(a) => {
                f.write_str("CUTCOM/")?;
                write_args(f, a)
            }
            RecordKind::Cycle(a) => {
                f.write_str("CYCLE/")?;
                write_args(f, a)
            }
            RecordKind::Units(u) => f.write_str(match u {
                LengthUnit::Mm => "UNITS/MM",
                LengthUnit::Inch => "UNITS/INCH",
            }),
            RecordKind::EndOfPath => f.write_str("END-OF-PATH"),
            RecordKind::Print { word, text } => write!(f, "{word}/{text}"),
            RecordKind::Partno(t) => write!(f, "PARTNO {t}"),
            RecordKind::Multax(on) => f.write_str(if *on { "MULTAX/ON" } else { "MULTAX/OFF" }),
            RecordKind::Cutter(n) => {
                f.write_str("CUTTER/")?;
                write_nums(f, n.as_slice())
            }
            RecordKind::Tlaxis(v) => {
                f.write_str("TLAXIS/")?;
                write_nums(f, v)
            }
            RecordKind::Indirv(v) => {
                f.write_str("INDIRV/")?;
                write_nums(f, v)
            }
            RecordKind::SetMode { absolute } => f.write_str(if *absolute {
                "SET/MODE,ABSOL"
            } else {
                "SET/MODE,INCR"
            }),
            RecordKind::Fini => f.write_str("FINI"),
            RecordKind::End => f.write_str("END"),
            RecordKind::Unknown { text, .. } => f.write_str(text),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::one;

    #[test]
    fn printed_records_parse_back() {
        for s in [
            "GOTO/1.5,2,-3",
            "CIRCLE/1,2,3,0,0,1,5,0.06,0.5,10,1,TIMES,2",
            "FEDRAT/MMPM,250",
            "SPINDL/RPM,1000,CLW",
            "KNOT/0.1,0.5,1",
            "TOOL PATH/A-1,TOOL,B_2",
            "PPRINT/OPERATION 1, ROUGH",
            "TPRINT/T1 BALL D10",
            "PARTNO BLADE-7",
            "MULTAX/ON",
            "MULTAX/OFF",
            "CUTTER/10,5,0,5,0,0,50",
            "TLAXIS/0,0,1",
            "INDIRV/1,0,0",
            "SET/MODE,ABSOL",
            "SET/MODE,INCR",
            "FINI",
            "END",
        ] {
            let r = one(s);
            assert_eq!(r.to_string(), s);
        }
    }
}
