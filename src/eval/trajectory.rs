//! Trajectory error of an estimated sequence of poses against the truth.
//!
//! - **ATE** (absolute trajectory error): RMSE of the position differences
//!   after the rigid alignment (rotation and translation, no scale) that
//!   minimises them ([`umeyama`]).
//! - **RPE** (relative pose error): over every segment that starts at a
//!   frame and ends at the first frame at least `segment` metres of true
//!   path later, the error of the relative motion, as translation error per
//!   metre travelled (percent) and rotation error per metre (degrees/m).
//! - **Drift**: the final position error, with the estimate anchored at the
//!   first true pose, in percent of the true path length.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// The rigid transform `T` minimising `Σ ‖target_i − T source_i‖²`
/// (Umeyama 1991 without scale; the determinant is corrected so the result
/// is a rotation). `None` when the lists are empty, differ in length or
/// hold non-finite coordinates.
/// For collinear points the rotation about their line is arbitrary (it
/// does not change the residuals).
pub fn umeyama(source: &[Point3<f64>], target: &[Point3<f64>]) -> Option<Isometry3<f64>> {
    if source.is_empty() || source.len() != target.len() {
        return None;
    }
    let finite = |p: &Point3<f64>| p.iter().all(|v| v.is_finite());
    if !(source.iter().all(finite) && target.iter().all(finite)) {
        return None;
    }
    let n = source.len() as f64;
    let mu_s = source.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
    let mu_t = target.iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
    let mut sigma = Matrix3::zeros();
    for (s, t) in source.iter().zip(target) {
        sigma += (t.coords - mu_t) * (s.coords - mu_s).transpose();
    }
    sigma /= n;
    let svd = sigma.svd(true, true);
    let (u, v_t) = (svd.u?, svd.v_t?);
    let sv = svd.singular_values;
    let smallest = (0..3).min_by(|&a, &b| sv[a].total_cmp(&sv[b]))?;
    let mut s = Matrix3::identity();
    if u.determinant() * v_t.determinant() < 0.0 {
        s[(smallest, smallest)] = -1.0;
    }
    let r = u * s * v_t;
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = mu_t - rotation * mu_s;
    Some(Isometry3::from_parts(Translation3::from(t), rotation))
}

/// Trajectory error figures (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryError {
    /// Frames compared.
    pub frames: usize,
    /// Length of the true path, m.
    pub path_length: f64,
    /// ATE: RMSE of the aligned positions, m.
    pub ate_rmse: f64,
    /// Largest aligned position error, m.
    pub ate_max: f64,
    /// RPE segment length, m.
    pub rpe_segment: f64,
    /// Segments evaluated for the RPE (0 when the path is shorter).
    pub rpe_segments: usize,
    /// Mean translation error per metre travelled, percent.
    pub rpe_translation_percent: f64,
    /// Mean rotation error per metre travelled, degrees/m.
    pub rpe_rotation_deg_per_m: f64,
    /// Final position error with the estimate anchored at the first true
    /// pose, m.
    pub final_error: f64,
    /// `final_error` in percent of the path length.
    pub drift_percent: f64,
}

impl TrajectoryError {
    /// A one-line summary.
    pub fn summary(&self) -> String {
        // Without a whole segment there is no RPE to speak of (NaN).
        let rpe = if self.rpe_segments > 0 {
            format!(
                "RPE {:.2} % and {:.3} deg/m over {} segments of {:.1} m",
                self.rpe_translation_percent,
                self.rpe_rotation_deg_per_m,
                self.rpe_segments,
                self.rpe_segment
            )
        } else {
            format!(
                "no RPE (path {:.1} m, shorter than one {:.1} m segment)",
                self.path_length, self.rpe_segment
            )
        };
        // A percentage of a path shorter than one segment says nothing.
        let drift = if self.path_length >= self.rpe_segment {
            format!(
                "drift {:.2} % ({:.3} m over {:.1} m, from the first pose)",
                self.drift_percent, self.final_error, self.path_length
            )
        } else {
            format!(
                "final error {:.3} m from the first pose (no drift percentage over a {:.1} m path)",
                self.final_error, self.path_length
            )
        };
        format!(
            "ATE RMSE {:.3} m (max {:.3}) after SE(3) alignment, {rpe}, {drift}",
            self.ate_rmse, self.ate_max,
        )
    }
}

