//! The mixed family: the layout of any other family, with the glass of
//! either kind, so that layouts and materials meet in combinations no
//! single family draws.

use super::draft::{Draft, GlassStyle};
use super::{SceneFamily, FAMILIES};

/// A mix of every family.
pub struct Mixed;

impl SceneFamily for Mixed {
    fn name(&self) -> &'static str {
        "mixed"
    }

    fn description(&self) -> &'static str {
        "the layout of any family with clear or coated glass drawn independently"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        let others: Vec<_> = FAMILIES
            .iter()
            .filter(|f| f.name() != self.name())
            .collect();
        let family = others[d.int(0, others.len() - 1)];
        d.style = Some(if d.chance(0.5) {
            GlassStyle::Clear
        } else {
            GlassStyle::Coated
        });
        family.draw(d)
    }
}
