//! Wavefront OBJ + MTL meshes (via `tobj`): triangulated, one index per vertex, with
//! materials mapped onto the Whitted material model.
//!
//! MTL mapping: `Kd` base colour, `map_Kd` base-colour texture (sRGB), `Ks` (its largest
//! component) specular weight, `Ns` shininess, `Ke` emission, `Ni` index of refraction
//! (values <= 0, which exporters write for "unset", mean 1.5), `d` / `Tr` transparency ->
//! transmission weight, `map_d` alpha texture (linear, cut-out at 0.5), `illum 3` mirror
//! (reflectivity = the largest `Ks` component, 1 when `Ks` is absent), `illum 4/6/7` glass.
//! OBJ texture coordinates have v pointing up; they are stored as `t = 1 - v`
//! (OpenImageIO convention, t down).

use std::io::Cursor;
use std::path::Path;

use glam::{Affine2, Vec2, Vec3};

use super::error::SceneError;
use super::files::Files;
use crate::scene::{
    ColorSpace, Material, SceneDescription, TextureBinding, TextureDesc, TriangleMesh, WrapMode,
};

/// Loads the OBJ file at `path` (and its MTL libraries and texture references) as a
/// scene part: meshes, materials and textures, no camera or lights.
pub(crate) fn load_obj(files: &Files, path: &Path) -> Result<SceneDescription, SceneError> {
    let label = path.display().to_string();
    let bytes = files.read(path)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let local = files.with_base(dir);
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |mtl: &Path| {
            let mtl_path = local.resolve(&mtl.to_string_lossy().replace('\\', "/"));
            let data = local
                .read(&mtl_path)
                .map_err(|_| tobj::LoadError::OpenFileFailed)?;
            tobj::load_mtl_buf(&mut Cursor::new(data))
        })
        .map_err(|e| SceneError::invalid(&label, format!("OBJ parse error: {e}")))?;

    let mut part = SceneDescription {
        source: label.clone(),
        ..Default::default()
    };
    match materials {
        Ok(list) => {
            for m in &list {
                let material = convert_material(m, &local, &mut part.textures, &label)?;
                part.materials.push(material);
            }
        }
        Err(e) => part.notes.push(format!(
            "{label}: material library not loaded ({e}): using a default material"
        )),
    }

    let mut default_material = None;
    for model in models {
        let mesh = convert_mesh(&model, &label, &mut part.notes)?;
        let Some(mut mesh) = mesh else { continue };
        mesh.material = match model.mesh.material_id {
            Some(id) if id < part.materials.len() => id,
            _ => *default_material.get_or_insert_with(|| {
                part.materials.push(Material {
                    name: "default".into(),
                    ..Material::default()
                });
                part.materials.len() - 1
            }),
        };
        part.meshes.push(mesh);
    }
    if part.meshes.is_empty() {
        return Err(SceneError::invalid(&label, "no triangles in the OBJ file"));
    }
    Ok(part)
}

/// One `tobj` model as a triangle mesh, or `None` when it has no triangles.
fn convert_mesh(
    model: &tobj::Model,
    label: &str,
    notes: &mut Vec<String>,
) -> Result<Option<TriangleMesh>, SceneError> {
    let m = &model.mesh;
    let positions: Vec<Vec3> = m
        .positions
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect();
    let triangles: Vec<[u32; 3]> = m
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    if triangles.is_empty() || positions.is_empty() {
        return Ok(None);
    }
    let mut normals: Vec<Vec3> = if m.normals.len() == m.positions.len() {
        m.normals
            .chunks_exact(3)
            .map(|n| Vec3::new(n[0], n[1], n[2]))
            .collect()
    } else {
        Vec::new()
    };
    // OBJ's v points up; OpenImageIO's t points down.
    let st: Vec<Vec2> = if m.texcoords.len() / 2 == positions.len() {
        m.texcoords
            .chunks_exact(2)
            .map(|uv| Vec2::new(uv[0], 1.0 - uv[1]))
            .collect()
    } else {
        Vec::new()
    };
    if let Some(bad) = triangles
        .iter()
        .flatten()
        .find(|&&i| i as usize >= positions.len())
    {
        return Err(SceneError::invalid(
            label,
            format!(
                "object '{}': vertex index {bad} out of range ({} vertices)",
                model.name,
                positions.len()
            ),
        ));
    }
    let repaired = repair_zero_normals(&positions, &triangles, &mut normals);
    if repaired > 0 {
        notes.push(format!(
            "{label}: object '{}': {repaired} zero-length normals replaced by the surrounding faces' normal",
            model.name
        ));
    }
    Ok(Some(TriangleMesh {
        name: model.name.clone(),
        positions,
        normals,
        st,
        triangles,
        material: 0,
    }))
}

