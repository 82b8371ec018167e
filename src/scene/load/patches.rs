//! The TOML scene's curved surfaces: `[[patch]]`, `[[bezier_triangle]]` and `[[patch_file]]`
//! (documented in `docs/scene-format.md`, "Curved surfaces").
//!
//! Every surface becomes a bicubic [`BezierPatch`] here (`crate::scene::patch::basis`).
//! Bad control data is refused with the TOML location of the offending table: a wrong number
//! of control points, a degree outside 1 to 3, a fully degenerate patch (`nan` and `inf`
//! are already refused by the number parser), and in a `.bpt` file any malformed or
//! non-finite number, named by its line.

use glam::{Vec2, Vec3};
use serde::Deserialize;
use toml::Spanned;

use super::error::SceneError;
use super::files::Files;
use super::merge::{Placement, Transform};
use super::toml_format::{v3, Located, Num, Scale, V3};
use crate::scene::patch::basis::{
    elevate_to_bicubic, hermite_to_bezier, lagrange_to_bezier, triangle_to_bezier,
};
use crate::scene::patch::bpt::parse_bpt;
use crate::scene::patch::height::HeightPatch;
use crate::scene::patch::BezierPatch;
use crate::scene::SceneDescription;

/// How a `[[patch]]`'s control points define its surface.
#[derive(Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawPatchKind {
    /// Bezier control points (of degree `degree`, bicubic by default).
    #[default]
    Bezier,
    /// A cubic Hermite (Catmull-Rom) rectangle through the inner four of 16 points.
    Hermite,
    /// The bicubic Lagrange rectangle through 16 points at u, v = 0, 1/3, 2/3, 1.
    Lagrange,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPatch {
    #[serde(default)]
    kind: RawPatchKind,
    /// Bezier degree in u and v, each 1 to 3 (default `[3, 3]`).
    degree: Option<Spanned<[usize; 2]>>,
    control_points: Spanned<Vec<V3>>,
    /// Texture coordinates at the corners (u, v) = (0, 0), (1, 0), (0, 1), (1, 1).
    st: Option<[[Num; 2]; 4]>,
    material: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawBezierTriangle {
    control_points: Spanned<Vec<V3>>,
    material: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawPatchFile {
    file: Spanned<String>,
    material: Option<Spanned<String>>,
    translate: Option<V3>,
    rotate: Option<V3>,
    scale: Option<Spanned<Scale>>,
}

/// How a `[[height_patch]]` is traced.
#[derive(Deserialize, Clone, Copy, Debug, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub(super) enum RawHeightTrace {
    /// Ray marching at `march_step` (`crate::scene::patch::height`).
    #[default]
    March,
    /// The same surface as a bicubic Bezier patch, traced exactly.
    Exact,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHeightPatch {
    /// `[x0, z0]`, the corner at u = v = 0.
    min: Spanned<[Num; 2]>,
    /// `[x1, z1]`, the corner at u = v = 1.
    max: [Num; 2],
    /// 16 heights, row by row (x fastest).
    heights: Spanned<Vec<Num>>,
    /// Sample spacing of the march, world units (default [`DEFAULT_MARCH_STEP`]).
    march_step: Option<Num>,
    #[serde(default)]
    trace: RawHeightTrace,
    material: Option<Spanned<String>>,
}

/// A height patch's march step when the scene gives none, world units.
pub const DEFAULT_MARCH_STEP: f32 = 0.01;

/// Resolves a material name (or the default material) to its index.
pub(super) type MaterialLookup<'m> =
    dyn FnMut(&mut SceneDescription, &Option<Spanned<String>>) -> Result<usize, SceneError> + 'm;

fn points(raw: &[V3]) -> Vec<Vec3> {
    raw.iter().map(|p| v3(*p)).collect()
}

fn checked(
    loc: &Located,
    at: &Spanned<Vec<V3>>,
    what: &str,
    patch: BezierPatch,
) -> Result<BezierPatch, SceneError> {
    match patch.problem() {
        Some(problem) => Err(loc.at(at, format!("{what}: {problem}"))),
        None => Ok(patch),
    }
}

/// Adds the `[[patch]]`, `[[bezier_triangle]]` and `[[patch_file]]` surfaces to `scene`.
pub(super) fn build_patches(
    scene: &mut SceneDescription,
    patches: &[RawPatch],
    triangles: &[RawBezierTriangle],
    patch_files: &[RawPatchFile],
    files: &Files,
    loc: &Located,
    material: &mut MaterialLookup,
) -> Result<(), SceneError> {
    for raw in patches {
        let given = points(raw.control_points.get_ref());
        let control = match raw.kind {
            RawPatchKind::Bezier => {
                let [du, dv] = raw.degree.as_ref().map_or([3, 3], |d| *d.get_ref());
                if !(1..=3).contains(&du) || !(1..=3).contains(&dv) {
                    let at = raw
                        .degree
                        .as_ref()
                        .expect("only a written degree can be wrong");
                    return Err(loc.at(
                        at,
                        format!("patch degree [{du}, {dv}]: each must be 1 to 3"),
                    ));
                }
                elevate_to_bicubic(du, dv, &given).ok_or_else(|| {
                    loc.at(
                        &raw.control_points,
                        format!(
                            "a Bezier patch of degree [{du}, {dv}] needs {} control points, not {}",
                            (du + 1) * (dv + 1),
                            given.len()
                        ),
                    )
                })?
            }
            kind => {
                if let Some(degree) = &raw.degree {
                    return Err(loc.at(degree, "only Bezier patches take a degree"));
                }
                let grid: [Vec3; 16] = given.as_slice().try_into().map_err(|_| {
                    loc.at(
                        &raw.control_points,
                        format!(
                            "a {kind:?} patch needs 16 control points, not {}",
                            given.len()
                        )
                        .to_lowercase(),
                    )
                })?;
                if kind == RawPatchKind::Hermite {
                    hermite_to_bezier(&grid)
                } else {
                    lagrange_to_bezier(&grid)
                }
            }
        };
        let corner_st = raw.st.map(|c| c.map(|[s, t]| Vec2::new(s.0, t.0)));
        let index = material(scene, &raw.material)?;
        let patch = BezierPatch {
            control,
            corner_st,
            material: index,
        };
        scene
            .patches
            .push(checked(loc, &raw.control_points, "patch", patch)?);
    }

    for raw in triangles {
        let given = points(raw.control_points.get_ref());
        let control: [Vec3; 10] = given.as_slice().try_into().map_err(|_| {
            loc.at(
                &raw.control_points,
                format!(
                    "a cubic Bezier triangle needs 10 control points, not {}",
                    given.len()
                ),
            )
        })?;
        let index = material(scene, &raw.material)?;
        let patch = BezierPatch {
            control: triangle_to_bezier(&control),
            corner_st: None,
            material: index,
        };
        scene
            .patches
            .push(checked(loc, &raw.control_points, "Bezier triangle", patch)?);
    }

    for raw in patch_files {
        let placement = Placement {
            translate: raw.translate.map_or(Vec3::ZERO, v3),
            rotate_degrees: raw.rotate.map_or(Vec3::ZERO, v3),
            scale: raw.scale.as_ref().map_or(Vec3::ONE, |s| s.get_ref().0),
        };
        let transform = Transform::new(placement.matrix()).ok_or_else(|| match &raw.scale {
            Some(s) => loc.at(s, "patch file scale must not be zero"),
            None => loc.at(&raw.file, "patch file transform is singular"),
        })?;
        let path = files.resolve(raw.file.get_ref());
        let label = path.display().to_string();
        let bytes = files.read(&path).map_err(|e| match e {
            SceneError::Unreadable { reason, .. } => loc.at(
                &raw.file,
                format!("cannot read patch file '{label}': {reason}"),
            ),
            other => other,
        })?;
        let text = String::from_utf8(bytes)
            .map_err(|_| SceneError::invalid(&label, "a patch file must be text (UTF-8)"))?;
        let grids = parse_bpt(&text).map_err(|message| SceneError::invalid(&label, message))?;
        let index = material(scene, &raw.material)?;
        for (number, grid) in grids.into_iter().enumerate() {
            let patch = BezierPatch {
                control: grid.map(|p| transform.point(p)),
                corner_st: None,
                material: index,
            };
            if let Some(problem) = patch.problem() {
                return Err(SceneError::invalid(
                    &label,
                    format!("patch {number}: {problem}"),
                ));
            }
            scene.patches.push(patch);
        }
    }
    Ok(())
}

/// Adds the `[[height_patch]]` surfaces to `scene`: marched ones to `height_patches`, exact
/// ones to `patches` as the same surface in Bezier form.
pub(super) fn build_height_patches(
    scene: &mut SceneDescription,
    raw_patches: &[RawHeightPatch],
    loc: &Located,
    material: &mut MaterialLookup,
) -> Result<(), SceneError> {
    for raw in raw_patches {
        let heights: [f32; 16] = raw
            .heights
            .get_ref()
            .iter()
            .map(|h| h.0)
            .collect::<Vec<f32>>()
            .try_into()
            .map_err(|given: Vec<f32>| {
                loc.at(
                    &raw.heights,
                    format!("a height patch needs 16 heights, not {}", given.len()),
                )
            })?;
        let (min, max) = (raw.min.get_ref(), &raw.max);
        let (x0, z0, x1, z1) = (min[0].0, min[1].0, max[0].0, max[1].0);
        let patch = HeightPatch {
            min: Vec2::new(x0, z0),
            max: Vec2::new(x1, z1),
            heights,
            material: material(scene, &raw.material)?,
            march_step: raw.march_step.as_ref().map_or(DEFAULT_MARCH_STEP, |s| s.0),
        };
        if let Some(problem) = patch.problem() {
            return Err(loc.at(&raw.min, format!("height patch: {problem}")));
        }
        match raw.trace {
            RawHeightTrace::March => scene.height_patches.push(patch),
            RawHeightTrace::Exact => scene.patches.push(patch.to_bezier()),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::scene::load::files::Files;
    use crate::scene::load::toml_format::parse;
    use std::path::Path;

    fn parse_here(text: &str) -> Result<crate::scene::SceneDescription, String> {
        let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
        parse(text, &Files::disk(&assets), "t.toml").map_err(|e| e.to_string())
    }

    fn grid(z: impl Fn(usize, usize) -> f32) -> String {
        let points: Vec<String> = (0..16)
            .map(|k| format!("[{}, {}, {}]", k % 4, k / 4, z(k % 4, k / 4)))
            .collect();
        format!("[{}]", points.join(", "))
    }

    #[test]
    fn the_three_kinds_load_as_bicubic_patches() {
        let g = grid(|i, j| (i * j) as f32 * 0.1);
        for kind in ["bezier", "hermite", "lagrange"] {
            let text = format!("[[patch]]\nkind = \"{kind}\"\ncontrol_points = {g}\n");
            let scene = parse_here(&text).unwrap();
            assert_eq!(scene.patches.len(), 1, "{kind}");
        }
        let text = "[[patch]]\ndegree = [1, 1]\ncontrol_points = [[0,0,0],[1,0,0],[0,1,0],[1,1,1]]\nst = [[0,0],[2,0],[0,2],[2,2]]\n";
        let scene = parse_here(text).unwrap();
        assert_eq!(scene.patches[0].control[15], glam::Vec3::new(1.0, 1.0, 1.0));
        assert!(scene.patches[0].corner_st.is_some());
    }

    #[test]
    fn the_teapot_file_loads_placed() {
        let text =
            "[[patch_file]]\nfile = \"../models/teapot.bpt\"\ntranslate = [0, 1, 0]\nscale = 2\n";
        let scene = parse_here(text).unwrap();
        assert_eq!(scene.patches.len(), 32);
        assert_eq!(scene.patches[0].control[0], glam::Vec3::new(2.8, 1.0, 4.8));
    }

    #[test]
    fn bad_control_data_is_refused_with_its_place() {
        let e = parse_here("[[patch]]\ncontrol_points = [[0,0,0],[1,0,0]]\n").unwrap_err();
        assert!(
            e.starts_with("t.toml:2:18: a Bezier patch of degree [3, 3] needs 16"),
            "{e}"
        );
        let e =
            parse_here("[[patch]]\nkind = 'hermite'\ncontrol_points = [[0,0,0]]\n").unwrap_err();
        assert!(
            e.contains("hermite patch needs 16 control points, not 1"),
            "{e}"
        );
        let nan = grid(|_, _| 0.0).replacen("0]", "nan]", 1);
        let e = parse_here(&format!("[[patch]]\ncontrol_points = {nan}\n")).unwrap_err();
        assert!(e.contains("not finite"), "{e}");
        let flat_line: Vec<String> = (0..16).map(|k| format!("[{k}, {k}, 0]")).collect();
        let text = format!("[[patch]]\ncontrol_points = [{}]\n", flat_line.join(","));
        let e = parse_here(&text).unwrap_err();
        assert!(e.contains("fully degenerate"), "{e}");
        let e = parse_here("[[bezier_triangle]]\ncontrol_points = [[0,0,0]]\n").unwrap_err();
        assert!(e.contains("needs 10 control points, not 1"), "{e}");
        let e = parse_here("[[patch]]\nkind = 'nurbs'\ncontrol_points = []\n").unwrap_err();
        assert!(e.contains("unknown variant"), "{e}");
        let e = parse_here("[[patch_file]]\nfile = 'missing.bpt'\n").unwrap_err();
        assert!(e.contains("cannot read patch file"), "{e}");
    }

    const HEIGHTS: &str = "[0,1,2,3, 0,1,2,3, 0,1,2,3, 0,1,2,3]";

    #[test]
    fn height_patches_load_marched_or_exact() {
        let text = format!("[[height_patch]]\nmin = [-1, -2]\nmax = [1, 2]\nheights = {HEIGHTS}\n");
        let scene = parse_here(&text).unwrap();
        assert_eq!(scene.height_patches.len(), 1);
        assert!(scene.patches.is_empty());
        let patch = &scene.height_patches[0];
        assert_eq!(patch.march_step, super::DEFAULT_MARCH_STEP);
        assert_eq!(patch.heights[7], 3.0);
        let exact = format!("{text}trace = 'exact'\nmarch_step = 0.5\n");
        let scene = parse_here(&exact).unwrap();
        assert!(scene.height_patches.is_empty());
        assert_eq!(scene.patches[0].control[15], glam::Vec3::new(1.0, 3.0, 2.0));
    }

    #[test]
    fn bad_height_patches_are_refused_with_their_place() {
        let e = parse_here("[[height_patch]]\nmin = [0, 0]\nmax = [1, 1]\nheights = [1, 2]\n")
            .unwrap_err();
        assert!(
            e.starts_with("t.toml:4:11: a height patch needs 16 heights, not 2"),
            "{e}"
        );
        let e = parse_here(&format!(
            "[[height_patch]]\nmin = [0, 0]\nmax = [0, 1]\nheights = {HEIGHTS}\n"
        ))
        .unwrap_err();
        assert!(e.contains("is empty"), "{e}");
        let e = parse_here(&format!(
            "[[height_patch]]\nmin = [0, 0]\nmax = [1, 1]\nheights = {HEIGHTS}\nmarch_step = 0\n"
        ))
        .unwrap_err();
        assert!(
            e.contains("march_step 0 must be a positive distance"),
            "{e}"
        );
    }
}
