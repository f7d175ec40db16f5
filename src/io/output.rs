//! Writing outputs without losing anything, like coreutils: a regular file is replaced
//! atomically (a temporary file in the same folder, renamed at the end); a character or block
//! device, FIFO or socket is written directly; a symbolic link is written through to its
//! target; an output that is one of the command's inputs (the same file after resolving links)
//! is refused. Temporary files are listed so that an interrupted process can remove them
//! ([`remove_temporaries`], called by the binary's SIGINT/SIGTERM/SIGHUP handler).
//!
//! A command's outputs land together or not at all ([`Outputs`]): a command checks them all
//! before its work ([`check_file`], [`check_folder`]), stages each in full beside its
//! destination, and renames them into place only when every one is written; a failure
//! leaves every existing file as it was ([`write_atomic`] and [`write_set`] are sets of one
//! file and of one folder).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Files the process has opened as inputs: their canonical path and (on Unix) device and
/// inode.
static INPUTS: Mutex<Vec<Input>> = Mutex::new(Vec::new());
/// Temporary files and folders not yet renamed into place.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

#[derive(Debug, Clone, PartialEq, Eq)]
struct Input {
    path: PathBuf,
    inode: Option<(u64, u64)>,
}

/// The (device, inode) of a file, and whether it has more than one hard link.
fn inode_links(path: &Path) -> Option<((u64, u64), bool)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        std::fs::metadata(path)
            .ok()
            .filter(|m| m.ino() != 0)
            .map(|m| ((m.dev(), m.ino()), m.nlink() > 1))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

fn inode(path: &Path) -> Option<(u64, u64)> {
    inode_links(path).map(|(id, _)| id)
}

/// The (device, inode) of a possible output, only when it has more than one hard link: the
/// only case where a second canonical path names the same file. A file with one link is told
/// apart from the inputs by its path alone (some sandboxed file systems report inode numbers
/// that repeat across files, and a match on those would refuse ordinary outputs).
fn linked_inode(path: &Path) -> Option<(u64, u64)> {
    inode_links(path).and_then(|(id, many)| many.then_some(id))
}

/// Record `path` as an input of this process: writing an output onto it (or onto a link or
/// a hard link to it) will be refused.
pub fn register_input(path: &Path) {
    let Ok(canonical) = std::fs::canonicalize(path) else {
        return;
    };
    let entry = Input {
        inode: inode(&canonical),
        path: canonical,
    };
    let mut v = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
    if !v.contains(&entry) {
        v.push(entry);
    }
}

fn is_input(path: &Path) -> bool {
    let Ok(canonical) = std::fs::canonicalize(path) else {
        return false;
    };
    let id = linked_inode(&canonical);
    INPUTS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .any(|i| {
            // The same path, or a hard link to a file that is still that input (an inode
            // freed by a deleted input and reused is not).
            i.path == canonical
                || (id.is_some()
                    && i.inode == id
                    && inode(&i.path) == id
                    && same_contents_stamp(&i.path, &canonical))
        })
}

/// Two names of one file share its length and modification time; files that merely report
/// the same inode number on an unusual file system rarely do.
fn same_contents_stamp(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(a), Ok(b)) => a.len() == b.len() && a.modified().ok() == b.modified().ok(),
        _ => false,
    }
}

fn track(path: &Path) {
    TEMPORARIES
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(path.to_path_buf());
}

fn untrack(path: &Path) {
    TEMPORARIES
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|p| p != path);
}

/// Output folders made by a set of outputs that has not landed yet.
static MADE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn track_folder(path: &Path) {
    MADE.lock()
        .unwrap_or_else(|e| e.into_inner())
        .push(path.to_path_buf());
}

fn untrack_folder(path: &Path) {
    MADE.lock()
        .unwrap_or_else(|e| e.into_inner())
        .retain(|p| p != path);
}

/// Remove every temporary file and folder not yet renamed into place, then the output
/// folders made for sets that have not landed, when they are empty (for a signal handler: it
/// only takes a lock and unlinks).
pub fn remove_temporaries() {
    let list = std::mem::take(&mut *TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner()));
    for p in list {
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(&p);
        } else {
            let _ = std::fs::remove_file(&p);
        }
    }
    let made = std::mem::take(&mut *MADE.lock().unwrap_or_else(|e| e.into_inner()));
    for d in made.iter().rev() {
        let _ = std::fs::remove_dir(d);
    }
}

