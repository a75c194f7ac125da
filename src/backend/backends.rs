//! The [`Backend`] seam: back-ends chosen by name, with their parameters
//! ready to be the `[backend]` section of the TOML configuration.

use serde::{Deserialize, Serialize};

use super::average::{average_planes, AverageWeights};
use super::graph::FactorGraph;
use super::robust::RobustKernel;
use super::solver::{gauss_newton, levenberg_marquardt, SolveReport, SolverParams};
use super::variables::Values;
use crate::{Error, Result};

pub use super::seam::Backend;

/// Back-ends selectable by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BackendName {
    /// The paper's weighted average of plane observations (poses unchanged).
    Average,
    /// Sparse Gauss–Newton on faer.
    Gn,
    /// Sparse Levenberg–Marquardt on faer.
    Lm,
    /// The factrs crate (behind the `factrs` cargo feature).
    Factrs,
}

impl BackendName {
    /// The name as written in configs and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            BackendName::Average => "average",
            BackendName::Gn => "gn",
            BackendName::Lm => "lm",
            BackendName::Factrs => "factrs",
        }
    }
}

impl std::str::FromStr for BackendName {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "average" => Ok(BackendName::Average),
            "gn" => Ok(BackendName::Gn),
            "lm" => Ok(BackendName::Lm),
            "factrs" => Ok(BackendName::Factrs),
            other => Err(Error::Config(format!(
                "unknown back-end '{other}' (expected average, gn, lm or factrs)"
            ))),
        }
    }
}

/// Which plane factor the SLAM front end should emit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlaneFactorKind {
    /// The paper's plane-to-plane residual (GTSAM `OrientedPlane3Factor`).
    PlaneToPlane,
    /// Point-to-plane on the inliers' scatter (BALM2 / π-LSAM).
    PointToPlane,
}

/// Back-end configuration (the `[backend]` section).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BackendParams {
    /// Which back-end.
    pub name: BackendName,
    /// Iteration limits, tolerances, damping.
    pub solver: SolverParams,
    /// Robust kernel put on plane factors.
    pub robust: RobustKernel,
    /// Plane factor type.
    pub plane_factor: PlaneFactorKind,
    /// Plane-to-plane normal noise (radians).
    pub plane_normal_sigma: f64,
    /// Plane-to-plane offset noise (metres).
    pub plane_offset_sigma: f64,
    /// Point-to-plane point noise (metres).
    pub point_sigma: f64,
    /// Relative-pose translation noise (metres).
    pub odometry_translation_sigma: f64,
    /// Relative-pose rotation noise (radians).
    pub odometry_rotation_sigma: f64,
    /// An observation whose points lie farther than this (rms) from its
    /// landmark's plane at the tracked pose is a wrong association and is
    /// left out of the graph, m (absent: every observation is kept, the
    /// paper). One such observation of a large plane outweighs hundreds of
    /// frames of odometry.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_observation_rms: Option<f64>,
    /// Where tracking's point term fixed directions the planes left free,
    /// a relative-pose factor along them ties the frame to the frame whose
    /// points it was registered against, with this translation noise, m
    /// (absent, with `point_anchor_rotation_sigma`: no such factors).
    /// Without them the back-end sees those directions only through the
    /// frame-to-frame odometry, whose error accumulates, and loses what the
    /// local point map knew.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point_anchor_translation_sigma: Option<f64>,
    /// ... and this rotation noise, radians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point_anchor_rotation_sigma: Option<f64>,
    /// Along the directions a frame-to-frame registration left free (its
    /// planes did not observe them) and the points did not fix, the
    /// odometry is the motion model's prediction, not a measurement: its
    /// factor carries this translation noise there instead of
    /// `odometry_translation_sigma`, m (absent, with
    /// `odometry_free_rotation_sigma`: the odometry's noise in every
    /// direction, as in both built-in configurations). A loop or a point
    /// anchor can then move those directions where the motion model put
    /// them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub odometry_free_translation_sigma: Option<f64>,
    /// ... and this rotation noise, radians.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub odometry_free_rotation_sigma: Option<f64>,
    /// `average`: weight of a landmark after its first observation (the
    /// paper's 3, [`crate::map::merge::SECOND_WEIGHT`]; no key).
    #[serde(skip, default = "average_second_weight")]
    pub average_second_weight: f64,
    /// `average`: cap on a landmark's weight (the paper's 10,
    /// [`crate::map::merge::MAX_WEIGHT`]; no key).
    #[serde(skip, default = "average_max_weight")]
    pub average_max_weight: f64,
}

fn average_second_weight() -> f64 {
    crate::map::merge::SECOND_WEIGHT
}

fn average_max_weight() -> f64 {
    crate::map::merge::MAX_WEIGHT
}

impl Default for BackendParams {
    /// `[backend]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("backend")
    }
}

