//! Wavefront OBJ + MTL meshes (via `tobj`): triangulated, one index per vertex, with
//! materials mapped onto the Whitted material model.
//!
//! MTL mapping: `Kd` base colour, `map_Kd` base-colour texture (sRGB), `Ks` (its largest
//! component) specular weight, `Ns` shininess, `Ke` emission, `Ni` index of refraction
//! (values <= 0, which exporters write for "unset", mean 1.5), `d` / `Tr` transparency ->
//! transmission weight, `map_d` alpha texture (linear, cut-out at 0.5), `illum 3` mirror
//! (reflectivity = the largest `Ks` component, 1 when `Ks` is absent), `illum 4/6/7` glass.
//! PBR extension (as Blender and three.js write it): `Pr` roughness, `Pm` metalness (either
//! selects the metallic-roughness model), `map_Pr` and `map_Pm` greyscale maps (or one
//! packed texture when they name the same file: green = roughness, blue = metalness), `map_Ke` emission texture (sRGB), `norm` /
//! `map_Bump` / `bump` tangent-space normal map with `-bm` as its scale. Map options come
//! before the file name (`MapStatement`): `-s`/`-o` transform the texture coordinates,
//! `-clamp on` clamps; the file name is the rest of the line. A line ending in `\\`
//! continues on the next.
//! OBJ texture coordinates have v pointing up; they are stored as `t = 1 - v`
//! (OpenImageIO convention, t down).
//!
//! Before `tobj` parses anything, the OBJ and MTL lines are decoded leniently
//! (`obj_text`), checked where `tobj` cannot say where a problem lies (face references,
//! colours, names) and rewritten one for one into the form `tobj` accepts, so every error
//! names the file and line it comes from.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use glam::{Affine2, Vec2, Vec3};

use super::error::SceneError;
use super::files::{note_not_loaded, Files};
use super::normals::repair_zero_normals;
use super::obj_text::{decode_lines, excerpt, join_continued_lines, LineCountingReader};
use super::polygon;
use crate::scene::{
    ClassicModel, ColorSpace, Material, MaterialModel, MetallicRoughnessModel, SceneDescription,
    TextureBinding, TextureDesc, TriangleMesh, WrapMode,
};

