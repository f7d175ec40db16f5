//! Gwyddion native files (`.gwy`, the `GWYP` serialised object format): one channel's
//! heights.
//!
//! After the magic `GWYP` comes one serialised object, the top `GwyContainer`: its name
//! (NUL-terminated), the byte size of its components (uint32 LE), then the components,
//! each a name, a type character and the value: `b` bool and `c` char (1 byte), `i`
//! int32, `q` int64, `d` float64, `s` a NUL-terminated string, `o` an object; the upper
//! case letter is an array (a uint32 count, then the items). A channel `N` is the
//! `GwyDataField` at `/N/data` (`xres`, `yres`, `xreal`, `yreal`, `xoff`, `yoff`,
//! `si_unit_xy` and `si_unit_z` as `GwySIUnit` objects with a `unitstr`, and `data`, a
//! float64 array, x fastest, row 0 first), its title the string `/N/data/title`, its mask
//! the data field `/N/mask` (a non-zero mask node is taken as not measured: NaN).
//!
//! Read: the channel named by `--channel` (its title), else the lowest-numbered channel
//! whose z unit is a length (in a file of one height channel, `/0/data`). Heights and
//! spacing (`xreal / xres`) to µm from the units; the origin from `xoff`/`yoff`.

use super::FormatError;
use super::binary::{self, Le};
use crate::surface::HeightMap;

/// The first bytes of a `.gwy`.
pub(crate) const MAGIC: &[u8] = b"GWYP";
/// Objects nest no deeper than this (a data field in a container is 3).
const MAX_DEPTH: usize = 32;

/// A value of a component.
enum Value<'a> {
    Int(i64),
    Double(f64),
    Str(String),
    Object(Object<'a>),
    /// A float64 array: its bytes.
    Doubles(&'a [u8], usize),
    Other,
}

struct Object<'a> {
    name: String,
    components: Vec<(String, Value<'a>, usize)>,
}

impl<'a> Object<'a> {
    fn get(&self, name: &str) -> Option<(&Value<'a>, usize)> {
        self.components
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|(_, v, at)| (v, *at))
    }
}

struct Parser<'a> {
    le: Le<'a>,
}

impl<'a> Parser<'a> {
    /// A NUL-terminated string at `at` ending before `end`; returns it and the offset after.
    fn cstr(&self, at: usize, end: usize, what: &str) -> Result<(String, usize), FormatError> {
        let s = self.le.bytes.get(at..end).unwrap_or(&[]);
        let n = s.iter().position(|&b| b == 0).ok_or_else(|| {
            FormatError::byte(
                at as u64,
                format!("{what}: the string runs past its object's end"),
            )
        })?;
        Ok((binary::latin1(&s[..n]), at + n + 1))
    }

    /// The object at `at` (name, size, components), ending before `end`.
    fn object(
        &self,
        at: usize,
        end: usize,
        depth: usize,
    ) -> Result<(Object<'a>, usize), FormatError> {
        if depth > MAX_DEPTH {
            return Err(FormatError::byte(at as u64, "objects nest too deep"));
        }
        let (name, p) = self.cstr(at, end, "an object name")?;
        let size = self.le.u32(p, "an object size")? as usize;
        let start = p + 4;
        let stop = start
            .checked_add(size)
            .filter(|&s| s <= end)
            .ok_or_else(|| {
                FormatError::byte(
                    p as u64,
                    format!("the size of object {name} ({size} bytes) goes past its container"),
                )
            })?;
        let mut components = Vec::new();
        let mut q = start;
        while q < stop {
            let (cname, r) = self.cstr(q, stop, "a component name")?;
            let ty = *self.le.bytes.get(r).filter(|_| r < stop).ok_or_else(|| {
                FormatError::byte(r as u64, format!("component {cname}: no type"))
            })?;
            let (value, next) = self.value(r + 1, stop, ty, &cname, depth)?;
            components.push((cname, value, r + 1));
            q = next;
        }
        Ok((Object { name, components }, stop))
    }

