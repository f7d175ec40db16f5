//! Opening and reading every input: each through a byte budget of its kind (`Read::take`
//! past which it is refused, naming the file and the budget, so that `/dev/zero` or a pipe
//! that never closes stops at once), `-` as standard input, and standard input, FIFOs and
//! devices read from their source only once (kept in a temporary file as they are read, so a
//! second reader, such as format detection then parsing, replays them instead of reopening).

use std::collections::HashMap;
use std::fs::File;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};

use crate::math::limits::MAX_NODES;

/// How much of an input crest reads before refusing it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// Most bytes of the whole input.
    pub bytes: u64,
    /// Most bytes of one line (formats read line by line; a line ends at `\n` or `\r`), if
    /// any.
    pub line: Option<u64>,
    /// Where the budget comes from, for the message.
    pub why: &'static str,
}

const MIB: u64 = 1 << 20;
const NODES: u64 = MAX_NODES as u64;

/// A tool path (CLSF, APT, contact12, G-code): read as a stream, so the bound is on time;
/// 8 GiB is about 150 million GOTO lines. A line (NX writes at most 80 characters) may have
/// 1 MiB.
pub const TOOLPATH: Budget = Budget {
    bytes: 8 << 30,
    line: Some(MIB),
    why: "a tool path of about 150 million moves; a line at most 1 MiB",
};
/// A TOML file (tool, process, machine, design, study).
pub const CONFIG: Budget = Budget {
    bytes: 8 * MIB,
    line: None,
    why: "a TOML configuration file",
};
/// A measured table, a series or a profile (CSV).
pub const TABLE: Budget = Budget {
    bytes: 256 * MIB,
    line: None,
    why: "a measured table or profile",
};
/// A shard file of task results (JSON lines).
pub const SHARD: Budget = Budget {
    bytes: 4 << 30,
    line: None,
    why: "a shard of task results",
};
/// A mesh (STL, OBJ, PLY) or a part map (PLY): 20 million triangles of ASCII STL.
pub const MESH: Budget = Budget {
    bytes: 20_000_000 * 256,
    line: None,
    why: "20 million triangles at 256 bytes",
};
/// A `.gsf` whose header is not in its first 64 KiB: the node limit in float32.
pub const GSF_MAX: Budget = Budget {
    bytes: NODES * 4 + MIB,
    line: None,
    why: "400 million nodes × 4 bytes + 1 MiB of header",
};
/// A binary `.sdf`: the node limit in float64.
pub const SDF_BINARY: Budget = Budget {
    bytes: NODES * 8 + MIB,
    line: None,
    why: "400 million nodes × 8 bytes + 1 MiB of header and trailer",
};
/// An `.x3p` (a zip archive): the node limit in float64, its validity bits and 16 MiB of
/// XML and zip structure (each entry is held to its own budget as it is decompressed).
pub const X3P: Budget = Budget {
    bytes: NODES * 8 + NODES / 8 + 16 * MIB,
    line: None,
    why: "400 million nodes × 8 bytes, their validity bits and 16 MiB of XML",
};
/// An instrument's binary height map (`.sur`, `.al3d`, `.gwy`, `.plu`, `.opd`, `.vk4`):
/// the node limit in float64 and 64 MiB of headers and other layers (each reader checks
/// its sizes against the bytes it has before it allocates).
pub const INSTRUMENT_MAP: Budget = Budget {
    bytes: NODES * 8 + 64 * MIB,
    line: None,
    why: "400 million nodes × 8 bytes + 64 MiB of headers and layers",
};
/// A text height map (grid CSV, text `.sdf`): the node limit at 26 bytes per height.
pub const MAP_TEXT: Budget = Budget {
    bytes: NODES * 26 + MIB,
    line: None,
    why: "400 million nodes × 26 bytes + 1 MiB of header",
};
/// An `x,y,z` point list: the node limit at 80 bytes per point.
pub const MAP_XYZ: Budget = Budget {
    bytes: NODES * 80 + MIB,
    line: None,
    why: "400 million points × 80 bytes + 1 MiB",
};