/// Compare `estimated` with `truth` (same length, same frames, both
/// `T_world_sensor`); RPE over segments of `segment` metres.
pub fn trajectory_error(
    estimated: &[Isometry3<f64>],
    truth: &[Isometry3<f64>],
    segment: f64,
) -> Result<TrajectoryError> {
    if estimated.len() != truth.len() || estimated.is_empty() {
        return Err(Error::Input(format!(
            "trajectory error needs as many estimated as true poses (got {} and {})",
            estimated.len(),
            truth.len()
        )));
    }
    if !(segment > 0.0) {
        return Err(Error::Input(format!(
            "the RPE segment length must be positive, got {segment}"
        )));
    }
    let pos = |p: &Isometry3<f64>| Point3::from(p.translation.vector);
    let est: Vec<Point3<f64>> = estimated.iter().map(pos).collect();
    let gt: Vec<Point3<f64>> = truth.iter().map(pos).collect();

    // ATE after alignment.
    let align = umeyama(&est, &gt).unwrap_or_else(Isometry3::identity);
    let errors: Vec<f64> = est
        .iter()
        .zip(&gt)
        .map(|(e, g)| (align * e - g).norm())
        .collect();
    let ate_rmse = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let ate_max = errors.iter().copied().fold(0.0, f64::max);

    // Cumulative true path length.
    let mut along = vec![0.0; gt.len()];
    for k in 1..gt.len() {
        along[k] = along[k - 1] + (gt[k] - gt[k - 1]).norm();
    }
    let path_length = along[gt.len() - 1];

    // RPE over segments of `segment` metres.
    let (mut trans, mut rot, mut count) = (0.0, 0.0, 0usize);
    let mut j = 0;
    for i in 0..gt.len() {
        j = j.max(i + 1);
        while j < gt.len() && along[j] - along[i] < segment {
            j += 1;
        }
        if j >= gt.len() {
            break;
        }
        let length = along[j] - along[i];
        let rel_gt = truth[i].inverse() * truth[j];
        let rel_est = estimated[i].inverse() * estimated[j];
        let err = rel_gt.inverse() * rel_est;
        trans += err.translation.vector.norm() / length;
        rot += err.rotation.angle().to_degrees() / length;
        count += 1;
    }
    let mean = |s: f64| {
        if count > 0 {
            s / count as f64
        } else {
            f64::NAN
        }
    };

    // Drift: anchored at the first true pose.
    let anchor = truth[0] * estimated[0].inverse();
    let last = gt.len() - 1;
    let final_error = (anchor * est[last] - gt[last]).norm();
    let drift_percent = if path_length > 0.0 {
        100.0 * final_error / path_length
    } else {
        f64::NAN
    };
    Ok(TrajectoryError {
        frames: gt.len(),
        path_length,
        ate_rmse,
        ate_max,
        rpe_segment: segment,
        rpe_segments: count,
        rpe_translation_percent: 100.0 * mean(trans),
        rpe_rotation_deg_per_m: mean(rot),
        final_error,
        drift_percent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(n: usize, step: f64) -> Vec<Isometry3<f64>> {
        (0..n)
            .map(|k| {
                let a = k as f64 * 0.1;
                Isometry3::new(
                    Vector3::new(k as f64 * step, (a).sin(), 0.1 * a),
                    Vector3::new(0.0, 0.0, a),
                )
            })
            .collect()
    }

    #[test]
    fn a_path_shorter_than_a_segment_reports_no_percentages() {
        let truth: Vec<Isometry3<f64>> = (0..3)
            .map(|k| Isometry3::translation(0.01 * k as f64, 0.0, 0.0))
            .collect();
        let est: Vec<Isometry3<f64>> = (0..3)
            .map(|k| Isometry3::translation(0.012 * k as f64, 0.0, 0.0))
            .collect();
        let e = trajectory_error(&est, &truth, 1.0).unwrap();
        let text = e.summary();
        assert!(!text.contains('%') && !text.contains("NaN"), "{text}");
        assert!(text.contains("final error 0.004 m"), "{text}");
    }

    #[test]
    fn a_rigidly_moved_trajectory_has_no_ate_but_the_drift_sees_it() {
        let truth = line(50, 0.1);
        let moved = Isometry3::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.1, 0.2, 0.3));
        let est: Vec<_> = truth.iter().map(|p| moved * p).collect();
        let e = trajectory_error(&est, &truth, 1.0).unwrap();
        assert!(e.ate_rmse < 1e-9, "{}", e.summary());
        assert!(e.rpe_translation_percent < 1e-9 && e.rpe_rotation_deg_per_m < 1e-9);
        // Anchoring at the first pose removes the rigid motion too.
        assert!(e.drift_percent < 1e-9);
        assert!(e.rpe_segments > 30);
    }

    #[test]
    fn a_scale_error_shows_in_every_figure() {
        let truth = line(50, 0.1);
        let est: Vec<_> = truth
            .iter()
            .map(|p| {
                Isometry3::from_parts(Translation3::from(p.translation.vector * 1.1), p.rotation)
            })
            .collect();
        let e = trajectory_error(&est, &truth, 1.0).unwrap();
        assert!(
            e.ate_rmse > 0.05 && e.drift_percent > 5.0,
            "{}",
            e.summary()
        );
        assert!(
            (e.rpe_translation_percent - 10.0).abs() < 1.0,
            "{}",
            e.summary()
        );
        assert!(trajectory_error(&est[..3], &truth, 1.0).is_err());
    }

    /// The summary says the ATE is SE(3)-aligned, and a path shorter than
    /// one RPE segment prints no NaN.
    #[test]
    fn a_short_run_summary_has_no_nan() {
        let truth = line(5, 0.1);
        let e = trajectory_error(&truth, &truth, 10.0).unwrap();
        assert_eq!(e.rpe_segments, 0);
        let s = e.summary();
        assert!(!s.contains("NaN") && s.contains("no RPE"), "{s}");
        assert!(s.contains("SE(3) alignment"), "{s}");
        let long = trajectory_error(&line(50, 0.1), &line(50, 0.1), 1.0).unwrap();
        assert!(long.summary().contains("segments of 1.0 m"));
    }
}