fn error(path: &Path, kind: std::io::ErrorKind, what: String) -> std::io::Error {
    std::io::Error::new(kind, format!("{}: {what}", path.display()))
}

/// Where an output really goes: the path itself, or the target of a symbolic link (followed
/// to the end), and whether it is a special file (device, FIFO, socket) to write directly.
fn destination(path: &Path) -> std::io::Result<(PathBuf, bool)> {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                // A link to a pipe, socket or device is written through the link itself:
                // `/dev/stdout` → `/proc/self/fd/1` → `pipe:[…]`, which names no path.
                if let Ok(t) = std::fs::metadata(&p)
                    && !t.is_file()
                    && !t.is_dir()
                {
                    return Ok((p, true));
                }
                let target = std::fs::read_link(&p)?;
                p = match p.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            Ok(m) => {
                if m.is_dir() {
                    return Err(error(
                        path,
                        std::io::ErrorKind::InvalidInput,
                        "is a directory, not a file".into(),
                    ));
                }
                return Ok((p, !m.file_type().is_file()));
            }
            Err(e) if missing(&e) => return Ok((p, false)),
            Err(e) => return Err(error(path, e.kind(), e.to_string())),
        }
    }
    Err(error(
        path,
        std::io::ErrorKind::InvalidInput,
        "too many levels of symbolic links".into(),
    ))
}

/// Write one output (see the module docs). `fill` writes the content; on any failure the
/// destination is left as it was (a regular file) and the temporary file is removed. A
/// device, FIFO or socket is written directly (there is nothing to replace).
pub fn write_atomic<F>(path: &Path, fill: F) -> std::io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let (dest, special) = destination(path)?;
    refuse_input(path, &dest)?;
    if special {
        let f = std::fs::OpenOptions::new().write(true).open(&dest)?;
        let mut w = std::io::BufWriter::with_capacity(1 << 16, f);
        fill(&mut w)?;
        return w.flush();
    }
    let mut set = Outputs::new();
    set.file(path, fill)?;
    set.land().map(drop)
}

fn refuse_input(path: &Path, dest: &Path) -> std::io::Result<()> {
    if is_input(dest) {
        return Err(error(
            path,
            std::io::ErrorKind::AlreadyExists,
            "is one of this command's inputs; refusing to overwrite it (choose another output)"
                .into(),
        ));
    }
    Ok(())
}

/// The folder a file goes into (`.` for a bare name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// A path that does not exist (or has a file where a folder of it should be).
fn missing(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
    )
}

/// A temporary file can be made in the folder `dir` (made and removed at once).
fn writable(what: &Path, dir: &Path) -> std::io::Result<()> {
    temp_builder().tempfile_in(dir).map(drop).map_err(|e| {
        error(
            what,
            e.kind(),
            format!("cannot write in the folder {}: {e}", dir.display()),
        )
    })
}

fn temp_builder() -> tempfile::Builder<'static, 'static> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(".crest-").suffix(".tmp");
    // tempfile creates 0600 files; outputs are ordinary files (0666 less the umask).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder
}

/// Check, before any work, that `path` can be written as an output file: it is not a folder
/// nor one of the command's inputs, its folder exists and a file can be made there. Cheap
/// (a few `stat`s and one empty temporary file), so a command can refuse a blocked output
/// at once instead of after minutes of work.
pub fn check_file(path: &Path) -> std::io::Result<()> {
    let (dest, special) = destination(path)?;
    refuse_input(path, &dest)?;
    if special {
        return Ok(());
    }
    let dir = folder_of(&dest);
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => writable(path, &dir),
        Ok(_) => Err(error(
            path,
            std::io::ErrorKind::InvalidInput,
            format!("{} is not a folder", dir.display()),
        )),
        Err(e) if missing(&e) => Err(error(
            path,
            std::io::ErrorKind::NotFound,
            format!("the folder {} does not exist", dir.display()),
        )),
        Err(e) => Err(error(path, e.kind(), e.to_string())),
    }
}

