//! `--patch-mode` and `--tessellation-error`: whether a scene's curved patches are traced
//! exactly or replaced by triangles before rendering, and the note that says which.
//!
//! Tessellation happens on the loaded scene (`crate::scene::patch::tessellate`), so the
//! renderer sees an ordinary triangle scene; the note records the triangles generated and
//! the time it took, and appears in the summary line and in `--stats` (`notes`).

use crate::cli::render_cmd::PatchMode;
use crate::cli::CommandError;
use crate::scene::patch::tessellate::tessellate_all;
use crate::scene::SceneDescription;

/// Applies `mode` to `scene`'s patches (nothing for a scene without patches).
pub fn apply(
    scene: &mut SceneDescription,
    mode: PatchMode,
    tessellation_error: f32,
) -> Result<(), CommandError> {
    if !(tessellation_error.is_finite() && tessellation_error > 0.0) {
        return Err(CommandError::bad_input(format!(
            "--tessellation-error {tessellation_error} must be a positive distance"
        )));
    }
    if scene.patches.is_empty() {
        return Ok(());
    }
    match mode {
        PatchMode::Exact => scene.notes.push(format!(
            "{} curved patches traced exactly",
            scene.patches.len()
        )),
        PatchMode::Tessellate => {
            let report = tessellate_all(&mut scene.patches, &mut scene.meshes, tessellation_error);
            scene.notes.push(format!(
                "{} curved patches tessellated within {tessellation_error}: {} triangles in {:.4} s",
                report.patches, report.triangles, report.seconds
            ));
        }
    }
    Ok(())
}
