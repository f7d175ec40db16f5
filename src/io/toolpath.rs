//! Reading tool-path files (CLSF and the APT family, contact12, or G-code through a
//! machine) into a [`Program`], with errors that name the file, line and column.
//!
//! The kind of file is decided by content on the first 64 KiB
//! ([`crate::parse::looks_like_contact12`], then [`crate::parse::looks_like_gcode`], else
//! CLSF), not by extension. Reading streams: [`stream_program`] hands each posture to a
//! callback and keeps none unless asked, so any file size reads in constant memory.
//! G-code is read through the forward kinematics of the machine in [`ReadOptions`]
//! (`crate::nc`).

use super::input::Bounded;
use crate::kinematics::Machine;
use crate::nc::{NcReader, Rtcp};
use crate::parse::Written;
use crate::parse::position::Frame;
use crate::parse::{
    ClsfReader, Contact12Reader, GcodeReader, Located, ParseError, Problem, Span,
    looks_like_contact12, looks_like_gcode,
};
use crate::toolpath::{LowerError, LowerOptions, Lowerer, Posture, PostureSink, Program, Toolpath};
use miette::Diagnostic;
use std::io::{BufRead, BufReader, Read};
use std::path::Path;

/// Input file kinds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// NX CLSF (APT-style records).
    Clsf,
    /// The 12-column contact file.
    Contact12,
    /// ISO G-code (read through a machine).
    Gcode,
}

impl InputKind {
    /// The name of the kind: `clsf`, `contact12` or `gcode`.
    pub fn name(self) -> &'static str {
        match self {
            InputKind::Clsf => "clsf",
            InputKind::Contact12 => "contact12",
            InputKind::Gcode => "gcode",
        }
    }
}

/// How to read a tool-path file: the lowering, and for G-code the machine and its
/// tool-centre-point control. A [`LowerOptions`] converts into one without a machine.
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Lowering options (MSYS, keeping postures, NURBS tolerance).
    pub lower: LowerOptions,
    /// The machine G-code is read through (`--machine`); CLSF and contact12 ignore it.
    pub machine: Option<Machine>,
    /// Tool-centre-point control of G-code (`--rtcp`).
    pub rtcp: Rtcp,
}

impl From<LowerOptions> for ReadOptions {
    fn from(lower: LowerOptions) -> ReadOptions {
        ReadOptions {
            lower,
            ..Default::default()
        }
    }
}

/// A bad-input error: file, line, column, what was expected and what was found, with a
/// code frame of the offending line (a [`Located`] in the file).
#[derive(Debug, thiserror::Error)]
#[error("{}:{}:{}: {}", .0.file.as_deref().unwrap_or_default(), .0.span.line, .0.span.column, .0.problem)]
pub struct InputError(pub Located);

impl Diagnostic for InputError {
    fn code<'a>(&'a self) -> Option<Box<dyn std::fmt::Display + 'a>> {
        Some(Box::new("crate::input"))
    }

    fn source_code(&self) -> Option<&dyn miette::SourceCode> {
        self.0.source_code()
    }

    fn labels(&self) -> Option<Box<dyn Iterator<Item = miette::LabeledSpan> + '_>> {
        self.0.labels()
    }
}

/// At most this many characters of an offending line (or token) are shown in a message,
/// around the error's column.
const SHOW_CHARS: usize = 120;

/// `text` cut to [`SHOW_CHARS`] characters around character `col` (0-based), with `…`
/// where it was cut; returns the cut text and the new position of `col`.
fn window(text: &str, col: usize) -> (String, usize) {
    let n = text.chars().count();
    if n <= SHOW_CHARS {
        return (text.to_string(), col);
    }
    let start = col.saturating_sub(SHOW_CHARS / 2).min(n - SHOW_CHARS);
    let mut out: String = text.chars().skip(start).take(SHOW_CHARS).collect();
    let mut at = col - start;
    if start > 0 {
        out.insert(0, '…');
        at += 1;
    }
    if start + SHOW_CHARS < n {
        out.push('…');
    }
    (out, at)
}

