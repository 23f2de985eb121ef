//! Which passes a scene needs, and why (../shared/DESIGN.md, rule 4: model only what the
//! scene requires). Pure CPU: `prism passes SCENE` prints this without touching the GPU, and
//! the renderer creates and records exactly these passes. The list is the frame recipe's
//! ([`crate::technique::recipe`]): each technique plans its own passes.
use crate::scene::Scene;
pub use crate::technique::{has, PlannedPass};

/// The ordered pass list for `scene`.
pub fn plan(scene: &Scene) -> Vec<PlannedPass> {
    crate::technique::recipe(scene).passes
}