/// Loads the OBJ file at `path` (and its MTL libraries and texture references) as a
/// scene part: meshes, materials and textures, no camera or lights.
pub(crate) fn load_obj(files: &Files, path: &Path) -> Result<SceneDescription, SceneError> {
    let label = path.display().to_string();
    let bytes = files.read(path)?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let local = files.with_base(dir);
    let mut part = SceneDescription {
        source: label.clone(),
        ..Default::default()
    };
    let mut lines = decode_lines(&bytes);
    join_continued_lines(&mut lines);
    let prepared = prepare_obj(lines, &local, &label, &mut part.notes)?;
    // Faces come whole (`face_arities`) and are triangulated here: `tobj` fans them, which
    // covers area outside a concave face.
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let text = prepared.lines.join("\n");
    let mut reader = LineCountingReader::new(&text);
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |mtl: &Path| {
        match prepared.libraries.get(&*mtl.to_string_lossy()) {
            Some(Some(library)) => library.parsed.clone(),
            // Unreadable: already recorded in the notes.
            Some(None) | None => Err(tobj::LoadError::OpenFileFailed),
        }
    })
    .map_err(|e| {
        let line = reader.line();
        let written = prepared
            .lines
            .get(line.wrapping_sub(1))
            .map_or("", String::as_str);
        SceneError::invalid(
            &label,
            format!("line {line}: {e} ('{}')", excerpt(written, 60)),
        )
    })?;

    // Without any readable library `tobj` reports the open failure, already noted.
    for (m, origin) in materials.unwrap_or_default().iter().zip(&prepared.origins) {
        let material = convert_material(m, origin, &local, &mut part.textures, &mut part.notes)?;
        part.materials.push(material);
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

/// An OBJ file's lines made ready for `tobj`, with its MTL libraries already read.
struct PreparedObj {
    /// The file's lines, one for one (so `tobj`'s line is the file's line), with `usemtl` and
    /// `mtllib` statements written the one way `tobj` reads them, vertex colours dropped and
    /// `usemtl` without a name turned into a name no library defines.
    lines: Vec<String>,
    /// Each `mtllib` file name as written, with its library (`None`: unreadable, noted).
    libraries: HashMap<String, Option<Library>>,
    /// Where each material `tobj` will return was written, in `tobj`'s order: the libraries'
    /// materials, one `mtllib` statement after the other.
    origins: Vec<MaterialOrigin>,
}

/// One MTL library, parsed.
struct Library {
    /// What `tobj` made of it (always `Ok`: a library it refuses is an error).
    parsed: tobj::MTLLoadResult,
    /// The names its materials can be used by.
    names: HashSet<String>,
    origins: Vec<MaterialOrigin>,
}

/// Where a material was written: its MTL file, its `newmtl` line and the line of each of its
/// statements (by keyword), for messages.
#[derive(Clone)]
struct MaterialOrigin {
    file: String,
    newmtl_line: usize,
    statement_lines: HashMap<String, usize>,
}

impl MaterialOrigin {
    /// The line of `keyword` in this material (its `newmtl` line if absent).
    fn line_of(&self, keyword: &str) -> usize {
        self.statement_lines
            .get(keyword)
            .copied()
            .unwrap_or(self.newmtl_line)
    }
}

/// The first word of `line` and the rest of it, trimmed.
fn split_keyword(line: &str) -> (&str, &str) {
    let line = line.trim();
    match line.find(char::is_whitespace) {
        Some(i) => (&line[..i], line[i..].trim()),
        None => (line, ""),
    }
}

/// Checks and rewrites the OBJ lines (see [`PreparedObj`]) and reads the MTL libraries.
/// Face indices are checked here, where the line is known: `tobj` checks them only when it
/// assembles a mesh, lines later.
fn prepare_obj(
    mut lines: Vec<String>,
    files: &Files,
    label: &str,
    notes: &mut Vec<String>,
) -> Result<PreparedObj, SceneError> {
    let at = |number: usize, message: String| {
        SceneError::invalid(label, format!("line {number}: {message}"))
    };
    // Totals first: `tobj` accepts faces that refer to vertices written after them.
    let mut totals = [0usize; 3];
    for line in &lines {
        match split_keyword(line).0 {
            "v" => totals[0] += 1,
            "vt" => totals[1] += 1,
            "vn" => totals[2] += 1,
            _ => {}
        }
    }
    let mut so_far = [0usize; 3];
    let mut libraries: HashMap<String, Option<Library>> = HashMap::new();
    let mut origins = Vec::new();
    let mut unnamed_usemtl = Vec::new();
    let mut unknown_noted: Vec<String> = Vec::new();
    for (index, line) in lines.iter_mut().enumerate() {
        let number = index + 1;
        let (keyword, rest) = split_keyword(line);
        match keyword {
            "v" => {
                so_far[0] += 1;
                // `v x y z r g b`: the colours are not used, and `tobj` refuses a file where
                // only some vertices have them.
                let words: Vec<&str> = rest.split_whitespace().collect();
                if words.len() == 6 {
                    *line = format!("v {} {} {}", words[0], words[1], words[2]);
                }
            }
            "vt" => so_far[1] += 1,
            "vn" => so_far[2] += 1,
            "f" => check_face(rest, &so_far, &totals).map_err(|m| at(number, m))?,
            "mtllib" => {
                let name = rest.to_owned();
                if !libraries.contains_key(&name) {
                    let library = load_library(files, &name, label, number, notes)?;
                    libraries.insert(name.clone(), library);
                }
                if let Some(Some(library)) = libraries.get(&name) {
                    origins.extend(library.origins.iter().cloned());
                }
                *line = format!("mtllib {name}");
            }
            "usemtl" => {
                if rest.is_empty() {
                    if unnamed_usemtl.is_empty() {
                        notes.push(format!(
                            "{label}: line {number}: usemtl without a material name: the default material is used"
                        ));
                    }
                    unnamed_usemtl.push(index);
                } else {
                    let known = libraries
                        .values()
                        .flatten()
                        .any(|library| library.names.contains(rest));
                    // A library that could not be read has its own note already.
                    let all_read = libraries.values().all(Option::is_some);
                    if !known && all_read && !unknown_noted.iter().any(|n| n == rest) {
                        notes.push(format!(
                            "{label}: line {number}: usemtl '{rest}' names no material of the libraries read so far: the default material is used"
                        ));
                        unknown_noted.push(rest.to_owned());
                    }
                    *line = format!("usemtl {rest}");
                }
            }
            _ => {}
        }
    }
    if !unnamed_usemtl.is_empty() {
        // `tobj` refuses `usemtl` without a name; any name no library defines gives the same
        // result, the default material.
        let mut name = String::from("(unnamed)");
        while libraries
            .values()
            .flatten()
            .any(|library| library.names.contains(&name))
        {
            name.push('\'');
        }
        for index in unnamed_usemtl {
            lines[index] = format!("usemtl {name}");
        }
    }
    Ok(PreparedObj {
        lines,
        libraries,
        origins,
    })
}

/// Checks one face's vertex references (`v`, `v/vt`, `v//vn`, `v/vt/vn`; negative numbers
/// count back from the last vertex read) against the file's vertex, texture-coordinate and
/// normal counts. Texture coordinates and normals are checked only when the file has any, as
/// `tobj` ignores them otherwise.
fn check_face(rest: &str, so_far: &[usize; 3], totals: &[usize; 3]) -> Result<(), String> {
    const KINDS: [(&str, &str); 3] = [
        ("vertex", "vertices"),
        ("texture coordinate", "texture coordinates"),
        ("normal", "normals"),
    ];
    if rest.is_empty() {
        return Err("face without vertices".into());
    }
    for corner in rest.split_whitespace() {
        for (slot, reference) in corner.split('/').enumerate().take(3) {
            if reference.is_empty() {
                if slot == 0 {
                    return Err(format!("face corner '{corner}' has no vertex number"));
                }
                continue;
            }
            if slot > 0 && totals[slot] == 0 {
                continue;
            }
            // Unparsable numbers are left to `tobj`, which reports the line.
            let Ok(n) = reference.parse::<i64>() else {
                continue;
            };
            let resolved = if n < 0 {
                so_far[slot] as i64 + n
            } else {
                n - 1
            };
            if n == 0 || resolved < 0 || resolved >= totals[slot] as i64 {
                let (one, many) = KINDS[slot];
                return Err(format!(
                    "face refers to {one} {n}, but the file has {} {many}",
                    totals[slot]
                ));
            }
        }
    }
    Ok(())
}

/// Reads, checks and parses the MTL library `name` of an `mtllib` statement at `obj_line`.
/// An unreadable library is a note (`None`): the faces fall back to the default material. A
/// malformed one is an error naming its line.
fn load_library(
    files: &Files,
    name: &str,
    obj_label: &str,
    obj_line: usize,
    notes: &mut Vec<String>,
) -> Result<Option<Library>, SceneError> {
    let path = files.resolve(&name.replace('\\', "/"));
    let bytes = match files.read(&path) {
        Ok(bytes) => bytes,
        Err(e) => {
            let reason = match e {
                SceneError::Unreadable { reason, .. } => reason,
                other => other.to_string(),
            };
            notes.push(format!(
                "{obj_label}: line {obj_line}: material library '{name}' not loaded ({reason}): its materials are replaced by a default material"
            ));
            return Ok(None);
        }
    };
    let label = path.display().to_string();
    let (lines, origins) = prepare_mtl(decode_lines(&bytes), &label, notes)?;
    let text = lines.join("\n");
    let mut reader = LineCountingReader::new(&text);
    let parsed = tobj::load_mtl_buf(&mut reader).map_err(|e| {
        let line = reader.line();
        let written = lines.get(line.wrapping_sub(1)).map_or("", String::as_str);
        SceneError::invalid(
            &label,
            format!("line {line}: {e} ('{}')", excerpt(written, 60)),
        )
    })?;
    let names = parsed.1.keys().cloned().collect();
    Ok(Some(Library {
        parsed: Ok(parsed),
        names,
        origins,
    }))
}

/// Checks and rewrites MTL lines, one for one, before `tobj` reads them:
/// - a material with an empty `newmtl` name is blanked out (its faces get the default
///   material, with a note); `tobj` would refuse the whole library;
/// - `Ka`/`Kd`/`Ks`/`Ke` with one number mean grey (the MTL format's `r` alone stands for
///   `r r r`): written out as three, since `tobj` needs three;
/// - colours with two numbers or none, negative `Kd`/`Ks`/`Ke` components, `Kd`/`Ks`
///   components above 1 and unreadable `Tr` values are errors at their line.
///
/// Returns the lines and where each material `tobj` will return was written.
fn prepare_mtl(
    mut lines: Vec<String>,
    label: &str,
    notes: &mut Vec<String>,
) -> Result<(Vec<String>, Vec<MaterialOrigin>), SceneError> {
    let at = |number: usize, message: String| {
        SceneError::invalid(label, format!("line {number}: {message}"))
    };
    let mut origins: Vec<MaterialOrigin> = Vec::new();
    let mut skipping = false;
    for (index, line) in lines.iter_mut().enumerate() {
        let number = index + 1;
        let (keyword, rest) = split_keyword(line);
        let (keyword, rest) = (keyword.to_owned(), rest.to_owned());
        let (keyword, rest) = (keyword.as_str(), rest.as_str());
        if keyword == "newmtl" {
            skipping = rest.is_empty();
            if skipping {
                notes.push(format!(
                    "{label}: line {number}: material without a name ignored: faces using it get the default material"
                ));
                line.clear();
            } else {
                origins.push(MaterialOrigin {
                    file: label.to_owned(),
                    newmtl_line: number,
                    statement_lines: HashMap::new(),
                });
            }
            continue;
        }
        if skipping {
            line.clear();
            continue;
        }
        match keyword {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                let words: Vec<&str> = rest.split_whitespace().collect();
                if words.is_empty() || words.len() == 2 {
                    return Err(at(
                        number,
                        format!("'{}' needs 1 or 3 numbers", excerpt(line, 60)),
                    ));
                }
                let values: Vec<f32> = words
                    .iter()
                    .take(3)
                    .filter_map(|w| w.parse::<f32>().ok())
                    .collect();
                if keyword != "Ka" && values.iter().any(|&x| x < 0.0) {
                    return Err(at(
                        number,
                        format!("'{}': a colour component is negative", excerpt(line, 60)),
                    ));
                }
                // Reflectances (the same rule as TOML's base_color and glTF's
                // baseColorFactor): above 1 a surface would give back more light than it
                // receives. Emission (`Ke`) may exceed 1; `Ka` is not used.
                if matches!(keyword, "Kd" | "Ks") && values.iter().any(|&x| x > 1.0) {
                    return Err(at(
                        number,
                        format!(
                            "'{}': {keyword} is a reflectance, its components must lie in [0, 1]",
                            excerpt(line, 60)
                        ),
                    ));
                }
                if words.len() == 1 {
                    *line = format!("{keyword} {0} {0} {0}", words[0]);
                }
            }
            "Ns" if rest.parse::<f32>().is_ok_and(|x| x < 0.0) => {
                return Err(at(number, format!("Ns {rest} is negative")));
            }
            // Dissolve and its complement are fractions of light (MTL: `d` from 0,
            // transparent, to 1, opaque; `d -halo f` names the same fraction): outside
            // [0, 1] they mean nothing, as a reflectance above 1 does.
            "Pr" | "Pm" | "d" | "Tr" => {
                let value = rest
                    .split_whitespace()
                    .find(|w| *w != "-halo")
                    .and_then(|v| v.parse::<f32>().ok());
                if !value.is_some_and(|v| (0.0..=1.0).contains(&v)) {
                    return Err(at(
                        number,
                        format!(
                            "'{}': {keyword} must be a number in [0, 1]",
                            excerpt(line, 60)
                        ),
                    ));
                }
            }
            keyword if keyword.starts_with("map_") || matches!(keyword, "bump" | "norm") => {
                if let Err(message) = MapStatement::parse(rest) {
                    return Err(at(number, format!("'{}': {message}", excerpt(line, 60))));
                }
            }
            _ => {}
        }
        if let Some(origin) = origins.last_mut() {
            origin.statement_lines.insert(keyword.to_owned(), number);
        }
    }
    Ok((lines, origins))
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
    if let Some(bad) = m.indices.iter().find(|&&i| i as usize >= positions.len()) {
        return Err(SceneError::invalid(
            label,
            format!(
                "object '{}': vertex index {bad} out of range ({} vertices)",
                model.name,
                positions.len()
            ),
        ));
    }
    // Without arities every face is a triangle.
    let triangles: Vec<[u32; 3]> = if m.face_arities.is_empty() {
        m.indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect()
    } else {
        let mut triangles = Vec::with_capacity(m.indices.len());
        let mut start = 0;
        for &arity in &m.face_arities {
            let end = (start + arity as usize).min(m.indices.len());
            triangles.extend(polygon::triangulate(&positions, &m.indices[start..end]));
            start = end;
        }
        triangles
    };
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
    if let Some(note) = repair_zero_normals(&positions, &triangles, &mut normals) {
        notes.push(format!("{label}: object '{}': {note}", model.name));
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

/// One parsed MTL material as a conetrace material; `origin` locates its messages.
fn convert_material(
    m: &tobj::Material,
    origin: &MaterialOrigin,
    files: &Files,
    textures: &mut Vec<TextureDesc>,
    notes: &mut Vec<String>,
) -> Result<Material, SceneError> {
    let at = |keyword: &str, message: String| {
        SceneError::invalid(
            &origin.file,
            format!("line {}: {message}", origin.line_of(keyword)),
        )
    };
    let mut material = Material {
        name: m.name.clone(),
        ..Material::default()
    };
    if let Some(kd) = m.diffuse {
        material.base_color = Vec3::from(kd);
    }
    let ks = m.specular.map(|ks| Vec3::from(ks).max_element());
    let mut classic = ClassicModel {
        specular: ks.unwrap_or(0.0),
        ..ClassicModel::default()
    };
    if let Some(ns) = m.shininess {
        classic.shininess = ns;
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
            .ok_or_else(|| at("Tr", format!("bad Tr value '{tr}'")))?,
        (None, None) => 0.0,
    };
    material.transmission = transparency.clamp(0.0, 1.0);
    match m.illumination_model {
        Some(3) => {
            material.mirror = ks.filter(|&k| k > 0.0).unwrap_or(1.0);
            classic.specular = 0.0;
        }
        Some(4 | 6 | 7) => material.transmission = 1.0,
        _ => {}
    }
    let mut texture = |keyword: &str, statement: &str, color_space: ColorSpace| {
        let place = format!("{}: line {}", origin.file, origin.line_of(keyword));
        add_texture(files, textures, statement, color_space, &place, notes)
            .map_err(|e| at(keyword, e))
    };
    if let Some(file) = &m.diffuse_texture {
        material.base_color_texture = texture("map_Kd", file, ColorSpace::Srgb)?;
    }
    if let Some(file) = &m.dissolve_texture {
        material.alpha_texture = texture("map_d", file, ColorSpace::Linear)?;
        if material.alpha_texture.is_some() {
            material.alpha_cutoff = Some(0.5);
        }
    }
    let param = |key: &str| m.unknown_param.get(key).map(String::as_str);
    let number =
        |key: &str| param(key).and_then(|v| v.split_whitespace().next()?.parse::<f32>().ok());
    // The PBR extension of MTL (`Pr`, `Pm`, `map_Pr`, `map_Pm`, as Blender and three.js
    // write them) selects the metallic-roughness model; otherwise the classic one.
    let (roughness_map, metallic_map) = (param("map_Pr"), param("map_Pm"));
    material.model = if number("Pr").is_some()
        || number("Pm").is_some()
        || roughness_map.is_some()
        || metallic_map.is_some()
    {
        // Without `Pm`, a metalness map gives the metalness by itself (factor 1).
        let default_metallic = if metallic_map.is_some() { 1.0 } else { 0.0 };
        let mut model = MetallicRoughnessModel::new(
            number("Pr").unwrap_or(1.0),
            number("Pm").unwrap_or(default_metallic),
        );
        match (roughness_map, metallic_map) {
            // One file for both: glTF's packing (green = roughness, blue = metalness).
            (Some(r), Some(m)) if MapStatement::parse(r) == MapStatement::parse(m) => {
                model.metallic_roughness_texture = texture("map_Pr", r, ColorSpace::Linear)?;
            }
            (r, m) => {
                if let Some(r) = r {
                    model.roughness_texture = texture("map_Pr", r, ColorSpace::Linear)?;
                }
                if let Some(m) = m {
                    model.metallic_texture = texture("map_Pm", m, ColorSpace::Linear)?;
                }
            }
        }
        MaterialModel::MetallicRoughness(model)
    } else {
        MaterialModel::Classic(classic)
    };
    if let Some(file) = param("map_Ke") {
        material.emission_texture = texture("map_Ke", file, ColorSpace::Srgb)?;
        // The texture gives the emission by itself unless `Ke` scales it.
        if m.emissive.is_none() && material.emission_texture.is_some() {
            material.emission = Vec3::ONE;
        }
    }
    // Tangent-space normal maps: `norm` (the PBR extension), and `map_Bump`/`bump`, which
    // Blender's exporter writes for a Normal Map node's image with its strength as `-bm`.
    let normal = match (param("norm"), &m.normal_texture) {
        (Some(statement), _) => Some(("norm", statement)),
        (None, Some(statement)) => Some((
            if origin.statement_lines.contains_key("bump") {
                "bump"
            } else {
                "map_Bump"
            },
            statement.as_str(),
        )),
        (None, None) => None,
    };
    if let Some((keyword, statement)) = normal {
        let keyword = if keyword == "map_Bump" && origin.statement_lines.contains_key("map_bump") {
            "map_bump"
        } else {
            keyword
        };
        material.normal_scale = MapStatement::parse(statement)
            .map_err(|e| at(keyword, e))?
            .bump_multiplier;
        material.normal_texture = texture(keyword, statement, ColorSpace::Linear)?;
    }
    Ok(material)
}

/// An MTL map statement (`map_Kd -s 2 2 1 -clamp on wood grain.png`): its options, then
/// the file name, which is the rest of the line (spaces included, `\\` read as `/`).
#[derive(Clone, Debug, PartialEq)]
struct MapStatement {
    file: String,
    /// `-s` and `-o` as a transform of (s, t) (the MTL spec's scale and origin offset of
    /// the texture coordinates, in OBJ's v-up convention, turned into t-down).
    transform: Affine2,
    /// `-clamp on`: the texture does not repeat.
    clamp: bool,
    /// `-bm`: the bump (normal map) multiplier, 1 when absent.
    bump_multiplier: f32,
    /// Options the renderer does not use (e.g. `-mm`, `-imfchan`, `-blendu`), for a note.
    ignored: Vec<String>,
}

impl MapStatement {
    /// Parses the options the MTL specification defines, each with its arguments; the rest
    /// of the statement is the file name. An unknown option is an error: how many words it
    /// takes is unknown, so the file name could not be found.
    fn parse(statement: &str) -> Result<MapStatement, String> {
        let mut rest = statement.trim();
        let mut scale = Vec2::ONE;
        let mut offset = Vec2::ZERO;
        let mut clamp = false;
        let mut bump_multiplier = 1.0;
        let mut ignored = Vec::new();
        // The next word of `rest`, and `rest` after it.
        fn word(rest: &mut &str) -> Option<String> {
            let trimmed = rest.trim_start();
            if trimmed.is_empty() {
                return None;
            }
            let end = trimmed.find(char::is_whitespace).unwrap_or(trimmed.len());
            *rest = &trimmed[end..];
            Some(trimmed[..end].to_owned())
        }
        // Up to three numbers (`-s u [v [w]]`), at least one.
        fn numbers(rest: &mut &str, option: &str) -> Result<Vec<f32>, String> {
            let mut values = Vec::new();
            while values.len() < 3 {
                let mut probe = *rest;
                match word(&mut probe).and_then(|w| w.parse::<f32>().ok()) {
                    Some(value) if value.is_finite() => {
                        values.push(value);
                        *rest = probe;
                    }
                    _ => break,
                }
            }
            if values.is_empty() {
                return Err(format!("{option} needs a finite number"));
            }
            Ok(values)
        }
        loop {
            let trimmed = rest.trim_start();
            if !trimmed.starts_with('-') {
                break;
            }
            let option = word(&mut rest).unwrap_or_default();
            match option.as_str() {
                "-s" | "-o" => {
                    let values = numbers(&mut rest, &option)?;
                    // A missing v is the spec's default: scale 1, offset 0.
                    let default_v = if option == "-s" { 1.0 } else { 0.0 };
                    let uv = Vec2::new(values[0], values.get(1).copied().unwrap_or(default_v));
                    if option == "-s" {
                        scale = uv;
                    } else {
                        offset = uv;
                    }
                }
                "-bm" => {
                    bump_multiplier = numbers(&mut rest, &option)?[0];
                }
                "-clamp" => match word(&mut rest).as_deref() {
                    Some("on") => clamp = true,
                    Some("off") => clamp = false,
                    other => return Err(format!("-clamp takes on or off, not {other:?}")),
                },
                "-blendu" | "-blendv" | "-cc" => {
                    word(&mut rest).ok_or_else(|| format!("{option} takes on or off"))?;
                    ignored.push(option);
                }
                "-t" => {
                    numbers(&mut rest, &option)?;
                    ignored.push(option);
                }
                "-mm" => {
                    for _ in 0..2 {
                        word(&mut rest).ok_or_else(|| "-mm takes a base and a gain".to_owned())?;
                    }
                    ignored.push(option);
                }
                "-texres" | "-boost" | "-imfchan" | "-type" => {
                    word(&mut rest).ok_or_else(|| format!("{option} takes a value"))?;
                    ignored.push(option);
                }
                _ => return Err(format!("unknown map option '{option}'")),
            }
        }
        let file = rest.trim().replace('\\', "/");
        if file.is_empty() {
            return Err("no file name".to_owned());
        }
        // u' = s_u u + o_u and v' = s_v v + o_v in OBJ's v-up coordinates; with t = 1 - v:
        // t' = s_v t + (1 - s_v - o_v).
        let transform = Affine2::from_cols(
            Vec2::new(scale.x, 0.0),
            Vec2::new(0.0, scale.y),
            Vec2::new(offset.x, 1.0 - scale.y - offset.y),
        );
        Ok(MapStatement {
            file,
            transform,
            clamp,
            bump_multiplier,
            ignored,
        })
    }
}

/// Adds (or reuses) the texture of an MTL map statement and returns its binding (with the
/// statement's `-s`/`-o` transform). Windows separators (`.\\a.jpg`, common in exported MTL
/// files) are read as `/`. Options the renderer ignores get a note. A file that cannot be
/// read gives `None` and a note at `place` (`files::note_not_loaded`).
fn add_texture(
    files: &Files,
    textures: &mut Vec<TextureDesc>,
    statement: &str,
    color_space: ColorSpace,
    place: &str,
    notes: &mut Vec<String>,
) -> Result<Option<TextureBinding>, String> {
    let map = MapStatement::parse(statement)?;
    if !map.ignored.is_empty() {
        notes.push(format!(
            "texture '{}': map option(s) {} ignored",
            map.file,
            map.ignored.join(", ")
        ));
    }
    let wrap = if map.clamp {
        WrapMode::Clamp
    } else {
        WrapMode::Periodic
    };
    let binding = |texture: usize| TextureBinding {
        texture,
        transform: map.transform,
    };
    if let Some(i) = textures
        .iter()
        .position(|t| t.name == map.file && t.color_space == Some(color_space) && t.wrap_s == wrap)
    {
        return Ok(Some(binding(i)));
    }
    let source = match files.texture_source(&files.resolve(&map.file)) {
        Ok(source) => source,
        Err(e) => {
            let what = format!("texture '{}'", map.file);
            note_not_loaded(notes, place, &what, &e, "rendered without it");
            return Ok(None);
        }
    };
    textures.push(TextureDesc {
        name: map.file.clone(),
        source,
        // The map's keyword states it.
        color_space: Some(color_space),
        wrap_s: wrap,
        wrap_t: wrap,
    });
    Ok(Some(binding(textures.len() - 1)))
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
        assert_eq!(
            m.model,
            MaterialModel::Classic(ClassicModel {
                specular: 0.5,
                shininess: 50.0
            })
        );
        let binding = m.base_color_texture.as_ref().unwrap();
        assert_eq!(
            part.textures[binding.texture].color_space,
            Some(ColorSpace::Srgb)
        );
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
    fn pbr_statements_map_onto_the_metallic_roughness_model() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        write(
            dir.path(),
            "quad.mtl",
            "newmtl red\nKd 1 0 0\nPr 0.4\nPm 0.8\nmap_Pr orm.png\nmap_Pm orm.png\n\
             Ke 2 2 2\nmap_Ke glow.png\nmap_Bump -bm 0.5 normals.png\n",
        );
        for file in ["orm.png", "glow.png", "normals.png"] {
            write(dir.path(), file, "not decoded here");
        }
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap();
        let m = &part.materials[0];
        assert_eq!(
            m.model
                .metallic_roughness()
                .map(|mr| (mr.roughness, mr.metallic)),
            Some((0.4, 0.8))
        );
        let model = m.model.metallic_roughness().unwrap();
        assert_eq!(m.emission, Vec3::splat(2.0));
        assert_eq!(m.normal_scale, 0.5);
        let texture = |b: &Option<TextureBinding>| &part.textures[b.as_ref().unwrap().texture];
        let orm = texture(&model.metallic_roughness_texture);
        assert_eq!(
            (orm.name.as_str(), orm.color_space),
            ("orm.png", Some(ColorSpace::Linear))
        );
        let glow = texture(&m.emission_texture);
        assert_eq!(
            (glow.name.as_str(), glow.color_space),
            ("glow.png", Some(ColorSpace::Srgb))
        );
        let normals = texture(&m.normal_texture);
        assert_eq!(
            (normals.name.as_str(), normals.color_space),
            ("normals.png", Some(ColorSpace::Linear))
        );

        // `norm`, separate greyscale maps, and map_Ke without Ke.
        write(
            dir.path(),
            "quad.mtl",
            "newmtl red\nmap_Pr orm.png\nmap_Pm glow.png\nmap_Ke glow.png\nnorm normals.png\n",
        );
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap();
        let m = &part.materials[0];
        assert_eq!(
            m.model
                .metallic_roughness()
                .map(|mr| (mr.roughness, mr.metallic)),
            Some((1.0, 1.0))
        );
        let model = m.model.metallic_roughness().unwrap();
        assert!(model.metallic_roughness_texture.is_none());
        let texture = |b: &Option<TextureBinding>| &part.textures[b.as_ref().unwrap().texture];
        assert_eq!(texture(&model.roughness_texture).name, "orm.png");
        let metal = texture(&model.metallic_texture);
        assert_eq!(
            (metal.name.as_str(), metal.color_space),
            ("glow.png", Some(ColorSpace::Linear))
        );
        assert_eq!(m.emission, Vec3::ONE);
        assert_eq!(m.normal_scale, 1.0);
        assert!(m.normal_texture.is_some());
    }

    /// `Kd` obeys the reflectance rule `Ks`, TOML's `base_color` and glTF's
    /// `baseColorFactor` obey; `Ke` is emission and may exceed 1.
    #[test]
    fn reflectances_above_one_are_errors_at_their_line() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        for (mtl, expected) in [
            (
                "newmtl red\nKd 2 0 0\n",
                "quad.mtl: line 2: 'Kd 2 0 0': Kd is a reflectance, its components must lie in [0, 1]",
            ),
            (
                "newmtl red\nKs 1.5\n",
                "quad.mtl: line 2: 'Ks 1.5': Ks is a reflectance, its components must lie in [0, 1]",
            ),
        ] {
            write(dir.path(), "quad.mtl", mtl);
            let err = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj"))
                .unwrap_err()
                .to_string();
            assert!(err.ends_with(expected), "{err}");
        }
        write(dir.path(), "quad.mtl", "newmtl red\nKd 1 1 1\nKe 4 4 4\n");
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap();
        assert_eq!(part.materials[0].emission, Vec3::splat(4.0));
    }

    #[test]
    fn bad_pbr_statements_are_errors_at_their_line() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        for (mtl, expected) in [
            (
                "newmtl red\nPr 1.5\n",
                "quad.mtl: line 2: 'Pr 1.5': Pr must be a number in [0, 1]",
            ),
            (
                "newmtl red\nPm x\n",
                "quad.mtl: line 2: 'Pm x': Pm must be a number in [0, 1]",
            ),
            (
                "newmtl red\nKd 1 1 1\nmap_Bump -bm nan n.png\n",
                "line 3: 'map_Bump -bm nan n.png': -bm needs a finite number",
            ),
        ] {
            write(dir.path(), "quad.mtl", mtl);
            let err = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj"))
                .unwrap_err()
                .to_string();
            assert!(err.contains(expected) && err.contains("quad.mtl"), "{err}");
            assert_eq!(err.lines().count(), 1, "{err}");
        }
    }

    /// Map statements as 3ds Max, Maya and Blender write them: options with their arguments
    /// (`-s` and `-o` become the binding's transform, `-clamp on` clamps, options without
    /// effect here are noted), then a file name that may hold spaces. The file name used to
    /// be the last word, so `-s` was dropped without a word and `quad space.png` read as
    /// `space.png`.
    #[test]
    fn map_options_and_file_names_with_spaces() {
        let parsed =
            MapStatement::parse("-s 2 4 1 -o 0.25 0.5 -clamp on -mm 0 1 wood grain.png").unwrap();
        assert_eq!(parsed.file, "wood grain.png");
        assert!(parsed.clamp);
        assert_eq!(parsed.ignored, ["-mm"]);
        // (u, v) = (0.5, 0.25), i.e. (s, t) = (0.5, 0.75): u' = 2 u + 0.25 = 1.25 and
        // v' = 4 v + 0.5 = 1.5, so (s', t') = (1.25, 1 - 1.5).
        let st = parsed.transform.transform_point2(Vec2::new(0.5, 0.75));
        assert!((st - Vec2::new(1.25, -0.5)).length() < 1e-6, "{st}");
        let plain = MapStatement::parse("  textures\\brick.png ").unwrap();
        assert_eq!(plain.file, "textures/brick.png");
        assert_eq!(plain.transform, Affine2::IDENTITY);
        assert_eq!(
            MapStatement::parse("-s 3 tile.png")
                .unwrap()
                .transform
                .matrix2
                .y_axis
                .y,
            1.0
        );
        for bad in [
            "-s tile.png",
            "-clamp maybe a.png",
            "-frobnicate 2 a.png",
            "-s 2 2",
        ] {
            assert!(MapStatement::parse(bad).is_err(), "{bad}");
        }

        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        fs::copy(
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/textures/checker.png"),
            dir.path().join("my checker.png"),
        )
        .unwrap();
        write(
            dir.path(),
            "quad.mtl",
            "newmtl red\nmap_Kd -s 2 2 1 -blendu off my checker.png\n",
        );
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap();
        let binding = part.materials[0].base_color_texture.clone().unwrap();
        assert_eq!(part.textures[binding.texture].name, "my checker.png");
        assert_eq!(binding.transform.matrix2.x_axis.x, 2.0);
        assert!(
            part.notes
                .iter()
                .any(|n| n.contains("-blendu") && n.contains("ignored")),
            "{:?}",
            part.notes
        );
    }

    /// A concave `f` (a U shape, as Blender writes n-gons) is tiled exactly: its triangles'
    /// area is the polygon's. `tobj`'s fan covered part of the notch (area 3 instead of 2.5).
    #[test]
    fn a_concave_face_loads_as_its_own_area() {
        let dir = tempfile::tempdir().unwrap();
        write(
            dir.path(),
            "u.obj",
            "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv 0.5 1 0\nv 0.5 -0.5 0\nv -0.5 -0.5 0\n\
             v -0.5 1 0\nv -1 1 0\nf 1 2 3 4 5 6 7 8\n",
        );
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("u.obj")).unwrap();
        let mesh = &part.meshes[0];
        let area: f32 = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        assert_eq!(mesh.triangles.len(), 6);
        assert!((area - 2.5).abs() < 1e-5, "area {area}");
    }

    /// A map file that cannot be read is left out with a note naming the MTL line, as a
    /// missing MTL library is; the material keeps its factors (`map_Ke` without its image
    /// does not make the surface a white emitter).
    #[test]
    fn missing_texture_files_are_left_out_with_a_note() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "quad.obj", QUAD);
        write(
            dir.path(),
            "quad.mtl",
            "newmtl red\nKd 1 0 0\nmap_Kd nothere.png\nmap_d nothere.png\n\
             map_Ke missing_glow.png\nnorm missing_normals.png\nPm 1\nmap_Pm missing_metal.png\n",
        );
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj"))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut m = part.materials[0].clone();
        assert_eq!(m.base_color, Vec3::new(1.0, 0.0, 0.0));
        assert!(m.texture_slots_mut().iter().all(|slot| slot.is_none()));
        assert_eq!((m.alpha_cutoff, m.emission), (None, Vec3::ZERO));
        assert!(part.textures.is_empty());
        for expected in [
            "quad.mtl: line 3: texture 'nothere.png' not loaded (no such file): rendered without it",
            "quad.mtl: line 5: texture 'missing_glow.png' not loaded",
            "quad.mtl: line 6: texture 'missing_normals.png' not loaded",
            "quad.mtl: line 8: texture 'missing_metal.png' not loaded",
        ] {
            assert!(
                part.notes.iter().any(|n| n.contains(expected)),
                "{expected} not in {:?}",
                part.notes
            );
        }
        let named = |file: &str| part.notes.iter().filter(|n| n.contains(file)).count();
        assert_eq!(named("'nothere.png'"), 1, "{:?}", part.notes);
    }

    #[test]
    fn relative_and_forward_face_references_are_accepted() {
        // Negative numbers count back from the last vertex read; a face may also refer to a
        // vertex written after it (as `tobj` allows).
        let dir = tempfile::tempdir().unwrap();
        write(
            dir.path(),
            "r.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nf 1 3 4\nv 1 1 0\n",
        );
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("r.obj")).unwrap();
        let triangles: usize = part.meshes.iter().map(|m| m.triangles.len()).sum();
        assert_eq!(triangles, 2);
        assert_eq!(
            check_face("-4 1 2", &[3, 0, 0], &[4, 0, 0]).unwrap_err(),
            "face refers to vertex -4, but the file has 4 vertices"
        );
        // Texture-coordinate numbers are ignored when the file has none.
        assert!(check_face("1/9 2/9 3/9", &[3, 0, 0], &[3, 0, 0]).is_ok());
    }

    #[test]
    fn unknown_material_names_get_the_default_material_and_a_note() {
        let dir = tempfile::tempdir().unwrap();
        write(
            dir.path(),
            "quad.obj",
            &QUAD.replace("usemtl red", "usemtl blue"),
        );
        write(dir.path(), "quad.mtl", "newmtl red\nKd 1 0 0\n");
        let part = load_obj(&Files::disk(dir.path()), &dir.path().join("quad.obj")).unwrap();
        assert_eq!(part.materials[part.meshes[0].material].name, "default");
        assert!(
            part.notes
                .iter()
                .any(|n| n.contains("line 11: usemtl 'blue' names no material")),
            "{:?}",
            part.notes
        );
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