impl InputError {
    /// The syntax error `s` in `file`, its line and found token cut to [`SHOW_CHARS`]
    /// characters around the column, the frame pointing at the token.
    fn new(file: &Path, s: &Located) -> InputError {
        let name = file.display().to_string();
        let column = s.span.column;
        let (line_text, col) = window(s.line_text(), column.saturating_sub(1) as usize);
        let (frame, offset, len) = if line_text.is_empty() {
            (None, 0, 0)
        } else {
            let byte = line_text
                .char_indices()
                .nth(col)
                .map(|(b, _)| b)
                .unwrap_or(line_text.len());
            let mut text = line_text;
            if byte >= text.len() {
                // At the end of the line: point at a blank after the last character.
                text.push(' ');
            }
            let len = text[byte..]
                .find([',', ' ', '\t', '/', ';'])
                .unwrap_or(text.len() - byte)
                .max(1);
            let frame = Frame {
                name: name.clone(),
                text,
                first_line: s.span.line.saturating_sub(1) as usize,
            };
            (Some(frame), byte, len)
        };
        let problem = match &s.problem {
            Problem::Expected { expected, found } => Problem::Expected {
                expected: expected.clone(),
                found: window(found, 0).0,
            },
            Problem::Message(m) => Problem::Message(m.clone()),
        };
        InputError(Located {
            file: Some(name),
            span: Span {
                offset,
                len,
                line: s.span.line,
                column,
            },
            problem,
            frame,
        })
    }
}

/// An I/O failure with context; the `io::Error` stays in the cause chain (so a broken
/// pipe can be recognised).
#[derive(Debug, thiserror::Error, Diagnostic)]
#[error("{context}")]
pub struct IoFailure {
    /// What was being done.
    pub context: String,
    /// The cause.
    #[source]
    pub source: std::io::Error,
}

