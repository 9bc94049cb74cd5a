//! The careful writer (docs/conventions.md "Outputs"): where a file option may write, decided
//! before anything is written, and how an old file is replaced.
//!
//! - `-` is standard output, streamed.
//! - An input of this command (the same device and inode under any name: a symlink, a hard link,
//!   `./x`; [`crate::input`] remembers every file read) is refused, exit 2: `run s.toml --csv
//!   s.toml` must not destroy the scene. So is a second output to the same file (`--csv X
//!   --parquet X`).
//! - An existing directory is refused. An existing FIFO or socket (a process substitution
//!   `>(gzip > f.gz)`), a terminal, and the null, zero and full devices are written in place as a
//!   stream. Every other device (a disk, `/dev/urandom`, a serial port) is refused by name.
//! - A new file is not created under `/dev` (except `/dev/shm`), `/proc` or `/sys`.
//! - A regular file (new or old) is written to `.NAME.flinch-PID-N.EXT` in the same folder and
//!   renamed over the target: in the `flinch` binary at the end of the command for a stream
//!   ([`settle`]; a library caller's when its writer is dropped), as soon as it is complete for a
//!   plot ([`via_temp`]). A command that fails (exit 2 or 3), or a write that fails, removes its
//!   temporary file, so the old file stays as it was, or no file appears. Only SIGKILL or a power cut can
//!   leave a temporary file behind (its name says what it is). No fsync: a CSV is not a database.
use std::fs::{File, Metadata, OpenOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

/// Where an output goes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Plan {
    /// Standard output.
    Stdout,
    /// Written in place as a stream (a FIFO, a socket, a terminal, /dev/null, /dev/zero, /dev/full).
    InPlace(PathBuf),
    /// Written to `temp`, renamed to `target` when complete.
    Staged {
        /// The file to replace or create (a symlink resolved: the file it points to is replaced).
        target: PathBuf,
        /// The temporary file beside it.
        temp: PathBuf,
    },
}

/// Temporary files written and not yet renamed or removed: (temp, target).
static PENDING: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());
static COUNTER: AtomicU64 = AtomicU64::new(0);

fn is_kernel_dir(d: &Path) -> bool {
    (d.starts_with("/dev") && !d.starts_with("/dev/shm")) || d.starts_with("/proc") || d.starts_with("/sys")
}

/// A character device written in place: null (1:3), zero (1:5), full (1:7), or a terminal (the
/// tty majors 4 and 5, the pseudo-terminals 136-143).
#[cfg(unix)]
fn writable_device(m: &Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    let rdev = m.rdev();
    let (major, minor) = (libc::major(rdev), libc::minor(rdev));
    (major == 1 && matches!(minor, 3 | 5 | 7)) || major == 4 || major == 5 || (136..=143).contains(&major)
}
#[cfg(not(unix))]
fn writable_device(_: &Metadata) -> bool {
    false
}

fn temp_beside(target: &Path) -> PathBuf {
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let (stem, ext) = match name.rsplit_once('.') {
        Some((s, e)) if !s.is_empty() => (s.to_string(), format!(".{e}")),
        _ => (name.clone(), String::new()),
    };
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    target.with_file_name(format!(".{stem}.flinch-{}-{n}{ext}", std::process::id()))
}