/// Replaces zero-length vertex normals (exporters write `vn 0 0 0`) by the area-weighted
/// normal of the triangles around the vertex; drops all normals (flat shading) when that is
/// zero too. Returns how many normals were replaced.
fn repair_zero_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    normals: &mut Vec<Vec3>,
) -> usize {
    let is_zero = |n: &Vec3| n.length_squared() == 0.0;
    let count = normals.iter().filter(|n| is_zero(n)).count();
    if count == 0 {
        return 0;
    }
    let mut face_sum = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let area_normal = (b - a).cross(c - a);
        for &i in t {
            face_sum[i as usize] += area_normal;
        }
    }
    for (n, sum) in normals.iter_mut().zip(&face_sum) {
        if is_zero(n) {
            *n = sum.normalize_or_zero();
        }
    }
    if normals.iter().any(is_zero) {
        normals.clear();
    }
    count
}

fn convert_material(
    m: &tobj::Material,
    files: &Files,
    textures: &mut Vec<TextureDesc>,
    label: &str,
) -> Result<Material, SceneError> {
    let mut material = Material {
        name: m.name.clone(),
        ..Material::default()
    };
    if let Some(kd) = m.diffuse {
        material.base_color = Vec3::from(kd);
    }
    let ks = m.specular.map(|ks| Vec3::from(ks).max_element());
    material.specular = ks.unwrap_or(0.0);
    if let Some(ns) = m.shininess {
        material.shininess = ns;
    }
    if let Some(ke) = m.emissive {
        material.emission = Vec3::from(ke);
    }
    if let Some(ni) = m.optical_density.filter(|&ni| ni > 0.0) {
        material.ior = ni;
    }
    let transparency = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => 1.0 - d,
        (None, Some(tr)) => tr
            .split_whitespace()
            .next()
            .and_then(|v| v.parse::<f32>().ok())
            .ok_or_else(|| {
                SceneError::invalid(label, format!("material '{}': bad Tr value '{tr}'", m.name))
            })?,
        (None, None) => 0.0,
    };
    material.transmission = transparency.clamp(0.0, 1.0);
    match m.illumination_model {
        Some(3) => {
            material.mirror = ks.filter(|&k| k > 0.0).unwrap_or(1.0);
            material.specular = 0.0;
        }
        Some(4 | 6 | 7) => material.transmission = 1.0,
        _ => {}
    }
    if let Some(file) = &m.diffuse_texture {
        let index = add_texture(files, textures, file, ColorSpace::Srgb, label)?;
        material.base_color_texture = Some(TextureBinding {
            texture: index,
            transform: Affine2::IDENTITY,
        });
    }
    if let Some(file) = &m.dissolve_texture {
        let index = add_texture(files, textures, file, ColorSpace::Linear, label)?;
        material.alpha_texture = Some(TextureBinding {
            texture: index,
            transform: Affine2::IDENTITY,
        });
        material.alpha_cutoff = Some(0.5);
    }
    Ok(material)
}