/// Check, before any work, that the files `names` can be written into the output folder
/// `dir` (made when missing, with its missing parents): `dir` is a folder or can be made,
/// and each name passes [`check_file`].
pub fn check_folder(dir: &Path, names: &[String]) -> std::io::Result<()> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => names.iter().try_for_each(|n| check_file(&dir.join(n))),
        Ok(_) => Err(error(
            dir,
            std::io::ErrorKind::InvalidInput,
            "exists and is not a folder".into(),
        )),
        Err(e) if missing(&e) => {
            // The nearest folder that exists must be a folder we can write in.
            let mut up = folder_of(dir);
            loop {
                match std::fs::metadata(&up) {
                    Ok(m) if m.is_dir() => return writable(dir, &up),
                    Ok(_) => {
                        return Err(error(
                            dir,
                            std::io::ErrorKind::InvalidInput,
                            format!("{} is not a folder", up.display()),
                        ));
                    }
                    Err(e) if missing(&e) => match up.parent() {
                        Some(p) if !p.as_os_str().is_empty() => up = p.to_path_buf(),
                        _ => return Err(error(dir, e.kind(), e.to_string())),
                    },
                    Err(e) => return Err(error(dir, e.kind(), e.to_string())),
                }
            }
        }
        Err(e) => Err(error(dir, e.kind(), e.to_string())),
    }
}

/// One staged output: where it was asked for, and its content so far.
#[derive(Debug)]
struct Staged {
    /// The path as the command named it (for messages and the list of files written).
    given: PathBuf,
    content: Content,
}

#[derive(Debug)]
enum Content {
    /// A temporary file beside the destination, renamed over it when the set lands.
    Beside(tempfile::TempPath),
    /// For a device, FIFO or socket: an anonymous temporary file copied into it when the set
    /// lands.
    Special(std::fs::File),
}

/// The outputs of one command, landed together or not at all: every file is written in
/// full to a temporary file beside its destination ([`Outputs::file`], [`Outputs::folder`]);
/// [`Outputs::land`] then checks every destination again and renames all of them into
/// place, putting back the files it replaced if one rename fails. Dropped without landing
/// (an error, a later failure), it removes its temporary files and the folders it made, and
/// no existing file has changed.
#[derive(Debug, Default)]
pub struct Outputs {
    staged: Vec<Staged>,
    /// Folders made for this set, outermost first.
    made: Vec<PathBuf>,
}

impl Outputs {
    /// An empty set.
    pub fn new() -> Outputs {
        Outputs::default()
    }

    /// Stage the file `path`: `fill` writes its content into a temporary file beside it.
    pub fn file<F>(&mut self, path: &Path, fill: F) -> std::io::Result<()>
    where
        F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
    {
        check_file(path)?;
        let (dest, special) = destination(path)?;
        let content = if special {
            let mut f = tempfile::tempfile()?;
            {
                let mut w = std::io::BufWriter::with_capacity(1 << 16, &mut f);
                fill(&mut w)?;
                w.flush()?;
            }
            Content::Special(f)
        } else {
            let mut tmp = temp_builder().tempfile_in(folder_of(&dest))?;
            track(tmp.path());
            let filled = (|| {
                let mut w = std::io::BufWriter::with_capacity(1 << 16, tmp.as_file_mut());
                fill(&mut w)?;
                w.flush()
            })();
            if let Err(e) = filled {
                untrack(tmp.path());
                return Err(e);
            }
            Content::Beside(tmp.into_temp_path())
        };
        self.staged.push(Staged {
            given: path.to_path_buf(),
            content,
        });
        Ok(())
    }

    /// Stage the files `(name, bytes)` in the output folder `dir`, made (with its missing
    /// parents) when it does not exist.
    pub fn folder(&mut self, dir: &Path, files: &[(String, Vec<u8>)]) -> std::io::Result<()> {
        let names: Vec<String> = files.iter().map(|(n, _)| n.clone()).collect();
        check_folder(dir, &names)?;
        self.make_folder(dir)?;
        for (name, bytes) in files {
            self.file(&dir.join(name), |w| w.write_all(bytes))?;
        }
        Ok(())
    }