/// How many bytes [`read_staged`] reads before it sets the budget.
pub const HEAD: usize = 1 << 16;

/// Why an input could not be read.
#[derive(Debug, thiserror::Error, miette::Diagnostic)]
pub enum InputError {
    /// The file could not be opened or read.
    #[error("{file}: cannot {action} the {what}: {cause}")]
    Io {
        /// File name as given.
        file: String,
        /// `open` or `read`.
        action: &'static str,
        /// What the file is.
        what: String,
        /// The cause (in the message, not repeated as a cause).
        cause: std::io::Error,
    },
    /// The input goes on past its budget.
    #[error(
        "{file}: the {what} goes on past {}, the most crest reads of it ({why}): an endless input or not a {what}",
        show_bytes(*budget)
    )]
    TooLarge {
        /// File name as given.
        file: String,
        /// What the file is.
        what: String,
        /// The budget, bytes.
        budget: u64,
        /// Where the budget comes from.
        why: String,
    },
    /// One line goes on past the line budget.
    #[error(
        "{file}: a line of the {what} (at byte {at}) goes on past {}, the most crest reads of one line: not a {what}",
        show_bytes(*budget)
    )]
    LongLine {
        /// File name as given.
        file: String,
        /// What the file is.
        what: String,
        /// Byte offset where the line starts.
        at: u64,
        /// The budget of a line, bytes.
        budget: u64,
    },
    /// A text input holds a NUL byte in its first bytes.
    #[error("{file}: the {what} is not text (a NUL byte at byte {at})")]
    NotText {
        /// File name as given.
        file: String,
        /// What the file is.
        what: String,
        /// Byte offset of the NUL.
        at: u64,
    },
}

impl InputError {
    /// The file the error names.
    pub fn file(&self) -> &str {
        match self {
            InputError::Io { file, .. }
            | InputError::TooLarge { file, .. }
            | InputError::LongLine { file, .. }
            | InputError::NotText { file, .. } => file,
        }
    }

    /// The message without the leading `FILE: `, for errors that place it themselves.
    pub fn detail(&self) -> String {
        let m = self.to_string();
        m.strip_prefix(&format!("{}: ", self.file()))
            .map(str::to_string)
            .unwrap_or(m)
    }
}

/// `n` bytes as people read them: `8 MiB`, `1.6 GB`, `84 bytes`.
pub fn show_bytes(n: u64) -> String {
    if n < 10_000 {
        format!("{n} bytes")
    } else if n.is_power_of_two() && n >= MIB {
        if n >= 1 << 30 {
            format!("{} GiB", n >> 30)
        } else {
            format!("{} MiB", n >> 20)
        }
    } else if n < 10_000_000 {
        format!("{n} bytes ({:.1} kB)", n as f64 / 1e3)
    } else {
        format!("{n} bytes ({:.1} GB)", n as f64 / 1e9)
    }
}

/// Whether `path` names standard input (`-`).
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// Whether `path` is a regular file (which may be opened again and read at offsets); not
/// standard input, a FIFO or a device.
pub fn is_regular(path: &Path) -> bool {
    !is_stdin(path) && std::fs::metadata(path).is_ok_and(|m| m.is_file())
}

/// An input opened for reading within its budget ([`open`]); its errors are
/// [`InputError`]s inside `std::io::Error` (see [`take_error`]).
pub struct Bounded {
    inner: std::io::Take<Source>,
    file: String,
    what: String,
    budget: Budget,
    read: u64,
    /// Bytes of the current line so far, and where it started.
    line: u64,
    line_at: u64,
}

enum Source {
    File(File),
    Replay(Replay),
}

impl Read for Source {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self {
            Source::File(f) => f.read(buf),
            Source::Replay(r) => r.read(buf),
        }
    }
}

impl Bounded {
    fn new(source: Source, path: &Path, what: &str, budget: Budget) -> Bounded {
        Bounded {
            inner: source.take(budget.bytes.saturating_add(1)),
            file: path.display().to_string(),
            what: what.to_string(),
            budget,
            read: 0,
            line: 0,
            line_at: 0,
        }
    }

