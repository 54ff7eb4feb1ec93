//! Output helpers shared by the commands: transforms as JSON, exit codes.

use std::io::Write;

use handeye::Error;

/// Exit code 2: bad input.
pub const BAD_INPUT: u8 = 2;
/// Exit code 3: X cannot be determined from valid input.
pub const DEGENERATE: u8 = 3;

/// Exit code 4 (`verify`): the saved X does not fit the recording.
pub const INCONSISTENT: u8 = 4;

/// The end of a run with a verdict that has its own exit code (`verify`: 3 or 4), after printing
/// the result.
#[derive(Debug)]
pub struct Verdict {
    /// The exit code.
    pub code: u8,
    /// What it means.
    pub message: String,
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for Verdict {}

/// Exit code 5: X was found, but its verdict is questionable and `--strict` was given.
pub const QUESTIONABLE: u8 = 5;

/// The end of a `--strict` run whose verdict is questionable (exit 5).
#[derive(Debug)]
pub struct Questionable;

impl std::fmt::Display for Questionable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(
            "the verdict is questionable (--strict): act on the cautions, then calibrate again",
        )
    }
}

impl std::error::Error for Questionable {}

/// A refusal the text face has printed on stdout: its exit code, and one short line for stderr
/// (the reason is said once).
pub fn said(e: &anyhow::Error) -> anyhow::Error {
    Verdict {
        code: exit_code(e),
        message: "refused: the reason is printed above".into(),
    }
    .into()
}

/// The exit code for an error: 2 for bad input, 3 for degenerate data, 5 for a questionable
/// verdict under `--strict`, 1 otherwise.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    if e.downcast_ref::<Questionable>().is_some() {
        return QUESTIONABLE;
    }
    if let Some(v) = e.downcast_ref::<Verdict>() {
        return v.code;
    }
    match e.downcast_ref::<Error>() {
        Some(
            Error::Degenerate { .. }
            | Error::TooFewMotions { .. }
            | Error::Misread { .. }
            | Error::Untrusted { .. }
            | Error::NoEstimate { .. }
            | Error::OffsetNotFound { .. }
            | Error::PixelsUnfit { .. },
        ) => DEGENERATE,
        Some(_) => BAD_INPUT,
        None => 1,
    }
}

/// The message of an error and of its causes, each cause left out when the text before already
/// says it (the library's errors print their source themselves).
pub fn error_message(e: &anyhow::Error) -> String {
    let mut message = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !message.contains(&text) {
            message.push_str(": ");
            message.push_str(&text);
        }
    }
    message
}

/// `name` with every control character escaped (`\u{1b}`, `\n`, …): a frame or topic name from
/// a recording may hold terminal escape sequences, which must not reach the terminal.
pub fn escaped(name: &str) -> std::borrow::Cow<'_, str> {
    escaped_but(name, &[])
}

/// Text for the terminal with its control characters escaped, its line ends and tabs kept.
pub fn escaped_text(text: &str) -> std::borrow::Cow<'_, str> {
    escaped_but(text, &['\n', '\t'])
}

/// `text` with every control character (C0, DEL, C1) but those of `keep` escaped.
fn escaped_but<'a>(text: &'a str, keep: &[char]) -> std::borrow::Cow<'a, str> {
    let bad = |c: char| c.is_control() && !keep.contains(&c);
    if !text.chars().any(bad) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if bad(c) {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

/// Prints a message on stderr, its control characters escaped (see [`escaped_text`]).
pub fn tell(text: &str) {
    eprintln!("{}", escaped_text(text));
}

/// `eprintln!` through [`tell`]: no control character of a name reaches the terminal.
#[macro_export]
macro_rules! tell {
    ($($arg:tt)*) => {
        $crate::output::tell(&format!($($arg)*))
    };
}

/// Prints text to stdout, its control characters escaped (see [`escaped_text`]), and flushes
/// it. A closed pipe comes back as an error, on which `main` exits 0 quietly (see
/// [`is_closed_pipe`]).
pub fn print_text(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(escaped_text(text).as_bytes())?;
    out.flush()?;
    Ok(())
}

/// `println!` that returns the write's error instead of panicking on a closed pipe.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::output::print_text(&format!("{}\n", format_args!($($arg)*)))
    };
}

/// Whether an error is a write to a closed pipe (`handeye … | head`): the reader has what it
/// wanted, so that is a success, said nothing about.
pub fn is_closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
            || cause
                .downcast_ref::<serde_json::Error>()
                .and_then(|j| j.io_error_kind())
                .is_some_and(|k| k == std::io::ErrorKind::BrokenPipe)
    })
}

/// Makes a panic of `print!`/`eprint!` on a closed pipe (a message or progress to a closed
/// stderr) a quiet exit 0; every other panic keeps the default report.
pub fn quiet_on_closed_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if payload.starts_with("failed printing to std") && payload.contains("Broken pipe") {
            std::process::exit(0);
        }
        default(info);
    }));
}