    fn value(
        &self,
        at: usize,
        end: usize,
        ty: u8,
        name: &str,
        depth: usize,
    ) -> Result<(Value<'a>, usize), FormatError> {
        let fixed = |n: usize| -> Result<&'a [u8], FormatError> {
            if at + n > end {
                return Err(FormatError::byte(
                    at as u64,
                    format!("component {name}: its value runs past its object's end"),
                ));
            }
            self.le.slice(at, n, name)
        };
        Ok(match ty {
            b'b' | b'c' => (Value::Int(i64::from(fixed(1)?[0])), at + 1),
            b'i' => {
                fixed(4)?;
                (Value::Int(i64::from(self.le.i32(at, name)?)), at + 4)
            }
            b'q' => {
                fixed(8)?;
                (Value::Int(self.le.i64(at, name)?), at + 8)
            }
            b'd' => {
                fixed(8)?;
                (Value::Double(self.le.f64(at, name)?), at + 8)
            }
            b's' => {
                let (s, next) = self.cstr(at, end, name)?;
                (Value::Str(s), next)
            }
            b'o' => {
                let (o, next) = self.object(at, end, depth + 1)?;
                (Value::Object(o), next)
            }
            b'B' | b'C' | b'I' | b'Q' | b'D' | b'S' | b'O' => {
                fixed(4)?;
                let count = self.le.u32(at, name)? as usize;
                let p = at + 4;
                let item = match ty {
                    b'B' | b'C' => 1,
                    b'I' => 4,
                    b'Q' | b'D' => 8,
                    _ => 0,
                };
                if item > 0 {
                    let len = count.checked_mul(item).filter(|&l| p + l <= end).ok_or_else(|| {
                        FormatError::byte(
                            at as u64,
                            format!("component {name}: an array of {count} items runs past its object's end"),
                        )
                    })?;
                    let bytes = self.le.slice(p, len, name)?;
                    let v = if ty == b'D' {
                        Value::Doubles(bytes, count)
                    } else {
                        Value::Other
                    };
                    (v, p + len)
                } else {
                    // Strings or objects: each at least one byte.
                    if count > end.saturating_sub(p) {
                        return Err(FormatError::byte(
                            at as u64,
                            format!("component {name}: {count} items cannot fit in its object"),
                        ));
                    }
                    let mut q = p;
                    for _ in 0..count {
                        q = if ty == b'S' {
                            self.cstr(q, end, name)?.1
                        } else {
                            self.object(q, end, depth + 1)?.1
                        };
                    }
                    (Value::Other, q)
                }
            }
            t => {
                return Err(FormatError::byte(
                    (at - 1) as u64,
                    format!("component {name}: unknown type {:?}", char::from(t)),
                ));
            }
        })
    }
}

/// The channel numbers of the container (`/N/data` data fields), ascending.
fn channels(top: &Object) -> Vec<u64> {
    let mut ids: Vec<u64> = top
        .components
        .iter()
        .filter_map(|(n, v, _)| {
            let id = n.strip_prefix('/')?.strip_suffix("/data")?.parse().ok()?;
            matches!(v, Value::Object(o) if o.name == "GwyDataField").then_some(id)
        })
        .collect();
    ids.sort_unstable();
    ids
}

fn field<'o, 'a>(top: &'o Object<'a>, key: &str) -> Option<&'o Object<'a>> {
    match top.get(key) {
        Some((Value::Object(o), _)) if o.name == "GwyDataField" => Some(o),
        _ => None,
    }
}

fn title(top: &Object, id: u64) -> String {
    match top.get(&format!("/{id}/data/title")) {
        Some((Value::Str(s), _)) => s.clone(),
        _ => String::new(),
    }
}

fn unit(f: &Object, key: &str) -> Option<String> {
    match f.get(key) {
        Some((Value::Object(u), _)) => match u.get("unitstr") {
            Some((Value::Str(s), _)) => Some(s.clone()),
            _ => Some(String::new()),
        },
        _ => None,
    }
}