    /// Change the budget (from what the first bytes say); counts from the start.
    fn set_budget(&mut self, budget: Budget) {
        self.budget = budget;
        self.inner
            .set_limit(budget.bytes.saturating_add(1).saturating_sub(self.read));
    }

    fn too_large(&self) -> InputError {
        InputError::TooLarge {
            file: self.file.clone(),
            what: self.what.clone(),
            budget: self.budget.bytes,
            why: self.budget.why.to_string(),
        }
    }

    /// The error of a failed read: the budget's own, or the I/O cause with the file named.
    pub fn error(&self, e: std::io::Error) -> InputError {
        take_error(e).unwrap_or_else(|cause| InputError::Io {
            file: self.file.clone(),
            action: "read",
            what: self.what.clone(),
            cause,
        })
    }

    /// Read the rest into `out` (an [`InputError`] past the budget).
    fn read_rest(&mut self, out: &mut Vec<u8>) -> Result<(), InputError> {
        self.read_to_end(out).map(|_| ()).map_err(|e| self.error(e))
    }
}

impl Read for Bounded {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let start = self.read;
        self.read += n as u64;
        if self.read > self.budget.bytes {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                self.too_large(),
            ));
        }
        if let Some(max) = self.budget.line {
            let mut at = 0;
            // `\r` ends a line too: CR-only files (`io::toolpath::LoneCr`) have no `\n`.
            for nl in memchr::memchr2_iter(b'\n', b'\r', &buf[..n]) {
                self.line += (nl - at) as u64;
                if self.line > max {
                    break;
                }
                self.line = 0;
                at = nl + 1;
                self.line_at = start + at as u64;
            }
            if self.line <= max {
                self.line += (n - at) as u64;
            }
            if self.line > max {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    InputError::LongLine {
                        file: self.file.clone(),
                        what: self.what.clone(),
                        at: self.line_at,
                        budget: max,
                    },
                ));
            }
        }
        Ok(n)
    }
}

/// The [`InputError`] a [`Bounded`] read raised, or the I/O error as it was.
pub fn take_error(e: std::io::Error) -> Result<InputError, std::io::Error> {
    if e.get_ref().is_some_and(|i| i.is::<InputError>()) {
        match e.into_inner().map(|i| i.downcast::<InputError>()) {
            Some(Ok(i)) => Ok(*i),
            _ => Err(std::io::Error::other("internal: lost input error")),
        }
    } else {
        Err(e)
    }
}

/// Open `path` (`-`: standard input) for reading within `budget`; `what` names the kind of
/// file in errors. A regular file is opened as it is; standard input, a FIFO or a device is
/// read from its source once, whatever the number of [`open`]s (see the module).
pub fn open(path: &Path, what: &str, budget: Budget) -> Result<Bounded, InputError> {
    let io = |cause| InputError::Io {
        file: path.display().to_string(),
        action: "open",
        what: what.to_string(),
        cause,
    };
    let source = if is_stdin(path) {
        Source::Replay(Replay::of(path, || Ok(Box::new(std::io::stdin()))).map_err(io)?)
    } else {
        super::output::register_input(path);
        // A FIFO is opened (which waits for a writer) only for its first reader.
        if std::fs::metadata(path).map_err(io)?.is_file() {
            Source::File(File::open(path).map_err(io)?)
        } else {
            Source::Replay(Replay::of(path, || Ok(Box::new(File::open(path)?))).map_err(io)?)
        }
    };
    Ok(Bounded::new(source, path, what, budget))
}

/// Read the whole of `path` within `budget` (see [`open`]).
pub fn read_bounded(path: &Path, what: &str, budget: Budget) -> Result<Vec<u8>, InputError> {
    let mut r = open(path, what, budget)?;
    let mut out = Vec::new();
    r.read_rest(&mut out)?;
    Ok(out)
}

