//! Coated and tinted glass: the office of [`super::office`] with
//! solar-control glazing whose reflectance is close to its transmittance,
//! and a coated partition into the next room, so that what lies behind the
//! glass and what the glass reflects come back about equally strong.

use super::draft::{Draft, GlassStyle};
use super::office::draw_window_room;
use super::SceneFamily;

/// Coated and tinted glass.
pub struct CoatedGlass;

impl SceneFamily for CoatedGlass {
    fn name(&self) -> &'static str {
        "coated-glass"
    }

    fn description(&self) -> &'static str {
        "an office with coated or tinted window walls and a coated partition: reflectance close to transmittance"
    }

    fn draw(&self, d: &mut Draft) -> Result<(), String> {
        draw_window_room(d, GlassStyle::Coated, true)
    }
}
