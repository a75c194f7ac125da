//! Loop closure (issue 15, item 3): revisits are closed with measurements
//! that agree with the truth, a wrong candidate is rejected by the
//! verification, and the switch turns it off.

mod common;

use nalgebra::Isometry3;
use specular::config::Config;
use specular::frontend::FramePlane;
use specular::pipeline::registry::{detector, extractor, rejector};
use specular::pipeline::slam::frame_features;
use specular::pipeline::{optimize_tracked, track_sequence, Sequence};
use specular::sensor::SensorModel;
use specular::slam::loop_closure::{LoopRejection, Pair, Verifier};

/// The office walked twice round: loops are closed, each loop's measured
/// relative pose agrees with the truth within 2 cm and 0.5 degrees, and
/// the back-end with them is not worse than without; with
/// `[slam.loop_closure] enabled = false` no loop is closed.
#[test]
fn office_revisits_close_loops_that_agree_with_the_truth() {
    let seq = common::simulated_subset("office", 0..600);
    let truth = seq.poses.clone().unwrap();
    let config = Config::resolve("default").unwrap();
    assert!(config.slam.loop_closure.enabled);
    let out = optimize_tracked(
        track_sequence(&seq, &config, Some(truth[0])).unwrap(),
        &config,
    )
    .unwrap();
    assert!(!out.loops.is_empty(), "no loop closed");
    for l in &out.loops {
        let true_rel = truth[l.from].inverse() * truth[l.to];
        let err = true_rel.inverse() * l.relative;
        assert!(
            err.translation.vector.norm() < 0.02 && err.rotation.angle().to_degrees() < 0.5,
            "loop {} -> {}: error {:.3} m, {:.2} deg",
            l.from,
            l.to,
            err.translation.vector.norm(),
            err.rotation.angle().to_degrees()
        );
        assert!(l.to - l.from >= config.slam.loop_closure.min_frames_apart);
    }
    let closed = out
        .reports
        .iter()
        .filter(|r| r.loop_closure.is_some())
        .count();
    assert_eq!(closed, out.loops.len());
    let mut off = config.clone();
    off.slam.loop_closure.enabled = false;
    let without =
        optimize_tracked(track_sequence(&seq, &off, Some(truth[0])).unwrap(), &off).unwrap();
    assert!(without.loops.is_empty());
    assert!(without.reports.iter().all(|r| r.loop_candidates == 0));
    let ate = |p: &[Isometry3<f64>]| {
        specular::eval::trajectory_error(p, &truth, 1.0)
            .unwrap()
            .ate_rmse
    };
    assert!(
        ate(&out.poses) <= ate(&without.poses) + 0.0005,
        "{} vs {}",
        ate(&out.poses),
        ate(&without.poses)
    );
}

/// The planes of frame `k` of a simulated sequence (sensor frame).
fn planes(seq: &Sequence, k: usize, config: &Config) -> Vec<FramePlane> {
    let sensor = SensorModel::resolve(&config.sensor).unwrap();
    let frame = seq.frame(k).unwrap();
    let (features, _) = frame_features(
        &frame,
        &sensor,
        detector(config, &sensor).as_ref(),
        extractor(config).as_ref(),
        &config.extractor,
        &config.slam.points,
        config.seed,
    )
    .unwrap();
    features.planes
}

/// In the corridor (floor, ceiling, parallel walls, repeated panes) a frame
/// 3 m further along looks like the same place to the planes; taken as a
/// candidate at the current estimate it is rejected (the planes leave the
/// axis free, and from 3 m away the points are not asked); so is an
/// office frame taken for another 1.5 m away. The right hypotheses, from
/// priors a few centimetres off, are accepted and corrected.
#[test]
fn a_wrong_candidate_in_a_corridor_is_rejected_by_verification() {
    let seq = common::simulated_subset("corridor", [100, 130].into_iter());
    let config = Config::resolve("default").unwrap();
    let truth = seq.poses.clone().unwrap();
    let a = planes(&seq, 0, &config);
    let b = planes(&seq, 1, &config);
    let true_rel = truth[0].inverse() * truth[1];
    assert!(true_rel.translation.vector.norm() > 2.5);
    let rej = rejector(&config);
    let lc = config.slam.loop_closure;
    let verifier = Verifier {
        rejector: rej.as_ref(),
        gauss_newton: &config.slam.gauss_newton,
        inlier_cos: config.slam.rejector.inlier_cos(),
        inlier_offset: config.slam.rejector.inlier_offset,
        points: None,
    };
    // The wrong hypothesis: frame 130 is where frame 100 was.
    let pair = Pair {
        current: &b,
        candidate: &a,
        travelled: 30.0,
        samples: None,
    };
    let wrong = verifier.verify(&pair, &Isometry3::identity(), &lc, 7);
    assert!(wrong.is_err(), "{wrong:?}");
    if let Err(LoopRejection::Degenerate { free, .. }) = &wrong {
        assert!(*free >= 1);
    }
    // Wrong too: an office frame as the candidate of another 1.5 m away.
    let office = common::simulated_subset("office", [40, 85].into_iter());
    let otruth = office.poses.clone().unwrap();
    assert!((otruth[0].inverse() * otruth[1]).translation.vector.norm() > 1.0);
    let (o0, o1) = (planes(&office, 0, &config), planes(&office, 1, &config));
    let pair = Pair {
        current: &o1,
        candidate: &o0,
        travelled: 30.0,
        samples: None,
    };
    let wrong = verifier.verify(&pair, &Isometry3::identity(), &lc, 7);
    assert!(wrong.is_err(), "{wrong:?}");
    // The right hypothesis is accepted: the office frame against itself
    // from a prior 5 cm off comes back to the identity, and against the
    // other frame from its true relative pose 3 cm off.
    let pair = Pair {
        current: &o0,
        candidate: &o0,
        travelled: 30.0,
        samples: None,
    };
    let m = verifier
        .verify(&pair, &Isometry3::translation(0.03, -0.03, 0.0), &lc, 7)
        .unwrap();
    assert!(m.relative.translation.vector.norm() < 0.005, "{m:?}");
    assert!((m.correction - 0.0424).abs() < 0.005, "{m:?}");
    let pair = Pair {
        current: &o1,
        candidate: &o0,
        travelled: 30.0,
        samples: None,
    };
    let true_rel = otruth[0].inverse() * otruth[1];
    let m = verifier
        .verify(
            &pair,
            &(true_rel * Isometry3::translation(0.03, 0.0, 0.0)),
            &lc,
            7,
        )
        .unwrap();
    let err = true_rel.inverse() * m.relative;
    assert!(err.translation.vector.norm() < 0.01, "{m:?}");
}
