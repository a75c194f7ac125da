//! Which rule decided each point's class, so a researcher can see why a
//! point was called a Reflection: written per point into the Foxglove
//! recording (`rule` field of `/cloud`) and counted against the labels in
//! `metrics.json` and `report.md`.

use serde::ser::SerializeMap;
use serde::{Serialize, Serializer};

use super::Class;

/// The rule of the decision procedure that gave a point its class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum Rule {
    /// No rule decided: the point stays unclassified (or takes the
    /// configured class for undecided points).
    #[default]
    Undecided = 0,
    /// Its beam crosses no reflective pane: Normal.
    NoPane = 1,
    /// It lies in front of the first pane its beam crosses: Normal.
    InFront = 2,
    /// On the pane, but a single echo as bright as a wall: Normal.
    WallEcho = 3,
    /// On the pane: reflective surface.
    OnPane = 4,
    /// Just behind the pane, within the band where on and behind cannot be
    /// told apart: unclassified.
    Band = 5,
    /// Where it was measured, space was seen free (or its path runs
    /// through a seen surface), and its mirror image is possible: a
    /// Reflection.
    RealRefuted = 6,
    /// Its mirror image lies in seen-free space (or the reflected path runs
    /// through a seen surface), and where it was measured is possible: an
    /// Obstacle seen through glass.
    MirrorRefuted = 7,
    /// Deeper behind the pane than anything seen in front of it: Obstacle.
    Depth = 8,
    /// The frame saw through its mirror image: Obstacle.
    FrameFreeSpace = 9,
    /// Its echo strength falls in the landmark's reflected or transmitted
    /// group.
    EchoStrength = 10,
    /// Its mirror image lands on an observed surface: Reflection.
    Support = 11,
    /// The near return of a beam whose far return is an Obstacle:
    /// Reflection.
    DualReturn = 12,
    /// On the pane, but a single echo met far from normal incidence, where
    /// glass gives none: Normal.
    ObliqueEcho = 13,
    /// Behind a landmark that transmits nothing (a mirror): Reflection.
    BehindMirror = 14,
    /// Measured on a surface seen directly from elsewhere in the sequence:
    /// real, an Obstacle.
    SeenSurface = 15,
    /// Behind a plane just beyond its seen reflective extent, where glass
    /// may continue without an echo: its mirror image lands on a seen
    /// surface, and no surface was seen where it was measured: Reflection.
    PastSeenExtent = 16,
    /// Weighed: a test from outside the crate weighed most.
    Weighed = 17,
    /// Weighed: no test weighed towards the class given; the landmark's
    /// glass-or-mirror prior decided.
    Prior = 18,
    /// Weighed: the point lies at the height of a floor or ceiling seen
    /// directly, which runs on behind the glass.
    LevelSurface = 19,
    /// Weighed: where the point was measured, beams seen through the same
    /// glass passed (confirmed transmissions): Reflection.
    SeenThrough = 20,
}

/// Every rule, in id order.
pub const RULES: [Rule; 21] = [
    Rule::Undecided,
    Rule::NoPane,
    Rule::InFront,
    Rule::WallEcho,
    Rule::OnPane,
    Rule::Band,
    Rule::RealRefuted,
    Rule::MirrorRefuted,
    Rule::Depth,
    Rule::FrameFreeSpace,
    Rule::EchoStrength,
    Rule::Support,
    Rule::DualReturn,
    Rule::ObliqueEcho,
    Rule::BehindMirror,
    Rule::SeenSurface,
    Rule::PastSeenExtent,
    Rule::Weighed,
    Rule::Prior,
    Rule::LevelSurface,
    Rule::SeenThrough,
];

impl Rule {
    /// The id written to the recording.
    pub fn id(self) -> u8 {
        self as u8
    }

    /// Short kebab-case name.
    pub fn name(self) -> &'static str {
        match self {
            Rule::Undecided => "undecided",
            Rule::NoPane => "no-pane",
            Rule::InFront => "in-front",
            Rule::WallEcho => "wall-echo",
            Rule::OnPane => "on-pane",
            Rule::Band => "band",
            Rule::RealRefuted => "real-refuted",
            Rule::MirrorRefuted => "mirror-refuted",
            Rule::Depth => "depth",
            Rule::FrameFreeSpace => "frame-free-space",
            Rule::EchoStrength => "echo-strength",
            Rule::Support => "support",
            Rule::DualReturn => "dual-return",
            Rule::ObliqueEcho => "oblique-echo",
            Rule::BehindMirror => "behind-mirror",
            Rule::SeenSurface => "seen-surface",
            Rule::PastSeenExtent => "past-seen-extent",
            Rule::Weighed => "weighed",
            Rule::Prior => "prior",
            Rule::LevelSurface => "level-surface",
            Rule::SeenThrough => "seen-through",
        }
    }
}