/// Decides where `path` may be written; `Err` is the reason it may not (bad input, exit 2).
pub fn plan(path: &Path) -> Result<Plan, String> {
    if path.as_os_str() == "-" {
        return Ok(Plan::Stdout);
    }
    let shown = path.display();
    match std::fs::metadata(path) {
        Ok(m) => {
            if let Some(input) = crate::input::input_named(&m) {
                let same = if input == shown.to_string() { String::new() } else { format!(" ({input})") };
                return Err(format!("{shown}: is a file this command reads{same}; give the output another name"));
            }
            let t = m.file_type();
            if t.is_dir() {
                return Err(format!("{shown}: is a directory; give a file name"));
            }
            if t.is_file() {
                let target = std::fs::canonicalize(path).map_err(|e| format!("{shown}: {e}"))?;
                if PENDING.lock().map(|p| p.iter().any(|(_, t)| *t == target)).unwrap_or(false) {
                    return Err(format!("{shown}: another output of this command already writes this file; give each output its own name"));
                }
                return Ok(Plan::Staged { temp: temp_beside(&target), target });
            }
            #[cfg(unix)]
            {
                use std::os::unix::fs::FileTypeExt;
                if t.is_fifo() || t.is_socket() || (t.is_char_device() && writable_device(&m)) {
                    return Ok(Plan::InPlace(path.to_path_buf()));
                }
            }
            Err(format!("{shown}: is a device; Flinch writes a regular file, standard output (-), a pipe, a terminal or /dev/null"))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let name = path.file_name().ok_or_else(|| format!("{shown}: is not a file name"))?;
            let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
            let dir = std::fs::canonicalize(parent).map_err(|e| format!("{shown}: its folder {} cannot be used: {e}", parent.display()))?;
            if is_kernel_dir(&dir) {
                return Err(format!("{shown}: would create a file in {} (a kernel file system); give a file name elsewhere", dir.display()));
            }
            let target = dir.join(name);
            if PENDING.lock().map(|p| p.iter().any(|(_, t)| *t == target)).unwrap_or(false) {
                return Err(format!("{shown}: another output of this command already writes this file; give each output its own name"));
            }
            Ok(Plan::Staged { temp: temp_beside(&target), target })
        }
        Err(e) => Err(format!("{shown}: cannot be used as an output: {e}")),
    }
}

/// Creates the temporary file of a staged plan (never an existing file), with the old target's
/// permissions, and records it for [`settle`].
fn create_temp(temp: &Path, target: &Path) -> std::io::Result<File> {
    let f = OpenOptions::new().write(true).create_new(true).open(temp)?;
    if let Ok(m) = std::fs::metadata(target) {
        let _ = f.set_permissions(m.permissions());
    }
    if let Ok(mut p) = PENDING.lock() {
        p.push((temp.to_path_buf(), target.to_path_buf()));
    }
    Ok(f)
}

/// Set by the `flinch` binary: temporary files wait for [`settle`] (the command's ending decides).
/// Unset (a library caller): each is renamed into place when its writer is dropped after writing
/// without an error, and removed when a write failed.
static DEFERRED: AtomicBool = AtomicBool::new(false);

/// Makes [`settle`] decide what becomes of every temporary file (the binary calls it first).
pub fn defer_to_settle() {
    DEFERRED.store(true, Ordering::SeqCst);
}

/// An output file being written: in place, or a temporary file beside its target.
#[derive(Debug)]
pub struct OutFile {
    f: File,
    /// (temporary, target) when staged.
    staged: Option<(PathBuf, PathBuf)>,
    failed: bool,
}

impl std::io::Write for OutFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.f.write(buf).inspect_err(|_| self.failed = true)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.f.flush().inspect_err(|_| self.failed = true)
    }
}

impl Drop for OutFile {
    fn drop(&mut self) {
        let Some((temp, target)) = &self.staged else { return };
        if DEFERRED.load(Ordering::SeqCst) && !self.failed {
            return;
        }
        if let Ok(mut p) = PENDING.lock() {
            p.retain(|(t, _)| t != temp);
        }
        if self.failed || std::fs::rename(temp, target).is_err() {
            let _ = std::fs::remove_file(temp);
        }
    }
}

/// Opens `path` for writing as [`plan`] says; `None` is standard output.
/// Why an output cannot be opened: refused (bad input, exit 2) or the system said no (exit 3).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OpenError {
    /// [`plan`] refused it.
    Refused(String),
    /// Opening or creating it failed.
    Failed(String),
}

/// Opens `path` for writing as [`plan`] says; `None` is standard output.
pub fn open(path: &Path) -> Result<Option<OutFile>, OpenError> {
    match plan(path).map_err(OpenError::Refused)? {
        Plan::Stdout => Ok(None),
        Plan::InPlace(p) => OpenOptions::new().write(true).open(&p).map(|f| Some(OutFile { f, staged: None, failed: false })).map_err(|e| OpenError::Failed(format!("{}: cannot open it: {e}", p.display()))),
        Plan::Staged { target, temp } => create_temp(&temp, &target).map(|f| Some(OutFile { f, staged: Some((temp, target)), failed: false })).map_err(|e| OpenError::Failed(format!("{}: cannot create it: {e}", path.display()))),
    }
}