    fn make_folder(&mut self, dir: &Path) -> std::io::Result<()> {
        let mut missing = Vec::new();
        let mut p = dir.to_path_buf();
        while !p.as_os_str().is_empty() && std::fs::symlink_metadata(&p).is_err() {
            missing.push(p.clone());
            match p.parent() {
                Some(q) => p = q.to_path_buf(),
                None => break,
            }
        }
        std::fs::create_dir_all(dir).map_err(|e| error(dir, e.kind(), e.to_string()))?;
        for m in missing.into_iter().rev() {
            track_folder(&m);
            self.made.push(m);
        }
        Ok(())
    }

    /// Rename every staged file into place, or none: each destination is checked again
    /// first, and when a rename fails the files already replaced are put back (from hard
    /// links kept beside them) and the new ones removed. Returns the paths, in order.
    pub fn land(mut self) -> std::io::Result<Vec<PathBuf>> {
        let staged = std::mem::take(&mut self.staged);
        for s in &staged {
            let (dest, special) = destination(&s.given)?;
            refuse_input(&s.given, &dest)?;
            if special != matches!(s.content, Content::Special(_)) {
                return Err(error(
                    &s.given,
                    std::io::ErrorKind::InvalidInput,
                    "changed while the command ran".into(),
                ));
            }
        }
        let given: Vec<PathBuf> = staged.iter().map(|s| s.given.clone()).collect();
        let temporaries: Vec<PathBuf> = staged
            .iter()
            .filter_map(|s| match &s.content {
                Content::Beside(t) => Some(t.to_path_buf()),
                Content::Special(_) => None,
            })
            .collect();
        // (destination, backup of the file it replaced) for each file landed so far.
        let mut landed: Vec<(PathBuf, Option<tempfile::TempPath>)> = Vec::new();
        let mut specials = Vec::new();
        let mut result = Ok(());
        for s in staged {
            let dest = match destination(&s.given) {
                Ok((d, _)) => d,
                Err(e) => {
                    result = Err(e);
                    break;
                }
            };
            let tmp = match s.content {
                Content::Beside(t) => t,
                Content::Special(f) => {
                    specials.push((s.given, dest, f));
                    continue;
                }
            };
            let backup = match backup(&dest) {
                Ok(b) => b,
                Err(e) => {
                    untrack(&tmp);
                    result = Err(error(
                        &s.given,
                        e.kind(),
                        format!("cannot keep a copy: {e}"),
                    ));
                    break;
                }
            };
            let tmp_path = tmp.to_path_buf();
            match tmp.persist(&dest) {
                Ok(()) => {
                    untrack(&tmp_path);
                    landed.push((dest, backup));
                }
                Err(e) => {
                    untrack(&tmp_path);
                    if let Some(b) = &backup {
                        untrack(b);
                    }
                    result = Err(error(&s.given, e.error.kind(), e.error.to_string()));
                    break;
                }
            }
        }
        if result.is_ok() {
            for (given, dest, mut f) in specials {
                use std::io::Seek;
                let copied = f.rewind().and_then(|()| {
                    let out = std::fs::OpenOptions::new().write(true).open(&dest)?;
                    let mut w = std::io::BufWriter::with_capacity(1 << 16, out);
                    std::io::copy(&mut f, &mut w)?;
                    w.flush()
                });
                if let Err(e) = copied {
                    result = Err(error(&given, e.kind(), e.to_string()));
                    break;
                }
            }
        }
        for t in &temporaries {
            untrack(t);
        }
        match result {
            Ok(()) => {
                for (_, b) in landed {
                    if let Some(b) = b {
                        untrack(&b);
                    }
                }
                for d in self.made.drain(..) {
                    untrack_folder(&d);
                }
                Ok(given)
            }
            Err(e) => {
                for (dest, b) in landed.into_iter().rev() {
                    match b {
                        Some(b) => {
                            untrack(&b);
                            let _ = b.persist(&dest);
                        }
                        None => {
                            let _ = std::fs::remove_file(&dest);
                        }
                    }
                }
                Err(e)
            }
        }
    }
}