/// What the first bytes of an input say about the rest ([`read_staged`]).
pub enum Stage {
    /// Read the rest within this budget.
    Budget(Budget),
    /// Read no further: the first bytes already show what the file is not (the parser
    /// gives the error on them).
    Stop,
    /// Refuse: a text input with a NUL byte at this offset.
    NotText(u64),
}

/// Read `path` whole: its first [`HEAD`] bytes, then the rest within the budget that
/// `stage` sets from them (the budget of a binary map from its header; none past a
/// header that is not the format's).
pub fn read_staged(
    path: &Path,
    what: &str,
    stage: impl FnOnce(&[u8]) -> Stage,
) -> Result<Vec<u8>, InputError> {
    let first = Budget {
        bytes: HEAD as u64,
        line: None,
        why: "",
    };
    let mut r = open(path, what, first)?;
    let mut out = Vec::new();
    (&mut r)
        .take(HEAD as u64)
        .read_to_end(&mut out)
        .map_err(|e| r.error(e))?;
    if out.len() < HEAD {
        return Ok(out);
    }
    match stage(&out) {
        Stage::Budget(b) => {
            r.set_budget(b);
            r.read_rest(&mut out)?;
            Ok(out)
        }
        Stage::Stop => Ok(out),
        Stage::NotText(at) => Err(InputError::NotText {
            file: path.display().to_string(),
            what: what.to_string(),
            at,
        }),
    }
}

/// [`Stage`] of a text input: refused for a NUL byte in its first bytes, else `budget`.
pub fn text_stage(head: &[u8], budget: Budget) -> Stage {
    match memchr::memchr(0, head) {
        Some(at) => Stage::NotText(at as u64),
        None => Stage::Budget(budget),
    }
}

/// A standard input, FIFO or device read once: the bytes read so far, kept in an
/// anonymous temporary file, and the source for the rest.
struct Spool {
    file: File,
    len: u64,
    source: Option<Box<dyn Read + Send>>,
}

/// The spools of this process, by the path as given.
fn spools() -> &'static Mutex<HashMap<PathBuf, Arc<Mutex<Spool>>>> {
    static SPOOLS: OnceLock<Mutex<HashMap<PathBuf, Arc<Mutex<Spool>>>>> = OnceLock::new();
    SPOOLS.get_or_init(Default::default)
}

/// One reader of a [`Spool`], from its start: what is kept is read back, the rest is read
/// from the source and kept.
struct Replay {
    spool: Arc<Mutex<Spool>>,
    pos: u64,
}

impl Replay {
    fn of(
        path: &Path,
        source: impl FnOnce() -> std::io::Result<Box<dyn Read + Send>>,
    ) -> std::io::Result<Replay> {
        let mut all = spools().lock().unwrap_or_else(|e| e.into_inner());
        let spool = match all.get(path) {
            Some(s) => s.clone(),
            None => {
                let s = Arc::new(Mutex::new(Spool {
                    file: tempfile::tempfile()?,
                    len: 0,
                    source: Some(source()?),
                }));
                all.insert(path.to_path_buf(), s.clone());
                s
            }
        };
        Ok(Replay { spool, pos: 0 })
    }
}

impl Read for Replay {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        use std::io::{Seek, SeekFrom};
        let mut s = self.spool.lock().unwrap_or_else(|e| e.into_inner());
        let n = if self.pos < s.len {
            let want = buf.len().min((s.len - self.pos) as usize);
            s.file.seek(SeekFrom::Start(self.pos))?;
            s.file.read(&mut buf[..want])?
        } else {
            let n = match s.source.as_mut() {
                Some(src) => src.read(buf)?,
                None => 0,
            };
            if n == 0 {
                s.source = None;
            } else {
                let end = s.len;
                s.file.seek(SeekFrom::Start(end))?;
                s.file.write_all(&buf[..n])?;
                s.len += n as u64;
            }
            n
        };
        self.pos += n as u64;
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn budget(bytes: u64, line: Option<u64>) -> Budget {
        Budget {
            bytes,
            line,
            why: "test",
        }
    }