/// A frame's classes with the rule that decided each.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Decisions {
    /// One class per point, in the frame's point order.
    pub classes: Vec<Class>,
    /// The rule behind each class.
    pub rules: Vec<Rule>,
    /// The posterior probability of each point's class given the evidence
    /// weighed, in [0, 1]. For an unclassified point, the posterior of the
    /// more probable class, which fell short of the decision threshold.
    pub confidence: Vec<f32>,
}

/// Points counted by (rule, predicted class, 3DRef truth label).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RuleTally {
    /// `counts[rule][prediction id][label]`; labels above 6 count as 7.
    counts: [[[u64; 8]; 8]; RULES.len()],
}

impl Default for RuleTally {
    fn default() -> Self {
        Self {
            counts: [[[0; 8]; 8]; RULES.len()],
        }
    }
}

impl RuleTally {
    /// Count one frame's labels, classes and rules (same order).
    pub fn add(&mut self, labels: impl IntoIterator<Item = u8>, classes: &[Class], rules: &[Rule]) {
        for ((label, class), rule) in labels.into_iter().zip(classes).zip(rules) {
            self.counts[rule.id() as usize][(class.id() & 7) as usize][(label as usize).min(7)] +=
                1;
        }
    }

    /// Points predicted as each class, whatever their rule and label
    /// (unlabelled runs have only these counts).
    pub fn predicted(&self, class: Class) -> u64 {
        let c = (class.id() & 7) as usize;
        self.counts
            .iter()
            .map(|by_class| by_class[c].iter().sum::<u64>())
            .sum()
    }

    /// Points decided by `rule` as `class` with truth `label`.
    pub fn count(&self, rule: Rule, class: Class, label: u8) -> u64 {
        self.counts[rule.id() as usize][(class.id() & 7) as usize][(label as usize).min(7)]
    }

    /// The (rule, prediction) pairs that decided any point, with their
    /// counts per label.
    fn rows(&self) -> impl Iterator<Item = (Rule, Class, &[u64; 8])> {
        RULES.iter().flat_map(move |&rule| {
            [
                Class::Unclassified,
                Class::Normal,
                Class::Glass,
                Class::Reflection,
                Class::Obstacle,
            ]
            .into_iter()
            .map(move |class| {
                (
                    rule,
                    class,
                    &self.counts[rule.id() as usize][class.id() as usize],
                )
            })
            .filter(|(_, _, row)| row.iter().any(|&c| c > 0))
        })
    }

    /// A Markdown table: one row per (rule, prediction), the points by truth
    /// label in columns.
    pub fn table(&self) -> String {
        let names = crate::eval::metrics::LABEL_NAMES;
        let mut s = String::from("| rule | prediction |");
        for (id, name) in names.iter().enumerate() {
            s.push_str(&format!(" {name} ({id}) |"));
        }
        s.push_str("\n|---|---|");
        s.push_str(&"---:|".repeat(names.len()));
        s.push('\n');
        for (rule, class, row) in self.rows() {
            s.push_str(&format!("| {} | {} |", rule.name(), class.name()));
            for c in row {
                s.push_str(&format!(" {c} |"));
            }
            s.push('\n');
        }
        s
    }
}

/// Serialised as `{"rule/prediction": [count per label 0..7], ...}`.
impl Serialize for RuleTally {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let rows: Vec<_> = self.rows().collect();
        let mut map = serializer.serialize_map(Some(rows.len()))?;
        for (rule, class, row) in rows {
            map.serialize_entry(&format!("{}/{}", rule.name(), class.name()), row)?;
        }
        map.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_are_counted_by_prediction_and_label_and_listed_when_used() {
        let mut t = RuleTally::default();
        let d = Decisions {
            classes: vec![Class::Reflection, Class::Obstacle, Class::Reflection],
            rules: vec![Rule::Support, Rule::MirrorRefuted, Rule::Support],
            confidence: vec![1.0; 3],
        };
        t.add([5u8, 6, 6], &d.classes, &d.rules);
        assert_eq!(t.count(Rule::Support, Class::Reflection, 5), 1);
        assert_eq!(t.count(Rule::Support, Class::Reflection, 6), 1);
        assert_eq!(t.count(Rule::MirrorRefuted, Class::Obstacle, 6), 1);
        let table = t.table();
        assert!(
            table.contains("| support | reflection | 0 | 0 | 0 | 0 | 0 | 1 | 1 | 0 |"),
            "{table}"
        );
        assert!(!table.contains("dual-return"), "{table}");
        let json = serde_json::to_string(&t).unwrap();
        assert_eq!(
            json,
            r#"{"mirror-refuted/obstacle":[0,0,0,0,0,0,1,0],"support/reflection":[0,0,0,0,0,1,1,0]}"#
        );
        // Ids are distinct and in order.
        for (i, r) in RULES.iter().enumerate() {
            assert_eq!(r.id() as usize, i);
        }
    }
}