/// Why a tool-path file could not be read (or the output its postures streamed into not
/// written): each message names the file.
#[derive(Debug, thiserror::Error, Diagnostic)]
pub enum ReadError {
    /// A syntax or lowering error at a place in the file, with its code frame.
    #[error(transparent)]
    #[diagnostic(transparent)]
    Located(Box<InputError>),
    /// The file could not be opened, or goes on past its budget.
    #[error(transparent)]
    #[diagnostic(transparent)]
    Budget(#[from] super::input::InputError),
    /// A read, or a write of the output the postures stream into, failed.
    #[error(transparent)]
    #[diagnostic(transparent)]
    Io(#[from] IoFailure),
    /// G-code, but no machine to read it through.
    #[error("{file}: G-code is read through the machine's kinematics: give ‹machine› MACHINE.toml")]
    NoMachine {
        /// File name as given.
        file: String,
    },
    /// The machine's axes cannot be read from G-code.
    #[error("{file}: {error}")]
    Letters {
        /// File name as given.
        file: String,
        /// Why (in the message, not repeated as a cause).
        error: crate::nc::LetterError,
    },
    /// The output the postures streamed into could not be written ([`name_output`]).
    #[error("{output}: cannot write")]
    Output {
        /// The output's name as given.
        output: String,
        /// The failed write.
        #[source]
        source: IoFailure,
    },
}

impl From<InputError> for ReadError {
    fn from(e: InputError) -> ReadError {
        ReadError::Located(Box::new(e))
    }
}

/// Turn a parse error into a diagnostic naming the file.
pub fn parse_diagnostic(file: &Path, e: ParseError) -> ReadError {
    match e {
        ParseError::Syntax(s) => InputError::new(file, &s).into(),
        ParseError::Io(io) => read_error(file, io),
    }
}

/// Turn a lowering error into a diagnostic naming the file.
pub fn lower_diagnostic(file: &Path, e: LowerError) -> ReadError {
    match e {
        LowerError::Invalid(s) => InputError::new(file, &s).into(),
        LowerError::Output(io) => IoFailure {
            context: OUTPUT_FAILED.into(),
            source: io,
        }
        .into(),
    }
}

const OUTPUT_FAILED: &str = "writing the output failed";

/// Name the output in a failure to write it (a full disk, a closed device): the lowering
/// that streams into it does not know its name.
pub fn name_output(e: ReadError, output: &Path) -> ReadError {
    match e {
        ReadError::Io(f) if f.context == OUTPUT_FAILED => ReadError::Output {
            output: output.display().to_string(),
            source: f,
        },
        e => e,
    }
}

/// Open a tool-path file (`-`: standard input) for reading within its budget
/// ([`super::input::TOOLPATH`]: a line of at most 1 MiB, 8 GiB in all), its line ends made
/// `\n` or `\r\n` ([`LoneCr`]).
pub fn open(path: &Path) -> Result<BufReader<LoneCr<Bounded>>, ReadError> {
    let f = super::input::open(path, "tool path", super::input::TOOLPATH)?;
    Ok(BufReader::with_capacity(1 << 16, LoneCr::new(f)))
}

/// A tool-path file opened once, its first bytes (read for [`open_detected`]) put back in
/// front of the rest.
pub type Opened = BufReader<std::io::Chain<std::io::Cursor<Vec<u8>>, BufReader<LoneCr<Bounded>>>>;

/// Open `path` ([`open`]) and decide from its first 64 KiB, read once, whether it holds
/// CLSF, contact12 or G-code; the reader hands on every byte from the first.
pub fn open_detected(path: &Path) -> Result<(InputKind, Opened), ReadError> {
    let mut reader = open(path)?;
    let mut head = Vec::with_capacity(1 << 16);
    (&mut reader)
        .take(1 << 16)
        .read_to_end(&mut head)
        .map_err(|e| read_error(path, e))?;
    let kind = kind_of(&head);
    Ok((
        kind,
        BufReader::with_capacity(1 << 16, std::io::Cursor::new(head).chain(reader)),
    ))
}

/// A failed read of `path`: the budget's own error ([`super::input::InputError`]), or the
/// I/O error with the file named.
fn read_error(path: &Path, e: std::io::Error) -> ReadError {
    match super::input::take_error(e) {
        Ok(budget) => budget.into(),
        Err(io) => IoFailure {
            context: format!("{}: reading failed", path.display()),
            source: io,
        }
        .into(),
    }
}

/// The kind of a tool-path file from its first bytes.
fn kind_of(head: &[u8]) -> InputKind {
    let text = String::from_utf8_lossy(head);
    if looks_like_contact12(&text) {
        InputKind::Contact12
    } else if looks_like_gcode(&text) {
        InputKind::Gcode
    } else {
        InputKind::Clsf
    }
}

/// A reader that turns every lone `\r` (classic Mac OS line ends) into `\n` and leaves
/// `\r\n` and `\n` as they are, so the line readers of CLSF, contact12 and G-code (which
/// end a line at `\n`) read CR-only files line by line, with the same line numbers.
pub struct LoneCr<R> {
    inner: R,
    buf: Vec<u8>,
    pos: usize,
    /// The last byte read was a `\r` whose meaning waits for the next byte.
    held_cr: bool,
    chunk: Box<[u8]>,
}

impl<R: Read> LoneCr<R> {
    /// Wrap `inner`.
    pub fn new(inner: R) -> LoneCr<R> {
        LoneCr {
            inner,
            buf: Vec::new(),
            pos: 0,
            held_cr: false,
            chunk: vec![0u8; 1 << 16].into_boxed_slice(),
        }
    }

    /// Read the next chunk into `buf`; false at the end of the input.
    fn fill(&mut self) -> std::io::Result<bool> {
        self.buf.clear();
        self.pos = 0;
        loop {
            let n = match self.inner.read(&mut self.chunk) {
                Ok(n) => n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e),
            };
            let c = &self.chunk[..n];
            if std::mem::take(&mut self.held_cr) {
                self.buf.push(if c.first() == Some(&b'\n') {
                    b'\r'
                } else {
                    b'\n'
                });
            }
            for (i, &b) in c.iter().enumerate() {
                if b != b'\r' {
                    self.buf.push(b);
                } else if let Some(&next) = c.get(i + 1) {
                    self.buf.push(if next == b'\n' { b'\r' } else { b'\n' });
                } else {
                    self.held_cr = true;
                }
            }
            if n == 0 || !self.buf.is_empty() {
                return Ok(!self.buf.is_empty());
            }
        }
    }
}

impl<R: Read> Read for LoneCr<R> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        if out.is_empty() {
            return Ok(0);
        }
        if self.pos == self.buf.len() && !self.fill()? {
            return Ok(0);
        }
        let n = out.len().min(self.buf.len() - self.pos);
        out[..n].copy_from_slice(&self.buf[self.pos..self.pos + n]);
        self.pos += n;
        Ok(n)
    }
}