/// A second name for the regular file `dest` (a hard link, or a copy where links are not
/// possible) beside it, so that it can be put back; `None` when there is no such file.
fn backup(dest: &Path) -> std::io::Result<Option<tempfile::TempPath>> {
    match std::fs::symlink_metadata(dest) {
        Ok(m) if m.file_type().is_file() => {}
        Ok(_) => return Ok(None),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e),
    }
    let dir = folder_of(dest);
    let b = temp_builder()
        .make_in(&dir, |p| {
            std::fs::hard_link(dest, p).or_else(|_| std::fs::copy(dest, p).map(drop))
        })?
        .into_temp_path();
    track(&b);
    Ok(Some(b))
}

impl Drop for Outputs {
    fn drop(&mut self) {
        for s in self.staged.drain(..) {
            if let Content::Beside(t) = &s.content {
                untrack(t);
            }
        }
        for d in self.made.drain(..).rev() {
            let _ = std::fs::remove_dir(&d);
            untrack_folder(&d);
        }
    }
}

/// A temporary folder beside an output folder, where a command that reads back what it
/// wrote (the demo) builds its set of files before [`Staging::land`] moves them in; removed
/// when dropped or on SIGINT/SIGTERM/SIGHUP.
#[derive(Debug)]
pub struct Staging {
    dir: Option<tempfile::TempDir>,
}

impl Staging {
    /// A staging folder for the output folder `out`.
    pub fn beside(out: &Path) -> std::io::Result<Staging> {
        let parent = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)?;
        let dir = tempfile::Builder::new()
            .prefix(".crest-set-")
            .tempdir_in(&parent)?;
        track(dir.path());
        Ok(Staging { dir: Some(dir) })
    }

    /// The staging folder.
    pub fn path(&self) -> &Path {
        self.dir.as_ref().map_or(Path::new("."), |d| d.path())
    }

    /// Move every file of the staging folder into `out` (as [`write_set`]); returns the
    /// final paths, sorted by name.
    pub fn land(self, out: &Path) -> std::io::Result<Vec<PathBuf>> {
        let mut files = Vec::new();
        let mut names: Vec<_> = std::fs::read_dir(self.path())?
            .flatten()
            .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        for n in names {
            files.push((n.clone(), std::fs::read(self.path().join(&n))?));
        }
        write_set(out, &files)
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if let Some(d) = self.dir.take() {
            untrack(d.path());
        }
    }
}

