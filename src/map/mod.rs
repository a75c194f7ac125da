//! The global plane map: landmarks fused from per-frame plane observations.
//!
//! A [`PlaneMap`] holds [`Landmark`]s (kind, plane and boundary in the world
//! frame, observation count, first/last frame). A [`MapMerger`] decides
//! whether a new observation is a known landmark and how to fuse it; the
//! paper's weighted-average merger is [`WeightedAverageMerger`].

pub mod boundary_fit;
pub mod direct;
pub mod evidence;
pub mod ghosts;
pub mod glass_or_mirror;
pub mod landmark;
pub mod merge;
pub mod panes;
pub mod params;
pub mod reflection_share;
pub mod through_surfaces;

pub use evidence::{
    gather_evidence, open_where_crossed, passed_through, path_crossings, EvidenceFrame,
    EvidenceGatherer, EvidenceParams, EvidenceTotal, FrameVotes,
};
pub use ghosts::{find_ghosts, Ghost, GhostParams};
pub use glass_or_mirror::{
    glass_or_mirror, BehindEchoes, GlassOrMirror, LandedEcho, MirrorParams, ThroughBeam,
};
pub use landmark::{Landmark, LandmarkSelection, PlaneMap, PlaneObservation};
pub use merge::{MapMerger, MergeParams, WeightedAverageMerger};
pub use panes::{find_panes, Pane, PaneParams};
pub use params::{BoundaryMode, MapParams, MergerName};
pub use through_surfaces::LandedStrengths;
