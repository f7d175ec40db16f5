//! Writing outputs without losing anything, like coreutils: a regular file is replaced
//! atomically (a temporary file in the same folder, renamed at the end); a character or block
//! device, FIFO or socket is written directly; a symbolic link is written through to its
//! target; an output that is one of the command's inputs (the same file after resolving links)
//! is refused. Temporary files are listed so that an interrupted process can remove them
//! ([`remove_temporaries`], called by the binary's SIGINT/SIGTERM/SIGHUP handler), and a set of files
//! lands whole or not at all ([`write_set`]).

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

/// Remove every temporary file and folder not yet renamed into place (for a signal
/// handler: it only takes a lock and unlinks).
pub fn remove_temporaries() {
    let list = std::mem::take(&mut *TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner()));
    for p in list {
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(&p);
        } else {
            let _ = std::fs::remove_file(&p);
        }
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
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((p, false)),
            Err(e) => return Err(e),
        }
    }
    Err(error(
        path,
        std::io::ErrorKind::InvalidInput,
        "too many levels of symbolic links".into(),
    ))
}

/// Write one output (see the module docs). `fill` writes the content; on any failure the
/// destination is left as it was (a regular file) and the temporary file is removed.
pub fn write_atomic<F>(path: &Path, fill: F) -> std::io::Result<()>
where
    F: FnOnce(&mut dyn Write) -> std::io::Result<()>,
{
    let (dest, special) = destination(path)?;
    if is_input(&dest) {
        return Err(error(
            path,
            std::io::ErrorKind::AlreadyExists,
            "is one of this command's inputs; refusing to overwrite it (choose another output)"
                .into(),
        ));
    }
    if special {
        let f = std::fs::OpenOptions::new().write(true).open(&dest)?;
        let mut w = std::io::BufWriter::with_capacity(1 << 16, f);
        fill(&mut w)?;
        return w.flush();
    }
    let dir = match dest.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".crest-").suffix(".tmp");
    // tempfile creates 0600 files; outputs are ordinary files (0666 less the umask).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(&dir)?;
    let tmp_path = tmp.path().to_path_buf();
    track(&tmp_path);
    let result = (|| {
        {
            let mut buffered = std::io::BufWriter::with_capacity(1 << 16, tmp.as_file_mut());
            fill(&mut buffered)?;
            buffered.flush()?;
        }
        tmp.persist(&dest).map_err(|e| e.error)?;
        Ok(())
    })();
    untrack(&tmp_path);
    result
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

/// Write a set of files `(name, bytes)` into the folder `dir` so that the set lands whole or
/// not at all: everything is written into a temporary folder beside `dir`, then moved in
/// (the temporary folder becomes `dir` when `dir` does not exist yet). Returns the paths
/// written, in order.
pub fn write_set(dir: &Path, files: &[(String, Vec<u8>)]) -> std::io::Result<Vec<PathBuf>> {
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent)?;
    if dir.exists() && !dir.is_dir() {
        return Err(error(
            dir,
            std::io::ErrorKind::InvalidInput,
            "exists and is not a folder".into(),
        ));
    }
    for (name, _) in files {
        let target = dir.join(name);
        if is_input(&target) {
            return Err(error(
                &target,
                std::io::ErrorKind::AlreadyExists,
                "is one of this command's inputs; refusing to overwrite it".into(),
            ));
        }
    }
    let staging = tempfile::Builder::new()
        .prefix(".crest-set-")
        .tempdir_in(&parent)?
        .keep();
    track(&staging);
    let result = (|| {
        for (name, bytes) in files {
            let p = staging.join(name);
            let mut f = std::fs::File::create(&p)?;
            f.write_all(bytes)?;
            f.sync_all().or(Ok::<(), std::io::Error>(()))?;
        }
        // The staging folder becomes `dir` when there is none. Another process may make
        // `dir` in between (the shards of one run written into one folder at once): then
        // the rename fails on the folder it made, and the files are moved in one by one.
        let whole = !dir.exists()
            && match std::fs::rename(&staging, dir) {
                Ok(()) => true,
                Err(_) if dir.is_dir() => false,
                Err(e) => return Err(e),
            };
        if !whole {
            for (name, _) in files {
                let (dest, special) = destination(&dir.join(name))?;
                if special {
                    let bytes = std::fs::read(staging.join(name))?;
                    write_atomic(&dest, |w| w.write_all(&bytes))?;
                } else {
                    std::fs::rename(staging.join(name), dest)?;
                }
            }
        }
        Ok(files.iter().map(|(n, _)| dir.join(n)).collect())
    })();
    if staging.exists() {
        let _ = std::fs::remove_dir_all(&staging);
    }
    untrack(&staging);
    result
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