    #[test]
    fn the_budget_is_exact_and_named() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        std::fs::write(&p, b"0123456789").unwrap();
        assert_eq!(
            read_bounded(&p, "table", budget(10, None)).unwrap().len(),
            10
        );
        let e = read_bounded(&p, "table", budget(9, None)).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("a.txt") && m.contains("9 bytes") && m.contains("(test)"),
            "{m}"
        );
    }

    #[test]
    fn a_long_line_is_refused_wherever_the_reads_cut_it() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.cls");
        std::fs::write(&p, b"abc\nabcdef\nab\n").unwrap();
        for max in [6, 7] {
            let mut r = open(&p, "tool path", budget(100, Some(max))).unwrap();
            let mut out = Vec::new();
            let mut byte = [0u8; 1];
            // One byte at a time and all at once.
            while r.read(&mut byte).unwrap() == 1 {
                out.push(byte[0]);
            }
            assert_eq!(out.len(), 14);
            assert!(read_bounded(&p, "tool path", budget(100, Some(max))).is_ok());
        }
        let e = read_bounded(&p, "tool path", budget(100, Some(5))).unwrap_err();
        assert!(e.to_string().contains("at byte 4"), "{e}");
        // CR-only line ends count as line ends.
        std::fs::write(&p, b"abc\rabcdef\rab\r").unwrap();
        assert!(read_bounded(&p, "tool path", budget(100, Some(6))).is_ok());
        assert!(read_bounded(&p, "tool path", budget(100, Some(5))).is_err());
    }

    #[test]
    fn a_fifo_is_read_once_by_any_number_of_readers() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("pipe");
        #[cfg(unix)]
        {
            let st = std::process::Command::new("mkfifo").arg(&p).status();
            if !st.is_ok_and(|s| s.success()) {
                return;
            }
            let q = p.clone();
            let writer = std::thread::spawn(move || std::fs::write(q, b"hello fifo\n").unwrap());
            let mut first = open(&p, "table", budget(100, None)).unwrap();
            let mut head = [0u8; 5];
            first.read_exact(&mut head).unwrap();
            assert_eq!(&head, b"hello");
            // A second open does not wait for a writer: it replays.
            let whole = read_bounded(&p, "table", budget(100, None)).unwrap();
            assert_eq!(whole, b"hello fifo\n");
            let mut rest = Vec::new();
            first.read_to_end(&mut rest).unwrap();
            assert_eq!(rest, b" fifo\n");
            writer.join().unwrap();
        }
    }

    #[test]
    fn staged_reads_stop_or_set_the_budget_from_the_head() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("big");
        std::fs::write(&p, vec![b'x'; HEAD + 10]).unwrap();
        let all = read_staged(&p, "map", |_| Stage::Budget(budget(HEAD as u64 + 10, None)));
        assert_eq!(all.unwrap().len(), HEAD + 10);
        let e = read_staged(&p, "map", |_| Stage::Budget(budget(HEAD as u64 + 9, None)));
        assert!(matches!(e, Err(InputError::TooLarge { .. })));
        assert_eq!(read_staged(&p, "map", |_| Stage::Stop).unwrap().len(), HEAD);
        let e = read_staged(&p, "map", |h| text_stage(h, budget(1, None)));
        assert!(matches!(e, Err(InputError::TooLarge { .. })));
        let mut bytes = vec![b'x'; HEAD + 10];
        bytes[7] = 0;
        std::fs::write(&p, bytes).unwrap();
        let e = read_staged(&p, "map", |h| text_stage(h, budget(u64::MAX, None)));
        assert!(matches!(e, Err(InputError::NotText { at: 7, .. })));
    }

    #[test]
    fn sizes_read_well() {
        assert_eq!(show_bytes(84), "84 bytes");
        assert_eq!(show_bytes(8 << 20), "8 MiB");
        assert_eq!(show_bytes(8 << 30), "8 GiB");
        assert!(show_bytes(1_600_000_084).contains("1.6 GB"));
    }
}
