//! From echoes to the returns a dual-return sensor reports.
//!
//! 1. **Merge**: echoes closer along the beam than the sensor's range
//!    resolution cannot be separated; they become one echo at the
//!    signal-weighted mean range, with the summed signal and the label and
//!    surface of the strongest contributor.
//! 2. **Detect**: echoes below the detection limit, or outside the sensor's
//!    range limits, are lost.
//! 3. **Select** by return mode: first + last (nearest and farthest),
//!    strongest + last, strongest + second strongest (ordered by
//!    strength), the three strongest (ordered by range), or the strongest
//!    alone. A later return exists only when it is a different echo.

use super::echo::Echo;
use crate::sensor::ReturnMode;

/// Sort echoes by range and merge those closer than `resolution`
/// (single linkage: a chain of close echoes becomes one).
pub fn merge(echoes: &mut Vec<Echo>, resolution: f64) {
    if echoes.len() < 2 {
        return;
    }
    echoes.sort_by(|a, b| {
        a.range
            .total_cmp(&b.range)
            .then(a.surface.cmp(&b.surface))
            .then(b.signal.total_cmp(&a.signal))
    });
    let mut out: Vec<Echo> = Vec::with_capacity(echoes.len());
    // Per merged echo: (weighted range sum, strongest signal) of the cluster.
    let mut weighted = 0.0;
    let mut strongest = 0.0;
    let mut last_range = f64::NEG_INFINITY;
    for e in echoes.iter() {
        match out.last_mut() {
            Some(m) if e.range - last_range <= resolution => {
                weighted += e.range * e.signal;
                m.signal += e.signal;
                if e.signal > strongest {
                    strongest = e.signal;
                    m.label = e.label;
                    m.surface = e.surface;
                    m.via = e.via;
                    m.bounces = e.bounces;
                }
                if m.signal > 0.0 {
                    m.range = weighted / m.signal;
                }
            }
            _ => {
                weighted = e.range * e.signal;
                strongest = e.signal;
                out.push(*e);
            }
        }
        last_range = e.range;
    }
    *echoes = out;
}

/// Keep the echoes a sensor detects: signal at least `min_signal` and range
/// within `min_range..=max_range`.
pub fn detect(echoes: &mut Vec<Echo>, min_signal: f64, min_range: f64, max_range: f64) {
    echoes.retain(|e| e.signal >= min_signal && e.range >= min_range && e.range <= max_range);
}

/// The (return 1, return 2) pair of a beam from its detected echoes sorted
/// by range. Return 2 is `None` when it would be the same echo as return 1.
pub fn select(echoes: &[Echo], mode: ReturnMode) -> (Option<Echo>, Option<Echo>) {
    let Some(first) = echoes.first() else {
        return (None, None);
    };
    let strongest = echoes
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.signal.total_cmp(&b.1.signal).then(b.0.cmp(&a.0)))
        .map(|(i, _)| i)
        .unwrap_or(0);
    let last_index = echoes.len() - 1;
    match mode {
        ReturnMode::FirstLast => (Some(*first), (last_index > 0).then(|| echoes[last_index])),
        ReturnMode::StrongestLast => (
            Some(echoes[strongest]),
            (last_index != strongest).then(|| echoes[last_index]),
        ),
        ReturnMode::Single => (Some(echoes[strongest]), None),
        ReturnMode::StrongestSecond => {
            let second = echoes
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != strongest)
                .max_by(|a, b| a.1.signal.total_cmp(&b.1.signal).then(b.0.cmp(&a.0)))
                .map(|(_, e)| *e);
            (Some(echoes[strongest]), second)
        }
        ReturnMode::Triple => {
            let t = select_triple(echoes);
            (t[0], t[1])
        }
    }
}

