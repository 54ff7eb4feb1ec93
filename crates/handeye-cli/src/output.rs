//! Output helpers shared by the commands: transforms as JSON, exit codes.

use std::io::Write;

use handeye::Error;
use serde_json::Value;

/// Exit code 2: bad input.
pub const BAD_INPUT: u8 = 2;
/// Exit code 3: X cannot be determined from valid input.
pub const DEGENERATE: u8 = 3;

/// The exit code for an error: 2 for bad input, 3 for degenerate data, 1 otherwise.
pub fn exit_code(e: &anyhow::Error) -> u8 {
    match e.downcast_ref::<Error>() {
        Some(
            Error::Degenerate { .. }
            | Error::TooFewMotions { .. }
            | Error::Misread { .. }
            | Error::Untrusted { .. },
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

/// Prints text to stdout and flushes it. A closed pipe comes back as an error, on which `main`
/// exits 0 quietly (see [`is_closed_pipe`]).
pub fn print_text(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
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

/// Prints one JSON document (pretty) to stdout.
pub fn print_json(v: &Value) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    serde_json::to_writer_pretty(&mut out, v)?;
    writeln!(out)?;
    out.flush()?;
    Ok(())
}

/// Prints one JSON line to stdout and flushes it, so that a reader at the other end of a pipe sees
/// it at once.
pub fn print_line(v: &Value) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    serde_json::to_writer(&mut out, v)?;
    writeln!(out)?;
    out.flush()?;
    Ok(())
}
