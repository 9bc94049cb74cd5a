//! The one reader of every file Flinch takes in (docs/conventions.md "Inputs"): a scene, a URDF,
//! depth frames and their index, robot poses, a calibration, a measured CSV, `sample --merge`
//! reports. Only regular files are read: a directory, a FIFO, a socket or a device is refused by
//! name before it is opened (opening a device can itself do something; reading a FIFO nobody
//! writes blocks forever). The file is then opened without blocking and checked again through the
//! opened handle (a path swapped for a FIFO in between cannot block). Each kind has a size cap; no
//! input makes Flinch read more than its cap, whatever the file says its size is.
//!
//! Every file read is remembered (device and inode) so that the writer ([`super::output`]) never
//! replaces an input of the same command, whatever name the output is given.
use std::fmt;
use std::fs::{File, Metadata};
use std::io::Read;
use std::path::Path;
use std::sync::Mutex;

/// What a file is, for its cap and its messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A scene (TOML), also from standard input.
    Scene,
    /// A robot's URDF.
    Urdf,
    /// A recorded depth frame (16-bit PNG or PGM).
    DepthFrame,
    /// A recording's `index.csv` (`t_s,file`).
    FrameIndex,
    /// Robot poses (`t_s,x_m,y_m`).
    Poses,
    /// A robot calibration (`.flcal`).
    Calibration,
    /// Measured traces (`run --measured`).
    Measured,
    /// A `flinch sample --json` report (`--merge`).
    MergeReport,
}

const MIB: u64 = 1 << 20;

impl Kind {
    /// The largest file of this kind read, bytes (docs/conventions.md states each with its reason).
    pub const fn cap(self) -> u64 {
        match self {
            Kind::Scene => MIB,
            Kind::Urdf | Kind::MergeReport => 16 * MIB,
            Kind::DepthFrame | Kind::FrameIndex | Kind::Poses | Kind::Calibration => 64 * MIB,
            Kind::Measured => 256 * MIB,
        }
    }

    /// As messages name it.
    pub const fn what(self) -> &'static str {
        match self {
            Kind::Scene => "a scene file",
            Kind::Urdf => "a URDF",
            Kind::DepthFrame => "a depth frame",
            Kind::FrameIndex => "a frame index (index.csv)",
            Kind::Poses => "a robot-poses file",
            Kind::Calibration => "a calibration file",
            Kind::Measured => "a measured CSV",
            Kind::MergeReport => "a sample report",
        }
    }

    /// Every kind, for the docs' table and its test.
    pub const ALL: [Kind; 8] = [Kind::Scene, Kind::Urdf, Kind::DepthFrame, Kind::FrameIndex, Kind::Poses, Kind::Calibration, Kind::Measured, Kind::MergeReport];
}

/// An input that cannot be read: `file[:line]: message`, exit 2.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputError {
    /// The file as the user named it.
    pub file: String,
    /// 1-based line, when the problem is on one.
    pub line: Option<usize>,
    /// What is wrong and what is allowed.
    pub message: String,
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}:{l}: {}", self.file, self.message),
            None => write!(f, "{}: {}", self.file, self.message),
        }
    }
}

impl std::error::Error for InputError {}

fn fail<T>(path: &Path, message: impl Into<String>) -> Result<T, InputError> {
    Err(InputError { file: path.display().to_string(), line: None, message: message.into() })
}

/// What a non-regular file is, for the refusal.
fn not_regular(m: &Metadata) -> Option<&'static str> {
    let t = m.file_type();
    if t.is_file() {
        return None;
    }
    if t.is_dir() {
        return Some("is a directory");
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return Some("is not a regular file (a FIFO)");
        }
        if t.is_socket() {
            return Some("is not a regular file (a socket)");
        }
        if t.is_char_device() {
            return Some("is not a regular file (a character device)");
        }
        if t.is_block_device() {
            return Some("is not a regular file (a block device)");
        }
    }
    Some("is not a regular file")
}

/// (device, inode) of a file, to recognise it under any name.
#[cfg(unix)]
pub fn identity(m: &Metadata) -> (u64, u64) {
    use std::os::unix::fs::MetadataExt;
    (m.dev(), m.ino())
}
#[cfg(not(unix))]
pub fn identity(_: &Metadata) -> (u64, u64) {
    (0, 0)
}

/// The inputs this process has read: (device, inode) and the name given.
static INPUTS: Mutex<Vec<((u64, u64), String)>> = Mutex::new(Vec::new());

/// Remembers an input (also one not opened through [`open`], e.g. a frame listed in an index).
pub fn remember(path: &Path, m: &Metadata) {
    if let Ok(mut v) = INPUTS.lock() {
        let id = identity(m);
        if !v.iter().any(|(i, _)| *i == id) {
            v.push((id, path.display().to_string()));
        }
    }
}

/// The input of this process that `m` is, if any (its name as given).
pub fn input_named(m: &Metadata) -> Option<String> {
    let id = identity(m);
    INPUTS.lock().ok()?.iter().find(|(i, _)| *i == id).map(|(_, n)| n.clone())
}

/// Checks `path` without opening it: a regular file within the kind's cap. Returns its metadata.
pub fn check(path: &Path, kind: Kind) -> Result<Metadata, InputError> {
    let m = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return fail(path, format!("no such file ({} was expected)", kind.what())),
        Err(e) => return fail(path, format!("cannot be read: {e}")),
    };
    if let Some(why) = not_regular(&m) {
        return fail(path, format!("{why}; {} must be a regular file", kind.what()));
    }
    if m.len() > kind.cap() {
        return fail(path, format!("{} bytes; {} is at most {} (docs/conventions.md)", m.len(), kind.what(), human(kind.cap())));
    }
    Ok(m)
}