impl BackendParams {
    /// An error naming the first invalid field.
    pub fn validate(&self) -> Result<()> {
        self.robust
            .validate()
            .map_err(|e| Error::Config(format!("backend.robust: {e}")))?;
        let positive = [
            ("plane_normal_sigma", self.plane_normal_sigma),
            ("plane_offset_sigma", self.plane_offset_sigma),
            ("point_sigma", self.point_sigma),
            (
                "odometry_translation_sigma",
                self.odometry_translation_sigma,
            ),
            ("odometry_rotation_sigma", self.odometry_rotation_sigma),
            ("average_second_weight", self.average_second_weight),
            ("average_max_weight", self.average_max_weight),
        ];
        for (name, v) in positive {
            if !(v > 0.0) || !v.is_finite() {
                return Err(Error::Config(format!(
                    "backend.{name} must be finite and positive, got {v}"
                )));
            }
        }
        for (name, v) in [
            (
                "point_anchor_translation_sigma",
                self.point_anchor_translation_sigma,
            ),
            (
                "point_anchor_rotation_sigma",
                self.point_anchor_rotation_sigma,
            ),
            (
                "odometry_free_translation_sigma",
                self.odometry_free_translation_sigma,
            ),
            (
                "odometry_free_rotation_sigma",
                self.odometry_free_rotation_sigma,
            ),
            ("max_observation_rms", self.max_observation_rms),
        ] {
            if let Some(v) = v.filter(|v| !(*v > 0.0) || !v.is_finite()) {
                return Err(Error::Config(format!(
                    "backend.{name} must be finite and positive (leave it out to switch it off), got {v}"
                )));
            }
        }
        for (a, b, va, vb) in [
            (
                "point_anchor_translation_sigma",
                "point_anchor_rotation_sigma",
                self.point_anchor_translation_sigma,
                self.point_anchor_rotation_sigma,
            ),
            (
                "odometry_free_translation_sigma",
                "odometry_free_rotation_sigma",
                self.odometry_free_translation_sigma,
                self.odometry_free_rotation_sigma,
            ),
        ] {
            if va.is_some() != vb.is_some() {
                return Err(Error::Config(format!(
                    "backend.{a} and backend.{b} are given together or not at all"
                )));
            }
        }
        let s = &self.solver;
        if s.max_iterations == 0 {
            return Err(Error::Config(
                "backend.solver.max_iterations must be ≥ 1".into(),
            ));
        }
        for (name, v) in [
            ("relative_tolerance", s.relative_tolerance),
            ("absolute_tolerance", s.absolute_tolerance),
            ("step_tolerance", s.step_tolerance),
            ("initial_lambda", s.initial_lambda),
            ("max_lambda", s.max_lambda),
            ("unobservable_threshold", s.unobservable_threshold),
        ] {
            if !(v >= 0.0) || !v.is_finite() {
                return Err(Error::Config(format!(
                    "backend.solver.{name} must be finite and non-negative, got {v}"
                )));
            }
        }
        if !(s.lambda_decrease > 0.0 && s.lambda_decrease < 1.0) {
            return Err(Error::Config(format!(
                "backend.solver.lambda_decrease must be in (0, 1), got {}",
                s.lambda_decrease
            )));
        }
        Ok(())
    }
}

/// Sparse Gauss–Newton.
#[derive(Debug, Clone, Default)]
pub struct GaussNewton {
    /// Solver parameters.
    pub params: SolverParams,
}

impl Backend for GaussNewton {
    fn name(&self) -> &'static str {
        "gn"
    }
    fn optimize(&self, graph: &FactorGraph, initial: &Values) -> Result<(Values, SolveReport)> {
        gauss_newton(graph, initial, &self.params)
    }
}

/// Sparse Levenberg–Marquardt.
#[derive(Debug, Clone, Default)]
pub struct LevenbergMarquardt {
    /// Solver parameters.
    pub params: SolverParams,
}

impl Backend for LevenbergMarquardt {
    fn name(&self) -> &'static str {
        "lm"
    }
    fn optimize(&self, graph: &FactorGraph, initial: &Values) -> Result<(Values, SolveReport)> {
        levenberg_marquardt(graph, initial, &self.params)
    }
}

/// The paper's weighted plane average (no joint optimisation).
#[derive(Debug, Clone, Default)]
pub struct Average {
    /// Averaging weights.
    pub weights: AverageWeights,
    /// Only the observability threshold is used.
    pub params: SolverParams,
}

impl Backend for Average {
    fn name(&self) -> &'static str {
        "average"
    }
    fn optimize(&self, graph: &FactorGraph, initial: &Values) -> Result<(Values, SolveReport)> {
        average_planes(graph, initial, self.weights, &self.params)
    }
}

/// The back-end called `name`, configured from `params`.
pub fn backend(name: BackendName, params: &BackendParams) -> Result<Box<dyn Backend>> {
    params.validate()?;
    match name {
        BackendName::Gn => Ok(Box::new(GaussNewton {
            params: params.solver,
        })),
        BackendName::Lm => Ok(Box::new(LevenbergMarquardt {
            params: params.solver,
        })),
        BackendName::Average => Ok(Box::new(Average {
            weights: AverageWeights {
                second: params.average_second_weight,
                max: params.average_max_weight,
            },
            params: params.solver,
        })),
        #[cfg(feature = "factrs")]
        BackendName::Factrs => Ok(Box::new(super::factrs_adapter::Factrs {
            params: params.solver,
            method: super::factrs_adapter::FactrsMethod::LevenbergMarquardt,
        })),
        #[cfg(not(feature = "factrs"))]
        BackendName::Factrs => Err(Error::Config(
            "back-end 'factrs' is not available in this build: build with --features factrs \
             (or use gn, lm or average)"
                .into(),
        )),
    }
}
