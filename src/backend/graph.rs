//! The pose-plane factor graph: variables (with their stored estimates),
//! factors, fixed variables and the gauge rule.
//!
//! Gauge: the graph's cost is invariant to a global rigid motion, so one
//! pose must be anchored. By default ([`FactorGraph::auto_gauge`]) the pose
//! with the smallest id is held fixed unless a [`PosePrior`] is present or a
//! pose is already listed in [`FactorGraph::fixed`]; fixed variables are
//! simply excluded from the linear system (GTSAM would use a tight prior;
//! `paper/gtsam_solve.py` does that to match).
//!
//! [`PosePrior`]: super::factors::PosePrior

use std::collections::BTreeSet;

use super::factors::{keys_text, AnyFactor, Factor, GraphFactor};
use super::variables::{Key, Values};
use crate::{Error, Result};

/// Variables, factors and gauge of a pose-plane graph.
#[derive(Debug, Clone, PartialEq)]
pub struct FactorGraph {
    /// The variables and their stored estimates (the initial values of a
    /// solve unless other values are given).
    pub values: Values,
    /// Factors in insertion order (their order fixes the summation order,
    /// hence bit-identical results).
    pub factors: Vec<GraphFactor>,
    /// Variables held constant.
    pub fixed: BTreeSet<Key>,
    /// Fix the first pose when nothing else anchors the gauge.
    pub auto_gauge: bool,
}

impl Default for FactorGraph {
    fn default() -> Self {
        Self {
            values: Values::default(),
            factors: Vec::new(),
            fixed: BTreeSet::new(),
            auto_gauge: true,
        }
    }
}

impl FactorGraph {
    /// An empty graph with the automatic gauge.
    pub fn new() -> Self {
        Self::default()
    }

    /// Append a factor without a robust kernel.
    pub fn add(&mut self, factor: AnyFactor) {
        self.factors.push(GraphFactor::new(factor));
    }

    /// Check that every factor's keys and every fixed key have a value and
    /// that every number is finite.
    pub fn validate(&self) -> Result<()> {
        for (i, f) in self.factors.iter().enumerate() {
            f.robust.validate()?;
            for &k in f.factor.keys() {
                if !self.values.contains(k) {
                    return Err(Error::Input(format!(
                        "factor {i} ({} on {}) refers to unknown variable {k}",
                        f.factor.type_name(),
                        keys_text(f.factor.keys())
                    )));
                }
            }
        }
        for &k in &self.fixed {
            if !self.values.contains(k) {
                return Err(Error::Input(format!("fixed variable {k} does not exist")));
            }
        }
        check_finite(&self.values)
    }

    /// The variables held constant in a solve: [`FactorGraph::fixed`] plus,
    /// with [`FactorGraph::auto_gauge`], the first pose when no pose is fixed
    /// and no pose prior exists.
    pub fn effective_fixed(&self) -> BTreeSet<Key> {
        let mut fixed = self.fixed.clone();
        let has_prior = self
            .factors
            .iter()
            .any(|f| matches!(f.factor, AnyFactor::PosePrior(_)));
        let pose_fixed = fixed.iter().any(|k| matches!(k, Key::Pose(_)));
        if self.auto_gauge && !has_prior && !pose_fixed {
            if let Some(&first) = self.values.poses.keys().next() {
                fixed.insert(Key::Pose(first));
            }
        }
        fixed
    }

    /// Total cost `½ Σ ρ(‖S r‖²)` at `values` (GTSAM's `graph.error`).
    pub fn cost(&self, values: &Values) -> Result<f64> {
        let mut total = 0.0;
        for f in &self.factors {
            total += f.cost(values)?;
        }
        if !total.is_finite() {
            return Err(Error::Input("the graph's cost is not finite".into()));
        }
        Ok(total)
    }
}

/// An error unless every value is finite.
pub(crate) fn check_finite(values: &Values) -> Result<()> {
    for (id, x) in &values.poses {
        let ok = x.translation.vector.iter().all(|v| v.is_finite())
            && x.rotation.coords.iter().all(|v| v.is_finite());
        if !ok {
            return Err(Error::Input(format!("pose x{id} is not finite")));
        }
    }
    for (id, p) in &values.planes {
        if !(p.normal.iter().all(|v| v.is_finite()) && p.d.is_finite()) {
            return Err(Error::Input(format!("plane p{id} is not finite")));
        }
    }
    Ok(())
}
