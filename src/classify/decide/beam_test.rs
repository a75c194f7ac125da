//! The beam test: where each point lies against the first reflective plane
//! its beam crosses (on it, in front, just behind, behind, or clear of
//! every plane), shared by both decision models.

use super::{BeamHit, BeamHits, DecisionParams};
use crate::classify::rule::Rule;
use crate::classify::Class;
use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
use crate::sensor::OrganizedScan;

/// The per-point outcome of the beam test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Beam {
    Clear,
    Surface,
    WallEcho,
    Oblique,
    Front,
    Band,
    Behind {
        plane: u16,
    },
    /// Behind the unseen continuation of a plane's extent.
    Unseen {
        plane: u16,
    },
}

/// The beam test of every point against `bounded` (`hits` from
/// [`BeamHits::compute`]): on, in front of, just behind or behind the first
/// plane its beam crosses, or clear of every plane.
pub(crate) fn beam_test(
    frame: &Frame,
    scan: &OrganizedScan,
    bounded: &[BoundedPlane],
    hits: &BeamHits,
    params: &DecisionParams,
) -> Vec<Beam> {
    let oblique_cos = if params.oblique_single_echo_deg > 0.0 {
        params.oblique_single_echo_deg.to_radians().cos()
    } else {
        -1.0
    };
    frame
        .points
        .iter()
        .enumerate()
        .map(|(i, pt)| {
            let p = pt.position();
            match hits.get(i, &p, bounded) {
                None => match hits.unseen(i, &p, bounded) {
                    Some(h) if p.coords.norm() - h.range > params.behind_distance => Beam::Unseen {
                        plane: h.plane as u16,
                    },
                    _ => Beam::Clear,
                },
                Some(BeamHit { plane: k, range: t }) => {
                    let s = p.coords.norm() - t;
                    if s.abs() <= params.glass_distance {
                        // A single echo as bright as a wall is the wall.
                        let single = scan.partner(i).is_none();
                        let cos = bounded[k].plane.normal.dot(&p.coords) / p.coords.norm();
                        // Far from normal incidence a single echo brighter
                        // than the plane's typical glass echo is opaque.
                        let glass_echo = bounded[k]
                            .evidence
                            .as_ref()
                            .and_then(|e| e.glass_echo_intensity);
                        // Stronger than the plane's glass echoes met at
                        // the same incidence, where they tell; else than
                        // their median.
                        let brighter = || {
                            bounded[k]
                                .evidence
                                .as_ref()
                                .and_then(|e| e.stronger_than_glass(pt.intensity, t, cos))
                                .unwrap_or_else(|| glass_echo.is_none_or(|m| pt.intensity > m))
                        };
                        if single && cos.abs() < oblique_cos && brighter() {
                            return Beam::Oblique;
                        }
                        match &bounded[k].evidence {
                            Some(e)
                                if params.wall_echo_test
                                    && single
                                    && e.is_opaque_echo(pt.intensity, t, cos) =>
                            {
                                Beam::WallEcho
                            }
                            _ => Beam::Surface,
                        }
                    } else if s < 0.0 {
                        Beam::Front
                    } else if s <= params.behind_distance {
                        Beam::Band
                    } else {
                        Beam::Behind { plane: k as u16 }
                    }
                }
            }
        })
        .collect()
}

/// The class and rule the beam test alone gives each point (behind-plane
/// points undecided).
pub(crate) fn beam_classes(beams: &[Beam]) -> (Vec<Class>, Vec<Rule>) {
    beams
        .iter()
        .map(|b| match b {
            Beam::Clear | Beam::Unseen { .. } => (Class::Normal, Rule::NoPane),
            Beam::Front => (Class::Normal, Rule::InFront),
            Beam::WallEcho => (Class::Normal, Rule::WallEcho),
            Beam::Oblique => (Class::Normal, Rule::ObliqueEcho),
            Beam::Surface => (Class::Glass, Rule::OnPane),
            Beam::Band => (Class::Unclassified, Rule::Band),
            Beam::Behind { .. } => (Class::Unclassified, Rule::Undecided),
        })
        .unzip()
}

/// Per plane, the deepest Normal point of the frame measured behind it
/// along its normal (0 at least): the room a reflection could come from.
pub(crate) fn room_depths(frame: &Frame, bounded: &[BoundedPlane], classes: &[Class]) -> Vec<f64> {
    let mut max_indoor = vec![0.0f64; bounded.len()];
    for (pt, c) in frame.points.iter().zip(classes) {
        if *c == Class::Normal {
            let p = pt.position();
            for (k, bp) in bounded.iter().enumerate() {
                max_indoor[k] = max_indoor[k].max(bp.plane.signed_distance(&p));
            }
        }
    }
    max_indoor
}