/// Decide whether `path` holds CLSF, contact12 or G-code, from its first 64 KiB (read
/// once: standard input or a pipe is replayed to the next reader, see [`super::input`]).
pub fn detect(path: &Path) -> Result<InputKind, ReadError> {
    Ok(open_detected(path)?.0)
}

/// Read `path` (CLSF or contact12, by content), lowering as it goes; `sink` receives
/// every posture with the header of its path. Postures are kept in the returned program
/// only when `opts.keep_postures`.
pub fn stream_program(
    path: &Path,
    opts: impl Into<ReadOptions>,
    sink: &mut PostureSink<'_>,
) -> Result<Program, ReadError> {
    let (kind, reader) = open_detected(path)?;
    stream_from(path, kind, reader, opts, sink)
}

/// [`stream_program`] on an already opened reader.
pub fn stream_from(
    path: &Path,
    kind: InputKind,
    reader: impl BufRead,
    opts: impl Into<ReadOptions>,
    sink: &mut PostureSink<'_>,
) -> Result<Program, ReadError> {
    stream_as::<false>(path, kind, reader, opts.into(), &mut |t, p, _| sink(t, p))
}

/// What [`stream_written_from`] hands on: each posture with its path, and the numbers of
/// its `GOTO` line as written when the reader kept them.
pub type WrittenSink<'a> =
    dyn FnMut(&Toolpath, &Posture, Option<&Written>) -> std::io::Result<()> + 'a;

/// [`stream_from`], handing each posture on with the numbers of its `GOTO` line as written
/// (CLSF lines read by [`ClsfReader::next_goto_written`]; `None` for anything else), for a
/// writer that copies the numbers it would print the same way.
pub fn stream_written_from(
    path: &Path,
    kind: InputKind,
    reader: impl BufRead,
    opts: impl Into<ReadOptions>,
    sink: &mut WrittenSink<'_>,
) -> Result<Program, ReadError> {
    stream_as::<true>(path, kind, reader, opts.into(), sink)
}