fn human(b: u64) -> String {
    if b % MIB == 0 { format!("{} MiB", b / MIB) } else { format!("{b} bytes") }
}

/// Opens a regular file of `kind` for reading: refused by name if it is not one (checked on the
/// path before opening and on the handle after, the open never blocking), or over the cap.
pub fn open(path: &Path, kind: Kind) -> Result<(File, Metadata), InputError> {
    let before = check(path, kind)?;
    let mut o = std::fs::OpenOptions::new();
    o.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        o.custom_flags(libc::O_NONBLOCK | libc::O_CLOEXEC);
    }
    let f = o.open(path).or_else(|e| fail(path, format!("cannot be read: {e}")))?;
    let m = f.metadata().or_else(|e| fail(path, format!("cannot be read: {e}")))?;
    if let Some(why) = not_regular(&m) {
        return fail(path, format!("{why}; {} must be a regular file", kind.what()));
    }
    if identity(&m) != identity(&before) {
        return fail(path, "changed while it was being opened; give a file that stays put");
    }
    remember(path, &m);
    Ok((f, m))
}

/// Reads a whole regular file of `kind`, at most its cap.
pub fn read_bytes(path: &Path, kind: Kind) -> Result<Vec<u8>, InputError> {
    let (f, m) = open(path, kind)?;
    let mut out = Vec::with_capacity(m.len().min(kind.cap()) as usize);
    f.take(kind.cap() + 1).read_to_end(&mut out).or_else(|e| fail(path, format!("cannot be read: {e}")))?;
    if out.len() as u64 > kind.cap() {
        return fail(path, format!("more than {}; {} is at most that (docs/conventions.md)", human(kind.cap()), kind.what()));
    }
    Ok(out)
}

/// UTF-8 text of bytes read from `shown`; a bad byte is refused with its line and offset.
pub fn utf8(bytes: Vec<u8>, shown: &str, kind: Kind) -> Result<String, InputError> {
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        InputError { file: shown.to_string(), line: Some(line), message: format!("not UTF-8 text (invalid byte at offset {at}); {} is UTF-8 text", kind.what()) }
    })
}

/// Reads a whole regular text file of `kind`.
pub fn read_text(path: &Path, kind: Kind) -> Result<String, InputError> {
    let b = read_bytes(path, kind)?;
    utf8(b, &path.display().to_string(), kind)
}

/// Reads standard input as text of `kind`, at most its cap.
pub fn read_stdin(kind: Kind) -> Result<String, InputError> {
    let mut out = Vec::new();
    std::io::stdin().lock().take(kind.cap() + 1).read_to_end(&mut out).map_err(|e| InputError { file: "<stdin>".into(), line: None, message: e.to_string() })?;
    if out.len() as u64 > kind.cap() {
        return Err(InputError { file: "<stdin>".into(), line: None, message: format!("more than {}; {} is at most that (docs/conventions.md)", human(kind.cap()), kind.what()) });
    }
    utf8(out, "<stdin>", kind)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("flinch-input-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[cfg(unix)]
    #[test]
    fn fifos_devices_and_directories_are_refused_by_name_without_blocking() {
        let d = dir("special");
        let fifo = d.join("f.urdf");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        for kind in Kind::ALL {
            let e = read_bytes(&fifo, kind).unwrap_err().to_string();
            assert!(e.starts_with(&fifo.display().to_string()) && e.contains("is not a regular file (a FIFO)"), "{e}");
            assert!(e.contains(kind.what()), "{e}");
        }
        assert!(read_text(Path::new("/dev/zero"), Kind::Urdf).unwrap_err().to_string().contains("(a character device)"));
        assert!(read_text(&d, Kind::Scene).unwrap_err().to_string().contains("is a directory"));
        assert!(read_text(&d.join("none"), Kind::Scene).unwrap_err().to_string().contains("no such file"));
    }

    #[test]
    fn a_file_over_its_cap_is_refused_before_reading() {
        let d = dir("cap");
        let big = d.join("big.csv");
        std::fs::File::create(&big).unwrap().set_len(Kind::Measured.cap() + 1).unwrap();
        let e = read_bytes(&big, Kind::Measured).unwrap_err().to_string();
        assert!(e.contains("268435457 bytes; a measured CSV is at most 256 MiB"), "{e}");
        // A file of exactly the cap reads whole.
        let ok = d.join("ok.toml");
        std::fs::write(&ok, vec![b'#'; Kind::Scene.cap() as usize]).unwrap();
        assert_eq!(read_bytes(&ok, Kind::Scene).unwrap().len() as u64, Kind::Scene.cap());
        let e = read_text(Path::new("/nonexistent"), Kind::Scene).unwrap_err();
        assert_eq!(e.line, None);
        // Not UTF-8: the line of the bad byte.
        let bad = d.join("bad.toml");
        std::fs::write(&bad, b"a = 1\nb = \"\xff\"\n").unwrap();
        let e = read_text(&bad, Kind::Scene).unwrap_err();
        assert_eq!(e.line, Some(2));
        // Remembered: the writer recognises it under another name.
        let m = std::fs::metadata(&ok).unwrap();
        assert!(input_named(&m).is_some());
    }
}
