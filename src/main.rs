//! The `specular` command-line tool.

mod cli;

#[cfg(feature = "mimalloc")]
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    if let Some(missing) = missing_cpu_feature() {
        eprintln!(
            "error: this build of specular needs an x86-64-v2 CPU, and this one lacks {missing}; \
             rebuild with RUSTFLAGS=\"-C target-cpu=x86-64\" (see .cargo/config.toml)"
        );
        return std::process::ExitCode::FAILURE;
    }
    match cli::run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // Ctrl-C or SIGTERM: the shell's convention, 128 + SIGINT.
        Err(_) if cli::interrupted() => {
            eprintln!(
                "interrupted: the run's outputs are incomplete (see its INCOMPLETE file; \
                 a forced rerun leaves the earlier run as it was)"
            );
            std::process::ExitCode::from(130)
        }
        Err(e) => {
            eprintln!("error: {}", message(&e));
            std::process::ExitCode::FAILURE
        }
    }
}

/// The error and its causes, each said once: a cause whose text the
/// message already holds (a library error that names its OS error) is not
/// repeated.
fn message(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out
}

/// The first CPU feature the build was compiled for that this CPU lacks
/// (see `.cargo/config.toml`), so an old CPU gets a message, not SIGILL.
fn missing_cpu_feature() -> Option<&'static str> {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse4.2"))]
    {
        if !std::is_x86_feature_detected!("sse4.2") {
            return Some("SSE4.2");
        }
        if !std::is_x86_feature_detected!("popcnt") {
            return Some("POPCNT");
        }
    }
    None
}