fn stream_as<const WRITTEN: bool>(
    path: &Path,
    kind: InputKind,
    reader: impl BufRead,
    opts: ReadOptions,
    sink: &mut WrittenSink<'_>,
) -> Result<Program, ReadError> {
    let mut low = Lowerer::new(opts.lower.clone());
    let stem = || {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    // With `WRITTEN`, the last GOTO lines as written (a posture leaves the lowering
    // when the next record comes, so its line is the one before the current one); nothing
    // is kept otherwise, and no posture is handed on with a line.
    // The lowering may hold postures back for their move kind (up to a feed segment's
    // `FEED_HOLD_LIMIT`): the ring keeps that many lines more.
    let mut kept = vec![Written::default(); KEPT];
    let read = || -> Result<(), ReadError> {
        match kind {
            InputKind::Clsf => {
                let mut k = 0;
                let mut records = ClsfReader::new(reader);
                loop {
                    // The bulk of a file, GOTO lines, from the reader's buffer to the lowering
                    // without a `Record` between them.
                    loop {
                        let next = if WRITTEN {
                            records.next_goto_written(&mut kept[k])
                        } else {
                            records.next_goto()
                        };
                        let Some((n, line)) = next.map_err(|e| parse_diagnostic(path, e))? else {
                            break;
                        };
                        low.push_goto(&n, line, &mut |t, p| sink(t, p, kept_for(&kept, p)))
                            .map_err(|e| lower_diagnostic(path, e))?;
                        k = (k + 1) % KEPT;
                    }
                    let Some(rec) = records.next() else {
                        break;
                    };
                    let rec = rec.map_err(|e| parse_diagnostic(path, e))?;
                    low.push(&rec, &mut |t, p| sink(t, p, kept_for(&kept, p)))
                        .map_err(|e| lower_diagnostic(path, e))?;
                }
            }
            InputKind::Gcode => {
                let Some(machine) = opts.machine.as_ref() else {
                    return Err(ReadError::NoMachine {
                        file: path.display().to_string(),
                    });
                };
                let mut nc = NcReader::new(machine, opts.rtcp, &stem()).map_err(|error| {
                    ReadError::Letters {
                        file: path.display().to_string(),
                        error,
                    }
                })?;
                for block in GcodeReader::new(reader) {
                    let block = block.map_err(|e| parse_diagnostic(path, e))?;
                    nc.push(&block, &mut low, &mut |t, p| sink(t, p, None))
                        .map_err(|e| lower_diagnostic(path, e))?;
                }
                nc.finish(&mut low, &mut |t, p| sink(t, p, None))
                    .map_err(|e| lower_diagnostic(path, e))?;
            }
            InputKind::Contact12 => {
                let name = stem();
                low.begin_path(&name, "", &mut |t, p| sink(t, p, None))
                    .map_err(|e| lower_diagnostic(path, e))?;
                for row in Contact12Reader::new(reader) {
                    let row = row.map_err(|e| parse_diagnostic(path, e))?;
                    low.push_contact12(&row, &mut |t, p| sink(t, p, None))
                        .map_err(|e| lower_diagnostic(path, e))?;
                }
            }
        }
        Ok(())
    };
    if let Err(e) = read() {
        // The postures held back for their kind (`toolpath::lower`'s move kinds) go out as
        // they stand, so that a stream into a FIFO gets every row before the bad line.
        let _ = low.release_held(&mut |t, p| sink(t, p, None));
        return Err(e);
    }
    low.finish(&mut |t, p| sink(t, p, kept_for(&kept, p)))
        .map_err(|e| lower_diagnostic(path, e))
}

/// GOTO lines kept as written while their postures may still be in the lowering.
const KEPT: usize = crate::toolpath::lower::FEED_HOLD_LIMIT + 2;

/// The kept line of `p`, if it is one of them.
fn kept_for<'k>(kept: &'k [Written], p: &Posture) -> Option<&'k Written> {
    kept.iter().find(|w| w.line != 0 && w.line == p.line)
}

/// Read and lower a CLSF or contact12 file (chosen by content), MSYS not applied.
pub fn read_program(path: &Path) -> Result<Program, ReadError> {
    read_program_with(path, LowerOptions::default())
}

/// [`read_program`] with options (e.g. `apply_msys` for `--absolute`, the machine for
/// G-code).
pub fn read_program_with(path: &Path, opts: impl Into<ReadOptions>) -> Result<Program, ReadError> {
    let mut sink = |_: &Toolpath, _: &Posture| Ok(());
    stream_program(path, opts, &mut sink)
}

#[cfg(test)]
mod line_end_tests {
    use super::LoneCr;
    use std::io::Read;