/// Up to three returns of a pulse: the three strongest detected echoes
/// (ties to the nearer), in range order, nearest first; `echoes` sorted by
/// range. Allocates nothing.
pub fn select_triple(echoes: &[Echo]) -> [Option<Echo>; 3] {
    // The indices of the three strongest, kept sorted by strength.
    let mut best: [Option<usize>; 3] = [None; 3];
    let stronger = |i: usize, j: usize| echoes[i].signal > echoes[j].signal;
    for i in 0..echoes.len() {
        let mut cand = i;
        for slot in best.iter_mut() {
            match *slot {
                None => {
                    *slot = Some(cand);
                    break;
                }
                Some(j) if stronger(cand, j) => {
                    *slot = Some(cand);
                    cand = j;
                }
                Some(_) => {}
            }
        }
    }
    let mut idx = best;
    idx.sort_by_key(|i| i.unwrap_or(usize::MAX));
    idx.map(|i| i.map(|i| echoes[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn e(range: f64, signal: f64, label: u8) -> Echo {
        Echo {
            range,
            signal,
            label,
            surface: 0,
            via: super::super::echo::NO_SURFACE,
            bounces: 0,
        }
    }

    #[test]
    fn close_echoes_merge_to_the_weighted_range_and_strongest_label() {
        let mut v = vec![e(5.05, 3.0, 6), e(5.0, 1.0, 2), e(9.0, 1.0, 5)];
        merge(&mut v, 0.1);
        assert_eq!(v.len(), 2);
        assert!((v[0].range - (5.0 + 3.0 * 5.05) / 4.0).abs() < 1e-12);
        assert_eq!(v[0].signal, 4.0);
        assert_eq!(v[0].label, 6);
        assert_eq!(v[1].label, 5);
    }

    #[test]
    fn modes_pick_the_right_echoes() {
        let v = [e(2.0, 0.1, 2), e(7.0, 5.0, 5), e(9.0, 1.0, 6)];
        let (a, b) = select(&v, ReturnMode::FirstLast);
        assert_eq!((a.unwrap().label, b.unwrap().label), (2, 6));
        let (a, b) = select(&v, ReturnMode::StrongestLast);
        assert_eq!((a.unwrap().label, b.unwrap().label), (5, 6));
        let (a, b) = select(&v, ReturnMode::Single);
        assert_eq!((a.unwrap().label, b), (5, None));
        // The strongest is the last: a single return.
        let w = [e(2.0, 0.1, 2), e(9.0, 1.0, 6)];
        let (a, b) = select(&w, ReturnMode::StrongestLast);
        assert_eq!((a.unwrap().label, b), (6, None));
        let (a, b) = select(&w[..1], ReturnMode::FirstLast);
        assert_eq!((a.unwrap().label, b), (2, None));
        assert_eq!(select(&[], ReturnMode::FirstLast), (None, None));
    }

    #[test]
    fn ouster_and_livox_modes() {
        // Strength order: the second strongest may be nearer.
        let v = [e(2.0, 0.5, 2), e(7.0, 5.0, 6), e(9.0, 0.1, 5)];
        let (a, b) = select(&v, ReturnMode::StrongestSecond);
        assert_eq!((a.unwrap().label, b.unwrap().label), (6, 2));
        let (a, b) = select(&v[1..2], ReturnMode::StrongestSecond);
        assert_eq!((a.unwrap().label, b), (6, None));
        // The three strongest of four, by range.
        let w = [
            e(1.0, 0.05, 1),
            e(2.0, 0.5, 2),
            e(7.0, 5.0, 6),
            e(9.0, 0.2, 5),
        ];
        let t = select_triple(&w);
        let labels: Vec<u8> = t.iter().flatten().map(|e| e.label).collect();
        assert_eq!(labels, [2, 6, 5]);
        let t = select_triple(&w[2..3]);
        assert_eq!((t[0].unwrap().label, t[1], t[2]), (6, None, None));
        assert_eq!(select_triple(&[]), [None, None, None]);
    }

    #[test]
    fn detection_limits() {
        let mut v = vec![
            e(0.05, 9.0, 1),
            e(3.0, 0.5, 1),
            e(3.5, 2.0, 1),
            e(70.0, 9.0, 1),
        ];
        detect(&mut v, 1.0, 0.1, 60.0);
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].range, 3.5);
    }
}
