//! What an intensity measures decides how the echo split reads it: a raw
//! echo power falls with r², a sensor's calibrated reflectivity does not.
//! The simulator's frames say they are raw power (in memory and in their PLY
//! header); real frames take the sensor model's scale (a reflectivity for
//! the QT64). The same echoes given either way must split alike.

use specular::classify::{Class, Rule};
use specular::cloud::{Frame, IntensityScale};
use specular::config::Config;
use specular::pipeline::{run_plane_optimized, PlaneOptimizedOutput, Sequence};
use specular::sim::{self, Scene};

/// 40 frames of the glass loop (uncoated partitions: their echoes behind
/// the glass fall in a weak reflected and a strong transmitted group),
/// each frame passed through `edit`, with the true poses.
fn glass_loop(edit: impl Fn(&mut Frame)) -> Sequence {
    let scene = Scene::resolve("glass-loop").unwrap();
    let mut run = sim::simulate(&scene, Some(40), None).unwrap();
    run.frames.iter_mut().for_each(edit);
    let poses = run.poses.iter().map(|p| p.pose).collect();
    Sequence::from_frames(run.frames, Some(poses), "glass-loop").unwrap()
}

/// Each used landmark's split threshold (`None`: no split).
fn thresholds(out: &PlaneOptimizedOutput) -> Vec<Option<f64>> {
    out.planes
        .iter()
        .map(|bp| bp.echo_split.map(|s| s.threshold))
        .collect()
}

/// Of the points `a` decided by their echo strength, how many `b` decided
/// by echo strength too, and how many of those it called reflected where
/// `a` called them transmitted, or the other way round. (A transmitted
/// echo is then an Obstacle or, through an opening, Normal: the evidence
/// grid decides that, from intensities read as they are.)
fn echo_strength_decisions(a: &PlaneOptimizedOutput, b: &PlaneOptimizedOutput) -> (usize, usize) {
    let mut both = 0;
    let mut differ = 0;
    for (x, y) in a.run.frames.iter().zip(&b.run.frames) {
        for i in 0..x.classes.len() {
            if x.rules[i] == Rule::EchoStrength && y.rules[i] == Rule::EchoStrength {
                both += 1;
                let reflected = |c: Class| c == Class::Reflection;
                differ += usize::from(reflected(x.classes[i]) != reflected(y.classes[i]));
            }
        }
    }
    (both, differ)
}

#[test]
fn the_same_echoes_as_raw_power_or_as_reflectivity_split_alike() {
    let config = Config::default();
    assert_eq!(
        Config::resolve("default").unwrap().plane_map.echo_split,
        config.plane_map.echo_split
    );
    assert!(config.plane_map.echo_split.is_some());
    let raw = run_plane_optimized(&glass_loop(|_| {}), &config).unwrap();
    // As a sensor that compensates the range reports them.
    let reflectivity = run_plane_optimized(
        &glass_loop(|f| {
            for p in &mut f.points {
                p.intensity *= (p.range() * p.range()) as f32;
            }
            f.intensity_scale = Some(IntensityScale::Reflectivity);
        }),
        &config,
    )
    .unwrap();
    // The raw power misread as a reflectivity.
    let misread = run_plane_optimized(
        &glass_loop(|f| f.intensity_scale = Some(IntensityScale::Reflectivity)),
        &config,
    )
    .unwrap();

    let want = thresholds(&raw);
    assert!(
        want.iter().any(Option::is_some),
        "no split to compare: {want:?}"
    );
    let got = thresholds(&reflectivity);
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        match (g, w) {
            (Some(g), Some(w)) => assert!((g - w).abs() <= 0.05, "{got:?} vs {want:?}"),
            (None, None) => {}
            _ => panic!("splits differ: {got:?} vs {want:?}"),
        }
    }
    // The intensity scale is the echo split's concern only: the other
    // intensity tests (a pane's own echoes against a wall's) compare echoes
    // at similar ranges and read the numbers as they are, so only the
    // points both runs decided by echo strength are compared.
    let (both, differ) = echo_strength_decisions(&raw, &reflectivity);
    assert!(
        both > 1000 && differ * 100 <= both,
        "{differ} of {both} differ"
    );
    // Read with the wrong scale, the same echoes split elsewhere.
    let misread_thresholds = thresholds(&misread);
    let (both_misread, differ_misread) = echo_strength_decisions(&raw, &misread);
    assert!(
        misread_thresholds
            .iter()
            .zip(&want)
            .any(|(m, w)| match (m, w) {
                (Some(m), Some(w)) => (m - w).abs() > 0.2,
                (None, None) => false,
                _ => true,
            }),
        "misread: {misread_thresholds:?} vs {want:?} ({differ_misread} of {both_misread} differ)"
    );
}
