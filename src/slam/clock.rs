//! The frames' timing: the interval since the previous frame, the input's
//! usual frame period, and gaps.
//!
//! The motion model extrapolates over the elapsed time, so it needs the
//! interval; and a frame that comes much later than the input's rhythm
//! (dropped frames, a paused recording) is the tracker's hardest case — the
//! prediction is the least certain there — so it is reported, never
//! silent. The usual period is the median of the recent intervals, so a
//! 5 Hz input is not a sequence of gaps, and a gap does not become the
//! norm after one occurrence.

use std::collections::VecDeque;

/// Intervals the usual period is the median of.
const RECENT: usize = 31;

/// The timing of one frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FrameTiming {
    /// Seconds since the previous frame (`None` for the first frame or
    /// when either has no timestamp; a zero or negative difference is
    /// given as is, and the motion model then assumes one frame period).
    pub interval: Option<f64>,
    /// The usual interval before this frame (median of the recent ones),
    /// s.
    pub period: Option<f64>,
    /// The interval exceeds the gap ratio times the usual period: frames
    /// are missing before this one.
    pub gap: bool,
}

/// Tracks the frames' timestamps as they come.
#[derive(Debug, Clone)]
pub struct FrameClock {
    gap_ratio: f64,
    last: Option<f64>,
    recent: VecDeque<f64>,
}

impl FrameClock {
    /// A clock that calls an interval over `gap_ratio` times the usual
    /// period a gap (0 or less: never).
    pub fn new(gap_ratio: f64) -> Self {
        Self {
            gap_ratio,
            last: None,
            recent: VecDeque::with_capacity(RECENT),
        }
    }

    /// The usual interval so far: the median of the recent positive
    /// intervals.
    pub fn period(&self) -> Option<f64> {
        let mut v: Vec<f64> = self.recent.iter().copied().collect();
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    }

    /// The timing of the next frame, stamped `stamp` (seconds; `None`
    /// when unknown).
    pub fn tick(&mut self, stamp: Option<f64>) -> FrameTiming {
        let stamp = stamp.filter(|s| s.is_finite());
        let interval = match (self.last, stamp) {
            (Some(a), Some(b)) => Some(b - a),
            _ => None,
        };
        let period = self.period();
        let gap = match (interval, period) {
            (Some(dt), Some(p)) => self.gap_ratio > 0.0 && dt > self.gap_ratio * p,
            _ => false,
        };
        if let Some(dt) = interval.filter(|dt| *dt > 0.0) {
            // A gap is not the input's rhythm: it stays out of the median.
            if !gap {
                if self.recent.len() == RECENT {
                    self.recent.pop_front();
                }
                self.recent.push_back(dt);
            }
        }
        if stamp.is_some() {
            self.last = stamp;
        }
        FrameTiming {
            interval,
            period,
            gap,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_gap_is_an_interval_far_over_the_usual_period() {
        let mut c = FrameClock::new(1.5);
        let mut t = 100.0;
        assert_eq!(c.tick(Some(t)), FrameTiming::default());
        for _ in 0..10 {
            t += 0.1;
            let f = c.tick(Some(t));
            assert!(!f.gap);
            assert!((f.interval.unwrap() - 0.1).abs() < 1e-9);
        }
        // Five frames missing.
        t += 0.6;
        let f = c.tick(Some(t));
        assert!(f.gap, "{f:?}");
        assert!((f.period.unwrap() - 0.1).abs() < 1e-9);
        // The gap does not change the usual period.
        t += 0.1;
        assert!(!c.tick(Some(t)).gap);
        assert!((c.period().unwrap() - 0.1).abs() < 1e-9);
    }

    #[test]
    fn a_slower_input_is_not_a_gap_and_unknown_stamps_are_no_interval() {
        let mut c = FrameClock::new(1.5);
        let mut t = 0.0;
        c.tick(Some(t));
        for _ in 0..5 {
            t += 0.2;
            assert!(!c.tick(Some(t)).gap);
        }
        assert!((c.period().unwrap() - 0.2).abs() < 1e-9);
        let mut none = FrameClock::new(1.5);
        for _ in 0..3 {
            let f = none.tick(None);
            assert_eq!(f.interval, None);
            assert!(!f.gap);
        }
        // Ratio 0: never a gap.
        let mut off = FrameClock::new(0.0);
        off.tick(Some(0.0));
        off.tick(Some(0.1));
        assert!(!off.tick(Some(5.0)).gap);
    }
}
