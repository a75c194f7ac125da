//! Parse each 3DRef demo frame once from memory, for instruction counting.
//!
//! `cargo run --release --example parse_once [-- DIR]` (or `SPECULAR_DATA=DIR`)
//! reads every frame of DIR into memory first, then calls `parse_frame` once
//! per frame and prints the point count. Meant to be run under
//! `valgrind --tool=callgrind`, where the parse cost is deterministic:
//!
//! ```text
//! valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.out \
//!     target/release/examples/parse_once
//! callgrind_annotate --inclusive=yes /tmp/cg.out | grep parse_frame
//! ```

use std::path::PathBuf;

use specular::io::{list_frames, parse_frame};

fn main() {
    let dir = std::env::args()
        .nth(1)
        .or_else(|| std::env::var("SPECULAR_DATA").ok())
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/work/shared/data/3dref-seq1-demo"));
    let frames = list_frames(&dir).unwrap_or_else(|e| {
        eprintln!("parse_once: {e}");
        std::process::exit(1);
    });
    let files: Vec<Vec<u8>> = frames
        .iter()
        .map(|f| std::fs::read(&f.path).expect("read frame"))
        .collect();
    let mut total = 0;
    for (bytes, entry) in files.iter().zip(&frames) {
        let frame = parse_frame(bytes, &entry.path).expect("parse frame");
        total += std::hint::black_box(frame).points.len();
    }
    println!("{} frames, {total} points", frames.len());
}