/// Write a set of files `(name, bytes)` into the folder `dir` (made when missing) so that the
/// set lands whole or not at all ([`Outputs::folder`], [`Outputs::land`]). Returns the paths
/// written, in order.
pub fn write_set(dir: &Path, files: &[(String, Vec<u8>)]) -> std::io::Result<Vec<PathBuf>> {
    let mut set = Outputs::new();
    set.folder(dir, files)?;
    set.land()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_are_replaced_and_inputs_refused() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.txt");
        std::fs::write(&p, "old").unwrap();
        write_atomic(&p, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        let inp = d.path().join("in.txt");
        std::fs::write(&inp, "input").unwrap();
        register_input(&inp);
        let e = write_atomic(&inp, |w| w.write_all(b"x")).unwrap_err();
        assert!(e.to_string().contains("inputs"), "{e}");
        assert_eq!(std::fs::read_to_string(&inp).unwrap(), "input");
        // No temporary file left.
        let left: Vec<_> = std::fs::read_dir(d.path())
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with(".crest-"))
            .collect();
        assert!(left.is_empty());
    }

    #[cfg(unix)]
    #[test]
    fn links_are_written_through_and_devices_directly() {
        let d = tempfile::tempdir().unwrap();
        let target = d.path().join("target.txt");
        std::fs::write(&target, "old").unwrap();
        let link = d.path().join("link.txt");
        std::os::unix::fs::symlink("target.txt", &link).unwrap();
        write_atomic(&link, |w| w.write_all(b"through")).unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "through");
        // A link to an input is refused, and so is a hard link to it.
        register_input(&target);
        assert!(write_atomic(&link, |w| w.write_all(b"x")).is_err());
        let hard = d.path().join("hard.txt");
        std::fs::hard_link(&target, &hard).unwrap();
        assert!(write_atomic(&hard, |w| w.write_all(b"x")).is_err());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "through");
        // /dev/null stays a device.
        write_atomic(Path::new("/dev/null"), |w| w.write_all(b"gone")).unwrap();
        use std::os::unix::fs::FileTypeExt;
        assert!(
            std::fs::metadata("/dev/null")
                .unwrap()
                .file_type()
                .is_char_device()
        );
    }

    #[test]
    fn sets_written_into_one_new_folder_at_once_all_land() {
        // Shards of one run write into the same folder, which none of them finds there.
        for round in 0..20 {
            let base = tempfile::tempdir().unwrap();
            let dir = base.path().join("shards");
            std::thread::scope(|s| {
                for k in 0..4 {
                    let dir = &dir;
                    s.spawn(move || {
                        let files = [(format!("shard-{k}.jsonl"), vec![b'0' + k as u8])];
                        write_set(dir, &files).unwrap_or_else(|e| panic!("round {round}: {e}"));
                    });
                }
            });
            for k in 0..4u8 {
                let got = std::fs::read(dir.join(format!("shard-{k}.jsonl"))).unwrap();
                assert_eq!(got, [b'0' + k], "round {round}");
            }
            let left: Vec<_> = std::fs::read_dir(base.path()).unwrap().flatten().collect();
            assert_eq!(left.len(), 1, "round {round}: no staging folder is left");
        }
    }

    #[test]
    fn a_blocked_name_changes_nothing() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("set");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("a"), "old a").unwrap();
        std::fs::create_dir(out.join("b")).unwrap();
        let files = vec![
            ("a".to_string(), b"1".to_vec()),
            ("b".to_string(), b"2".to_vec()),
            ("c".to_string(), b"3".to_vec()),
        ];
        let e = check_folder(&out, &["a".into(), "b".into()]).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        let e = write_set(&out, &files).unwrap_err();
        assert!(e.to_string().contains("b: is a directory"), "{e}");
        // A set of files anywhere: the second one blocked after the first is staged.
        let single = d.path().join("single.txt");
        std::fs::write(&single, "old single").unwrap();
        let mut set = Outputs::new();
        set.file(&single, |w| w.write_all(b"new")).unwrap();
        assert!(set.file(&out.join("b"), |w| w.write_all(b"x")).is_err());
        drop(set);
        // A file whose folder does not exist is refused up front, naming the folder.
        let e = check_file(&d.path().join("none/x.txt")).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        assert_eq!(std::fs::read_to_string(out.join("a")).unwrap(), "old a");
        assert_eq!(std::fs::read_to_string(&single).unwrap(), "old single");
        let mut names: Vec<String> = std::fs::read_dir(&out)
            .unwrap()
            .chain(std::fs::read_dir(d.path()).unwrap())
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["a", "b", "set", "single.txt"]);
        // A rename that fails while landing puts back the files already replaced.
        let mut set = Outputs::new();
        set.file(&out.join("a"), |w| w.write_all(b"new a")).unwrap();
        set.file(&out.join("c"), |w| w.write_all(b"new c")).unwrap();
        std::fs::create_dir(out.join("c")).unwrap();
        std::fs::write(out.join("c/inside"), "").unwrap();
        assert!(set.land().is_err());
        assert_eq!(std::fs::read_to_string(out.join("a")).unwrap(), "old a");
        let left = std::fs::read_dir(&out).unwrap().count();
        assert_eq!(left, 3, "a, b, c only");
        // A new folder is removed again when its set does not land.
        let fresh = d.path().join("fresh/deeper");
        let mut set = Outputs::new();
        set.folder(&fresh, &files[..1]).unwrap();
        assert!(fresh.join(".").is_dir());
        drop(set);
        assert!(!d.path().join("fresh").exists());
    }

    #[test]
    fn a_set_lands_whole() {
        let d = tempfile::tempdir().unwrap();
        let out = d.path().join("set");
        let files = vec![
            ("a".to_string(), b"1".to_vec()),
            ("b".to_string(), b"2".to_vec()),
        ];
        let got = write_set(&out, &files).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!(std::fs::read_to_string(out.join("b")).unwrap(), "2");
        // Into an existing folder; nothing left behind.
        write_set(&out, &files).unwrap();
        let names: Vec<String> = std::fs::read_dir(d.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, vec!["set".to_string()]);
    }
}
