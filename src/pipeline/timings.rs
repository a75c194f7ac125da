//! Per-stage timing, reported by `--timings` and the benchmarks.

use std::time::Duration;

/// Time spent in each stage, summed over frames (CPU time of the workers,
/// not wall time), plus the wall time of the whole run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimings {
    /// Stage names in pipeline order with their summed time.
    pub stages: Vec<(&'static str, Duration)>,
    /// Frames processed.
    pub frames: usize,
    /// Wall time of the run.
    pub wall: Duration,
}

impl StageTimings {
    /// Add `d` to stage `name` (appended on first use).
    pub fn add(&mut self, name: &'static str, d: Duration) {
        match self.stages.iter_mut().find(|(n, _)| *n == name) {
            Some((_, t)) => *t += d,
            None => self.stages.push((name, d)),
        }
    }

    /// Add the time spent reading frames from their files (stage
    /// "parse"), when there was any: frames held in memory take none.
    pub fn add_reading(&mut self, d: Duration) {
        if !d.is_zero() {
            self.add("parse", d);
        }
    }

    /// Merge another set of timings (stages added, frames summed, wall kept).
    pub fn merge(&mut self, other: &StageTimings) {
        for (n, d) in &other.stages {
            self.add(n, *d);
        }
        self.frames += other.frames;
    }

    /// Add `other`'s time per stage, not its frames (a second pass over
    /// the same frames).
    pub fn merge_stages(&mut self, other: &StageTimings) {
        for (n, d) in &other.stages {
            self.add(n, *d);
        }
    }

    /// A table of milliseconds per frame for each stage.
    pub fn table(&self) -> String {
        let per = |d: Duration| d.as_secs_f64() * 1e3 / self.frames.max(1) as f64;
        let mut s = format!("stage                 ms/frame  ({} frames)\n", self.frames);
        let mut total = Duration::ZERO;
        for (n, d) in &self.stages {
            s.push_str(&format!("{:<20} {:>9.3}\n", n, per(*d)));
            total += *d;
        }
        s.push_str(&format!("{:<20} {:>9.3}\n", "sum of stages", per(total)));
        s.push_str(&format!(
            "{:<20} {:>9.3}  (wall {:.1} ms, {} threads)\n",
            "wall per frame",
            per(self.wall),
            self.wall.as_secs_f64() * 1e3,
            rayon::current_num_threads()
        ));
        s
    }
}
