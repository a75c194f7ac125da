//! Progress bars for the long loops (frame parsing, detection,
//! classification). Off by default, so library users and tests see nothing;
//! the command-line tool turns them on when stderr is a terminal and
//! `--quiet` is not given.

use std::sync::atomic::{AtomicBool, Ordering};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

static ENABLED: AtomicBool = AtomicBool::new(false);

/// Turn progress bars on or off (process-wide).
pub fn set_enabled(on: bool) {
    ENABLED.store(on, Ordering::Relaxed);
}

/// Whether progress bars are drawn.
pub fn enabled() -> bool {
    ENABLED.load(Ordering::Relaxed)
}

/// A progress bar over `len` frames labelled `stage`, drawn on stderr when
/// enabled and hidden otherwise. Finish it with `finish_and_clear`.
pub fn bar(len: usize, stage: &'static str) -> ProgressBar {
    if !enabled() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::with_draw_target(Some(len as u64), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{msg:>10} {bar:40} {pos}/{len} frames, {per_sec}, eta {eta}")
    {
        bar.set_style(style);
    }
    bar.set_message(stage);
    bar
}