pub(crate) fn parse(bytes: &[u8], channel: Option<&str>) -> Result<HeightMap, FormatError> {
    if !bytes.starts_with(MAGIC) {
        return Err(FormatError::byte(0, "not a .gwy (no GWYP magic)"));
    }
    let p = Parser { le: Le::new(bytes) };
    let (top, _) = p.object(MAGIC.len(), bytes.len(), 0)?;
    if top.name != "GwyContainer" {
        return Err(FormatError::byte(
            4,
            format!("the top object is {:?}, not a GwyContainer", top.name),
        ));
    }
    let ids = channels(&top);
    let list = || {
        ids.iter()
            .map(|&i| format!("{i}: {:?}", title(&top, i)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let id = match channel {
        Some(name) => ids
            .iter()
            .copied()
            .find(|&i| title(&top, i) == name)
            .or_else(|| {
                ids.iter()
                    .copied()
                    .find(|&i| title(&top, i).eq_ignore_ascii_case(name))
            })
            .ok_or_else(|| {
                FormatError::file(format!(
                    "no channel is titled {name:?} (the channels: {})",
                    list()
                ))
            })?,
        None => ids
            .iter()
            .copied()
            .find(|&i| {
                field(&top, &format!("/{i}/data"))
                    .and_then(|f| unit(f, "si_unit_z"))
                    .is_some_and(|u| binary::um_per(&u).is_some())
            })
            .ok_or_else(|| {
                FormatError::file(if ids.is_empty() {
                    "the file holds no channel (/N/data data field)".to_string()
                } else {
                    format!(
                        "no channel has heights in a length unit (the channels: {}): name one with ‹channel›",
                        list()
                    )
                })
            })?,
    };
    let key = format!("/{id}/data");
    let f = field(&top, &key).ok_or_else(|| FormatError::file(format!("{key} is missing")))?;
    let int = |name: &str| -> Result<i64, FormatError> {
        match f.get(name) {
            Some((Value::Int(v), _)) => Ok(*v),
            _ => Err(FormatError::file(format!("{key} has no integer {name}"))),
        }
    };
    let double = |name: &str, default: Option<f64>| -> Result<f64, FormatError> {
        match (f.get(name), default) {
            (Some((Value::Double(v), _)), _) if v.is_finite() => Ok(*v),
            (Some((_, at)), _) => Err(FormatError::byte(
                at as u64,
                format!("{key}/{name} is not a finite number"),
            )),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(FormatError::file(format!("{key} has no {name}"))),
        }
    };
    let (nx, ny) = (int("xres")?, int("yres")?);
    let (data, count, at) = match f.get("data") {
        Some((Value::Doubles(b, n), at)) => (*b, *n, at),
        _ => {
            return Err(FormatError::file(format!(
                "{key} has no float64 data array"
            )));
        }
    };
    let n = binary::nodes(nx, ny, 8, data.len(), &format!("{key} xres × yres"))?;
    if count != n {
        return Err(FormatError::byte(
            at as u64,
            format!("{key}/data holds {count} values but xres × yres is {n}"),
        ));
    }
    let units = |name: &str| -> Result<f64, FormatError> {
        let u = unit(f, name).ok_or_else(|| FormatError::file(format!("{key} has no {name}")))?;
        binary::um_per(&u)
            .ok_or_else(|| FormatError::file(format!("{key}/{name} is {u:?}, not a length unit")))
    };
    let (uxy, uz) = (units("si_unit_xy")?, units("si_unit_z")?);
    let mask = match field(&top, &format!("/{id}/mask")) {
        Some(m) => match m.get("data") {
            Some((Value::Doubles(b, c), _)) if *c == n => Some(*b),
            _ => {
                return Err(FormatError::file(format!(
                    "/{id}/mask has no float64 data of the channel's {n} nodes"
                )));
            }
        },
        None => None,
    };
    let z: Vec<f64> = data
        .chunks_exact(8)
        .enumerate()
        .map(|(k, b)| {
            let masked = mask.is_some_and(|m| {
                f64::from_le_bytes(m[8 * k..8 * k + 8].try_into().unwrap_or([0; 8])) != 0.0
            });
            let v = f64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
            if masked { f64::NAN } else { v * uz }
        })
        .collect();
    let dx = binary::spacing(double("xreal", None)? / nx as f64 * uxy, "xreal / xres")?;
    let dy = binary::spacing(double("yreal", None)? / ny as f64 * uxy, "yreal / yres")?;
    let x0 = double("xoff", Some(0.0))? * uxy * 1e-3;
    let y0 = double("yoff", Some(0.0))? * uxy * 1e-3;
    binary::finish(nx as usize, ny as usize, (dx, dy), (x0, y0), z)
}