/// Prints one JSON document (pretty) to stdout in one write: stdout is line-buffered, and a
/// report with per-motion rows written straight to it cost a system call per line (7,517 calls,
/// about 6 ms, for all pairs of 50 poses). The library's result types are serialised directly,
/// with no `serde_json::Value` in between (a tree of small allocations as large as the report).
pub fn print_json(v: &(impl serde::Serialize + ?Sized)) -> anyhow::Result<()> {
    let mut text = json_safe(serde_json::to_vec_pretty(v)?);
    text.push(b'\n');
    let mut out = std::io::stdout().lock();
    out.write_all(&text)?;
    out.flush()?;
    Ok(())
}

/// JSON text with the control characters JSON leaves raw (DEL and the C1 controls, U+007F to
/// U+009F) written as `\u` escapes, which read back as the same string: with the C0 controls that
/// `serde_json` escapes, no control character of a name reaches the terminal.
fn json_safe(json: Vec<u8>) -> Vec<u8> {
    let raw = |c: char| ('\u{7f}'..='\u{9f}').contains(&c);
    match std::str::from_utf8(&json) {
        Ok(text) if text.chars().any(raw) => {
            let mut out = String::with_capacity(text.len() + 16);
            for c in text.chars() {
                if raw(c) {
                    out.push_str(&format!("\\u{:04x}", c as u32));
                } else {
                    out.push(c);
                }
            }
            out.into_bytes()
        }
        _ => json,
    }
}

/// Bytes kept before [`LineOut`] writes them out even when no input is awaited.
const LINE_OUT_BUFFER: usize = 64 * 1024;

/// Standard output for a stream of lines (`online`): the lines are kept in a buffer and written
/// in one go when the buffer fills, when the run is about to wait for input
/// ([`LineOut::flush_quietly`], called by the input reader before each read), and at the end; on a
/// terminal, after each line. A reader at the other end of a pipe thus sees every line before
/// `handeye` waits for the next pose, without one write per line on a fast input.
///
/// Clones share the buffer. A failed write (a closed pipe) is kept and returned by the next
/// [`LineOut::json`], [`LineOut::text`] or [`LineOut::flush`].
#[derive(Clone)]
pub struct LineOut(std::rc::Rc<std::cell::RefCell<LineBuffer>>);

struct LineBuffer {
    bytes: Vec<u8>,
    terminal: bool,
    failed: Option<std::io::Error>,
}

impl LineOut {
    /// The buffered standard output.
    pub fn stdout() -> Self {
        Self(std::rc::Rc::new(std::cell::RefCell::new(LineBuffer {
            bytes: Vec::with_capacity(LINE_OUT_BUFFER),
            terminal: std::io::IsTerminal::is_terminal(&std::io::stdout()),
            failed: None,
        })))
    }

    /// One JSON line: the value, compact, and a line end.
    pub fn json(&self, v: &impl serde::Serialize) -> anyhow::Result<()> {
        let mut buffer = self.0.borrow_mut();
        let line = json_safe(serde_json::to_vec(v)?);
        buffer.bytes.extend_from_slice(&line);
        buffer.bytes.push(b'\n');
        Ok(buffer.written()?)
    }

    /// Text (whole lines, each ending in `\n`), its control characters escaped.
    pub fn text(&self, text: &str) -> anyhow::Result<()> {
        let mut buffer = self.0.borrow_mut();
        buffer
            .bytes
            .extend_from_slice(escaped_text(text).as_bytes());
        Ok(buffer.written()?)
    }

    /// Writes out what is buffered; the error of this write or of an earlier one.
    pub fn flush(&self) -> std::io::Result<()> {
        let mut buffer = self.0.borrow_mut();
        buffer.flush();
        buffer.failed.take().map_or(Ok(()), Err)
    }

    /// Writes out what is buffered, keeping an error for the next write (for the input reader,
    /// which cannot report an error of the output).
    pub fn flush_quietly(&self) {
        if let Ok(mut buffer) = self.0.try_borrow_mut() {
            buffer.flush();
        }
    }
}

impl LineBuffer {
    /// After a line was added: writes the buffer out on a terminal or when it is full; the error
    /// of this write or of an earlier one.
    fn written(&mut self) -> std::io::Result<()> {
        if self.terminal || self.bytes.len() >= LINE_OUT_BUFFER {
            self.flush();
        }
        self.failed.take().map_or(Ok(()), Err)
    }

    fn flush(&mut self) {
        if self.bytes.is_empty() || self.failed.is_some() {
            return;
        }
        let mut out = std::io::stdout().lock();
        if let Err(e) = out.write_all(&self.bytes).and_then(|()| out.flush()) {
            self.failed = Some(e);
        }
        self.bytes.clear();
    }
}