/// Renames (`keep`) or removes every pending temporary file. Idempotent.
pub fn settle(keep: bool) {
    let pending = PENDING.lock().map(|mut p| std::mem::take(&mut *p)).unwrap_or_default();
    for (temp, target) in pending {
        if keep {
            if let Err(e) = std::fs::rename(&temp, &target) {
                let msg = format!("error: {}: could not move the finished output into place: {e}", target.display());
                let _ = writeln!(std::io::stderr().lock(), "{}", crate::terminal::escape(&msg));
                let _ = std::fs::remove_file(&temp);
            }
        } else {
            let _ = std::fs::remove_file(&temp);
        }
    }
}

/// Writes a whole file through `write` (given the path to write to): a temporary file beside
/// `path`, renamed over it when `write` succeeds, removed when it fails. For plots and other files
/// drawn by a library that takes a path.
pub fn via_temp(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), String> {
    match plan(path)? {
        Plan::Stdout => Err("standard output (-) cannot take this file; give a file name".into()),
        Plan::InPlace(p) => write(&p),
        Plan::Staged { target, temp } => {
            let r = write(&temp);
            match r {
                Ok(()) if temp.exists() => std::fs::rename(&temp, &target).map_err(|e| {
                    let _ = std::fs::remove_file(&temp);
                    format!("{}: could not move the finished file into place: {e}", path.display())
                }),
                Ok(()) => Ok(()),
                Err(e) => {
                    let _ = std::fs::remove_file(&temp);
                    Err(e)
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("flinch-writer-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn an_input_is_never_an_output_under_any_name() {
        let d = dir("input");
        let scene = d.join("s.toml");
        std::fs::write(&scene, "name = \"x\"\n").unwrap();
        crate::input::read_text(&scene, crate::input::Kind::Scene).unwrap();
        let hard = d.join("hard.toml");
        std::fs::hard_link(&scene, &hard).unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(&scene, d.join("sym.toml")).unwrap();
        for p in [scene.clone(), hard, d.join("sym.toml"), d.join(".").join("s.toml")] {
            let e = plan(&p).unwrap_err();
            assert!(e.contains("is a file this command reads"), "{e}");
            assert!(matches!(open(&p).unwrap_err(), OpenError::Refused(_)));
        }
        assert_eq!(std::fs::read_to_string(&scene).unwrap(), "name = \"x\"\n");
    }

    #[test]
    fn special_files_and_kernel_folders_are_refused_or_streamed() {
        assert!(plan(Path::new("/dev/flinch-writer-test.svg")).unwrap_err().contains("kernel file system"));
        assert!(plan(Path::new("/proc/flinch.csv")).unwrap_err().contains("kernel file system"));
        assert!(plan(Path::new("/dev/urandom")).unwrap_err().contains("is a device"));
        assert!(plan(Path::new("/")).unwrap_err().contains("is a directory"));
        assert_eq!(plan(Path::new("/dev/null")).unwrap(), Plan::InPlace("/dev/null".into()));
        assert_eq!(plan(Path::new("-")).unwrap(), Plan::Stdout);
        assert!(!Path::new("/dev/flinch-writer-test.svg").exists());
    }

    #[test]
    fn the_old_file_stays_until_the_new_one_is_complete_and_a_failure_leaves_it() {
        defer_to_settle();
        let d = dir("staged");
        let out = d.join("out.csv");
        std::fs::write(&out, "old\n").unwrap();
        let mut f = open(&out).unwrap().unwrap();
        f.write_all(b"new\n").unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "old\n", "the target is untouched while writing");
        // A second output to the same file is refused.
        assert!(plan(&out).unwrap_err().contains("another output"));
        settle(false);
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "old\n", "a failed command leaves the old file");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "no temporary file left");
        let mut f = open(&out).unwrap().unwrap();
        f.write_all(b"new\n").unwrap();
        settle(true);
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "new\n");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        // A plot drawn through a temporary file: a failed drawing leaves the old one.
        let r = via_temp(&out, |p| {
            std::fs::write(p, "half").unwrap();
            Err("drawing failed".into())
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "new\n");
        via_temp(&out, |p| std::fs::write(p, "plot").map_err(|e| e.to_string())).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "plot");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    }
}
