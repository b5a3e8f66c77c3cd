//! A closed stdout ends a command quietly with exit code 0, as `ripgrep`
//! and the Unix tools do: `plinth identify --json | head -1` has printed
//! what its reader wanted, and is not an error.
//!
//! Rust ignores SIGPIPE, so a write to a closed pipe returns `BrokenPipe`:
//! `println!` then panics with "failed printing to stdout", and an explicit
//! `writeln!` returns the error. [`exit_quietly_on_closed_stdout`] installs
//! a panic hook that turns the first into exit 0 with nothing printed (every
//! other panic keeps the default report), and [`is_closed_stdout`] lets
//! `main` recognise the second in an error chain.

/// Installs the panic hook: a panic from printing to a closed stdout exits
/// the process with code 0 and prints nothing; any other panic is reported
/// as usual.
pub fn exit_quietly_on_closed_stdout() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if is_closed_stdout_message(payload) {
            std::process::exit(0);
        }
        default(info);
    }));
}

/// True for the message of `println!`'s panic on a closed pipe.
fn is_closed_stdout_message(message: &str) -> bool {
    // The operating system's text of EPIPE ("Broken pipe (os error 32)"
    // on Unix, "The pipe is being closed. (os error 232)" on Windows).
    message.starts_with("failed printing to stdout")
        && (message.contains("Broken pipe") || message.contains("pipe is being closed"))
}

/// True when the error (or one of its causes) is a write to a closed pipe.
pub fn is_closed_stdout(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recognises_a_closed_pipe_and_nothing_else() {
        assert!(is_closed_stdout_message(
            "failed printing to stdout: Broken pipe (os error 32)"
        ));
        assert!(!is_closed_stdout_message("index out of bounds"));
        assert!(!is_closed_stdout_message(
            "failed printing to stdout: No space left on device (os error 28)"
        ));
        let e = anyhow::Error::from(std::io::Error::from(std::io::ErrorKind::BrokenPipe))
            .context("writing the table");
        assert!(is_closed_stdout(&e));
        assert!(!is_closed_stdout(&anyhow::anyhow!("other")));
    }
}
