//! Where results go, and how a command ends (docs/conventions.md): `-` is standard output for
//! every file option, results go to standard output and messages to standard error, and the exit
//! code says what happened: 0 ran (favourable verdict), 1 ran (unfavourable verdict), 2 bad input,
//! 3 runtime failure (the solver gave up, an output could not be written), 130 interrupted (Ctrl-C),
//! 141 the reader of standard output went away (`| head`), quietly, as a tool killed by SIGPIPE.
//!
//! Writing never panics: a full disk or `> /dev/full` is exit 3 with the output named. Where a file
//! output may go, and how it replaces an old file, is [`crate::writer`]'s.

use std::fmt;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// Ran, verdict favourable.
pub const EXIT_OK: u8 = 0;
/// Ran, verdict unfavourable ("does not fit", "collided", ...).
pub const EXIT_VERDICT: u8 = 1;
/// Bad input: usage, an unreadable or invalid scene, a refused option.
pub const EXIT_BAD_INPUT: u8 = 2;
/// Runtime failure: the solver gave up, an output could not be written.
pub const EXIT_RUNTIME: u8 = 3;
/// `avoid` only: ran, stopped safely before the goal (never inside the operator, the SSM bound
/// kept): not the goal, but not unsafe either.
pub const EXIT_SAFE_STOP: u8 = 4;
/// `avoid` only: ran on recorded frames, and the verdict is not verified (judged against the scene
/// file's model operator, not the recording).
pub const EXIT_UNVERIFIED: u8 = 5;
/// Interrupted by Ctrl-C (the shell's 128 + SIGINT); what was written so far is complete rows.
pub const EXIT_INTERRUPTED: u8 = 130;

/// The reader of standard output went away (128 + SIGPIPE), reported without a message.
pub const EXIT_PIPE: u8 = 141;

/// Why a command stopped: an exit code and the message for standard error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Failure {
    /// One of the `EXIT_*` codes.
    pub code: u8,
    /// The message (without "error: ").
    pub message: String,
}

impl Failure {
    /// Exit 2.
    pub fn bad_input(message: impl Into<String>) -> Self {
        Self { code: EXIT_BAD_INPUT, message: message.into() }
    }
    /// Exit 3.
    pub fn runtime(message: impl Into<String>) -> Self {
        Self { code: EXIT_RUNTIME, message: message.into() }
    }
    /// Exit 130.
    pub fn interrupted(message: impl Into<String>) -> Self {
        Self { code: EXIT_INTERRUPTED, message: message.into() }
    }
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// True for the file name `-` (standard output).
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// What a file option names, for messages: the path, or "standard output".
pub fn shown(path: &Path) -> String {
    if is_stdout(path) { "standard output".into() } else { path.display().to_string() }
}

/// Opens an output (`-`: standard output), buffered: one `write` per 64 KiB, not per field.
/// A regular file is written to a temporary file beside it and renamed over it when the command
/// ends ([`settle`]); see [`crate::writer`] for what is refused.
pub fn create(path: &Path) -> Result<Box<dyn Write>, Failure> {
    let f = create_file(path)?;
    match f {
        None => Ok(Box::new(BufWriter::with_capacity(1 << 16, Stdout))),
        Some(f) => Ok(Box::new(BufWriter::with_capacity(1 << 16, f))),
    }
}

/// [`create`] unbuffered: the opened file (`None` for standard output), for writers that buffer
/// themselves or need `Send` (Parquet).
pub fn create_file(path: &Path) -> Result<Option<crate::writer::OutFile>, Failure> {
    crate::writer::open(path).map_err(|e| match e {
        crate::writer::OpenError::Refused(m) => Failure::bad_input(m),
        crate::writer::OpenError::Failed(m) => Failure::runtime(m),
    })
}

/// Refuses, before anything runs, an output the careful writer would refuse (an input of this
/// command, a directory, a device, a new file under /dev, /proc or /sys): exit 2 naming `option`.
/// Call it after the command's inputs are read.
pub fn check_target(option: &str, path: &Path) -> Result<(), Failure> {
    crate::writer::plan(path).map(|_| ()).map_err(|e| Failure::bad_input(format!("{option} {e}")))
}

/// Ends every output this process opened with [`create`]: `keep` renames each temporary file over
/// its target (a command that ran, or was interrupted with its complete prefix), otherwise removes
/// them so the old files stay as they were (a refusal, a runtime failure). Main calls it once at the
/// end; the paths that end the process early call it before `exit`.
pub fn settle(keep: bool) {
    crate::writer::settle(keep);
}

/// For the binary: every output's temporary file waits for [`settle`] (a library caller's is
/// renamed into place when its writer is dropped).
pub fn defer_to_settle() {
    crate::writer::defer_to_settle();
}

/// Whether outputs are kept for a command ending with `code`: everything but bad input (2) and a
/// runtime failure (3).
pub fn keeps(code: u8) -> bool {
    code != EXIT_BAD_INPUT && code != EXIT_RUNTIME
}

/// Maps a write error on `path` to the command's ending: a closed reader is exit 141 without a
/// message, anything else exit 3 naming the output.
pub fn write_error(path: &Path, e: &io::Error) -> Failure {
    if e.kind() == io::ErrorKind::BrokenPipe {
        Failure { code: EXIT_PIPE, message: String::new() }
    } else {
        Failure::runtime(format!("{}: could not write: {e}", shown(path)))
    }
}

/// For a command whose errors are text (`Result<_, String>`): a closed reader ends the process
/// here as the print guard does (outputs kept, quiet exit 141), since a message string cannot carry
/// the exit code; any other failure becomes its message (exit 3 in `main`).
pub fn message_or_end_on_closed_pipe(f: Failure) -> String {
    if f.code == EXIT_PIPE {
        settle(true);
        std::process::exit(i32::from(EXIT_PIPE));
    }
    f.message
}

/// Standard output, unlocked per write so it can sit behind a `Box<dyn Write>`.
struct Stdout;

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        io::stdout().lock().write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        io::stdout().lock().flush()
    }
}

/// Writes `text` to standard output and flushes; characters a terminal would obey (controls, bidi
/// overrides) are shown escaped ([`crate::terminal::escape`]).
pub fn print(text: &str) -> Result<(), Failure> {
    let text = crate::terminal::escape(text);
    let mut out = io::stdout().lock();
    out.write_all(text.as_bytes()).and_then(|_| out.flush()).map_err(|e| write_error(Path::new("-"), &e))
}

/// A message line to standard error ("wrote ...", notes, progress); never fails.
pub fn note(text: &str) {
    let _ = writeln!(io::stderr().lock(), "{}", crate::terminal::escape(text));
}

/// Installs a panic hook that turns a failed `println!` anywhere in the program (a subcommand that
/// prints with the standard macros) into the documented ending instead of a panic: exit 3 with the
/// reason, or a quiet exit 141 when the reader went away. Any other panic keeps the default report.
pub fn install_print_guard() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info.payload().downcast_ref::<String>().map(String::as_str).or_else(|| info.payload().downcast_ref::<&str>().copied()).unwrap_or("");
        if let Some(rest) = msg.strip_prefix("failed printing to stdout: ") {
            if rest.contains("Broken pipe") || rest.contains("os error 32") {
                settle(true);
                std::process::exit(i32::from(EXIT_PIPE));
            }
            note(&format!("error: standard output: could not write: {rest}"));
            settle(false);
            std::process::exit(i32::from(EXIT_RUNTIME));
        }
        default(info);
    }));
}
