//! The log of a command-line run: `tracing` messages on stderr. The
//! library only emits them; a command (`specular`, `specular-reproduce`)
//! installs the subscriber once, at start, with [`init`].

use std::io::IsTerminal;

/// Log to stderr: warnings by default, `verbose` 1 (`-v`) info, 2 or more
/// (`-vv`) debug; a `RUST_LOG` filter takes precedence. Colours only on a
/// terminal. A second call (or another subscriber already installed) is
/// ignored.
pub fn init(verbose: u8) {
    let level = match verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(level));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .try_init();
}