    /// Reads one byte at a time: a CR at the end of every chunk.
    struct Trickle<'a>(&'a [u8]);
    impl Read for Trickle<'_> {
        fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
            let n = self.0.len().min(1).min(out.len());
            out[..n].copy_from_slice(&self.0[..n]);
            self.0 = &self.0[n..];
            Ok(n)
        }
    }

    #[test]
    fn lone_cr_becomes_lf_and_crlf_stays() {
        let input = b"A\rB\r\nC\n\r\rD\r";
        let want = b"A\nB\r\nC\n\n\nD\n".to_vec();
        let mut out = Vec::new();
        LoneCr::new(&input[..]).read_to_end(&mut out).unwrap();
        assert_eq!(out, want);
        out.clear();
        LoneCr::new(Trickle(input)).read_to_end(&mut out).unwrap();
        assert_eq!(out, want);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs::File;
    use std::io::Write;

    fn temp(text: &str, name: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
        let p = dir.path().join(name);
        let mut f = File::create(&p).unwrap_or_else(|e| panic!("{e}"));
        f.write_all(text.as_bytes())
            .unwrap_or_else(|e| panic!("{e}"));
        (dir, p)
    }

    #[test]
    fn reads_both_kinds() {
        let (_d, p) = temp("TOOL PATH/A,TOOL,T\nGOTO/1,2,3\nEND-OF-PATH\n", "a.cls");
        let prog = read_program(&p).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(prog.paths[0].postures.len(), 1);
        let (_d, p) = temp("1 2 3 0 0 1 1 2 3 0 0 1\n", "b.txt");
        let prog = read_program(&p).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(prog.paths[0].name, "b");
        assert!(prog.paths[0].postures[0].contact.is_some());
    }

    /// `crest convert`'s contact12 rows: copied where a GOTO's numbers print as written,
    /// printed elsewhere; the bytes are those of printing every row, for NX's lines, the
    /// same numbers written otherwise, and the same file in inches.
    #[test]
    fn rows_copied_as_written_are_the_rows_printed() {
        use crate::toolpath::Contact12Writer;
        let sample = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/samples/clsf/ball_lead15_contact.cls"
        );
        let sample = std::fs::read_to_string(sample).unwrap_or_else(|e| panic!("{e}"));
        let mut text = String::new();
        for (k, line) in sample.lines().enumerate() {
            text.push_str(line);
            text.push('\n');
            if let Some(numbers) = line.strip_prefix("GOTO/") {
                let otherwise: Vec<String> = numbers
                    .split(',')
                    .enumerate()
                    .map(|(i, t)| match (k + i) % 7 {
                        0 => format!("{t}0"),
                        1 if !t.starts_with('-') => format!("+{t}"),
                        2 => format!("{t}E0"),
                        3 if t.starts_with("0.") => t[1..].to_string(),
                        4 => format!("0{t}").replace("0-", "-0"),
                        _ => t.to_string(),
                    })
                    .collect();
                text.push_str(&format!("GOTO/{}\n", otherwise.join(",")));
            }
        }
        let inches = text.replacen("\nGOTO/", "\nUNITS/INCH\nGOTO/", 1);
        let mut rows = Vec::new();
        for (name, text) in [("mixed", &text), ("inches", &inches)] {
            let (_d, p) = temp(text, "a.cls");
            let printed = {
                let mut out = Vec::new();
                let mut cw = Contact12Writer::new(false);
                let mut sink = |_: &Toolpath, q: &Posture| cw.posture(q, &mut out);
                let r = File::open(&p)
                    .map(BufReader::new)
                    .unwrap_or_else(|e| panic!("{e}"));
                stream_from(&p, InputKind::Clsf, r, LowerOptions::default(), &mut sink)
                    .unwrap_or_else(|e| panic!("{e:?}"));
                cw.flush(&mut out).unwrap_or_else(|e| panic!("{e}"));
                out
            };
            let (mut out, mut copied) = (Vec::new(), 0);
            let mut cw = Contact12Writer::new(false);
            let mut sink = |_: &Toolpath, q: &Posture, w: Option<&Written>| {
                copied += usize::from(w.is_some());
                cw.posture_written(q, w, &mut out)
            };
            let r = File::open(&p)
                .map(BufReader::new)
                .unwrap_or_else(|e| panic!("{e}"));
            stream_written_from(&p, InputKind::Clsf, r, LowerOptions::default(), &mut sink)
                .unwrap_or_else(|e| panic!("{e:?}"));
            cw.flush(&mut out).unwrap_or_else(|e| panic!("{e}"));
            assert!(printed.len() > 10_000 && copied > 100, "{name}: {copied}");
            assert!(out == printed, "{name}");
            rows.push(out);
        }
        // The inch file's rows are other numbers (scaled: printed, none copied).
        assert!(rows[0] != rows[1]);
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let (_d, p) = temp("TOOL PATH/A,TOOL,T\nGOTO/1,2,zz\n", "bad.cls");
        let e = read_program(&p)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.ends_with("bad.cls:2:10: expected a number, found `zz`"),
            "{e}"
        );
    }
}
