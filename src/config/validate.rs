//! Range checks on the composed configuration, each naming the key it
//! rejects: run when a configuration is loaded, so no stage sees a value
//! it cannot use.

use super::Config;

impl Config {
    pub(super) fn validate(&self) -> std::result::Result<(), String> {
        let d = &self.detector;
        let positive = [
            ("detector.dual_gap", d.dual_gap),
            ("detector.ransac.distance", d.ransac.distance),
            ("input.pose_tolerance", self.input.pose_tolerance),
            (
                "plane_map.decision.glass_distance",
                self.plane_map.decision.glass_distance,
            ),
            ("plane_map.support_voxel", self.plane_map.support_voxel),
            ("extractor.ransac.distance", self.extractor.ransac.distance),
            (
                "extractor.ground.ransac.distance",
                self.extractor.ground.ransac.distance,
            ),
            ("extractor.normals.max_gap", self.extractor.normals.max_gap),
            ("extractor.min_area", self.extractor.min_area),
            (
                "slam.rejector.inlier_offset",
                self.slam.rejector.inlier_offset,
            ),
            ("slam.rpe_segment", self.slam.rpe_segment),
            ("slam.gap_ratio", self.slam.gap_ratio),
        ];
        for (name, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("{name} must be positive, got {v}"));
            }
        }
        let gap = self.input.pose_interpolation_gap;
        if !(gap >= 0.0 && gap.is_finite()) {
            return Err(format!(
                "input.pose_interpolation_gap must be >= 0 (0: never interpolate), got {gap}"
            ));
        }
        let cache = self.input.frame_cache_mb;
        if !(cache >= 0.0 && cache.is_finite()) {
            return Err(format!(
                "input.frame_cache_mb must be a number of megabytes >= 0 (0: keep no frame), got {cache}"
            ));
        }
        if d.max_planes == 0 {
            return Err("detector.max_planes must be at least 1".into());
        }
        for (name, v) in [
            ("extractor.reflective_link", self.extractor.reflective_link),
            ("slam.keyframe_move", self.slam.keyframe_move),
            ("slam.keyframe_turn_deg", self.slam.keyframe_turn_deg),
            (
                "backend.max_observation_rms",
                self.backend.max_observation_rms,
            ),
        ] {
            if let Some(v) = v.filter(|v| !(*v > 0.0 && v.is_finite())) {
                return Err(format!(
                    "{name} must be positive (leave it out to switch it off), got {v}"
                ));
            }
        }
        if let Some(w) = self.slam.window.filter(|w| *w < 2) {
            return Err(format!(
                "slam.window must be at least 2 frames (leave it out for no window), got {w}"
            ));
        }
        let dec = &self.plane_map.decision;
        if dec.behind_distance < dec.glass_distance {
            return Err("plane_map.decision.behind_distance must be >= glass_distance".into());
        }
        if self.extractor.min_points < 3 {
            return Err("extractor.min_points must be at least 3".into());
        }
        if let Some(tolerance) = d.surface_tolerance_deg {
            if !(tolerance > 0.0 && tolerance < 90.0) {
                return Err(format!(
                    "detector.surface_tolerance_deg must be in (0, 90) (leave it out to keep every plane), got {tolerance}"
                ));
            }
        }
        if let Some(parallel) = self.slam.points.parallel_reflective_deg {
            if !(parallel > 0.0 && parallel < 90.0) {
                return Err(format!(
                    "slam.points.parallel_reflective_deg must be in (0, 90) (leave it out for none), got {parallel}"
                ));
            }
        }
        let gain = self.slam.motion.free_direction_gain;
        if !(0.0..=1.0).contains(&gain) {
            return Err(format!(
                "slam.motion.free_direction_gain must be in [0, 1], got {gain}"
            ));
        }
        if !(self.slam.gauss_newton.degeneracy_threshold >= 0.0)
            || !(self.slam.rejector.min_eigenvalue >= 0.0)
        {
            return Err(
                "slam.gauss_newton.degeneracy_threshold and slam.rejector.min_eigenvalue must be >= 0"
                    .into(),
            );
        }
        if self.map.min_observations == 0 {
            return Err("map.min_observations must be at least 1".into());
        }
        if !(self.output.map_voxel >= 0.0) {
            return Err("output.map_voxel must be >= 0".into());
        }
        if !(self.output.topdown_min_height < self.output.topdown_max_height) {
            return Err(
                "output.topdown_min_height must be below output.topdown_max_height (-inf and inf: no bound)"
                    .into(),
            );
        }
        self.slam.loop_closure.validate()?;
        self.backend.validate().map_err(|e| e.to_string())?;
        Ok(())
    }
}