/// Adds (or reuses) a texture for an MTL map statement. Options such as `-s 1 1 1` before
/// the file name are skipped: the file name is the last word. Windows separators (`.\\a.jpg`,
/// common in exported MTL files) are read as `/`.
fn add_texture(
    files: &Files,
    textures: &mut Vec<TextureDesc>,
    statement: &str,
    color_space: ColorSpace,
    context: &str,
) -> Result<usize, SceneError> {
    let name = statement
        .split_whitespace()
        .last()
        .unwrap_or(statement)
        .replace('\\', "/");
    if let Some(i) = textures
        .iter()
        .position(|t| t.name == name && t.color_space == color_space)
    {
        return Ok(i);
    }
    let source = files
        .texture_source(&files.resolve(&name))
        .map_err(|e| SceneError::invalid(context, format!("texture '{name}': {e}")))?;
    textures.push(TextureDesc {
        name,
        source,
        color_space,
        wrap_s: WrapMode::Periodic,
        wrap_t: WrapMode::Periodic,
    });
    Ok(textures.len() - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn write(dir: &Path, name: &str, text: &str) {
        fs::write(dir.join(name), text).unwrap();
    }

    const QUAD: &str = "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl red\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";

    #[test]
    fn quads_triangulate_and_v_flips_to_t() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        write(
            dir.path(),
            "quad.mtl",
            "newmtl red\nKd 1 0 0\nKs 0.5 0.2 0.1\nNs 50\nmap_Kd tex.png\n",
        );
        write(dir.path(), "tex.png", "not decoded here");
        let files = Files::disk(dir.path());
        let part = load_obj(&files, &dir.path().join("quad.obj")).unwrap();
        assert_eq!(part.meshes.len(), 1);
        let mesh = &part.meshes[0];
        assert_eq!(mesh.triangles.len(), 2);
        assert_eq!(mesh.normals.len(), mesh.positions.len());
        for (p, st) in mesh.positions.iter().zip(&mesh.st) {
            // vt equals the position's xy here, so t must be 1 - y.
            assert_eq!(st.x, p.x);
            assert_eq!(st.y, 1.0 - p.y);
        }
        let m = &part.materials[mesh.material];
        assert_eq!(m.base_color, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(m.specular, 0.5);
        assert_eq!(m.shininess, 50.0);
        let binding = m.base_color_texture.as_ref().unwrap();
        assert_eq!(part.textures[binding.texture].color_space, ColorSpace::Srgb);
    }

    #[test]
    fn illum_models_map_to_mirror_and_glass() {
        let dir = tempfile::tempdir().unwrap();
        let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\nusemtl c\nf 2 1 3\n";
        write(dir.path(), "m.obj", obj);
        write(
            dir.path(),
            "m.mtl",
            "newmtl a\nillum 3\nKs 0.9 0.9 0.9\nnewmtl b\nillum 7\nNi 1.33\nnewmtl c\nd 0.25\nKe 2 2 2\n",
        );
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("m.obj")).unwrap();
        let by_name = |n: &str| part.materials.iter().find(|m| m.name == n).unwrap();
        assert_eq!(by_name("a").mirror, 0.9);
        assert_eq!(by_name("b").transmission, 1.0);
        assert_eq!(by_name("b").ior, 1.33);
        assert_eq!(by_name("c").transmission, 0.75);
        assert_eq!(by_name("c").emission, Vec3::splat(2.0));
    }

    #[test]
    fn missing_mtl_gives_default_material_and_note() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap();
        assert_eq!(part.materials.len(), 1);
        assert_eq!(part.materials[0].base_color, Material::default().base_color);
        assert!(
            part.notes.iter().any(|n| n.contains("material library")),
            "{:?}",
            part.notes
        );
    }

    #[test]
    fn missing_texture_file_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        write(dir.path(), "quad.mtl", "newmtl red\nmap_Kd nothere.png\n");
        let err = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap_err();
        assert!(err.to_string().contains("nothere.png"), "{err}");
    }

    #[test]
    fn zero_normals_are_repaired_from_faces() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let mut normals = vec![Vec3::ZERO, Vec3::Z, Vec3::Z];
        assert_eq!(
            repair_zero_normals(&positions, &[[0, 1, 2]], &mut normals),
            1
        );
        assert_eq!(normals[0], Vec3::Z);
        // A degenerate triangle cannot supply a normal: fall back to flat shading.
        let mut normals = vec![Vec3::ZERO; 3];
        repair_zero_normals(&[Vec3::ZERO; 3], &[[0, 1, 2]], &mut normals);
        assert!(normals.is_empty());
    }

    #[test]
    fn empty_and_malformed_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "empty.obj", "");
        write(
            dir.path(),
            "bad.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
        );
        let files = Files::disk(dir.path());
        assert!(load_obj(&files, &dir.path().join("empty.obj")).is_err());
        let err = load_obj(&files, &dir.path().join("bad.obj"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("bad.obj"), "{err}");
    }
}
