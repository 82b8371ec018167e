//! glTF 2.0 (`.gltf` with external or embedded buffers, `.glb`) as a scene part.
//!
//! The `gltf` crate parses and validates the JSON; this file resolves buffers itself and
//! reads accessors with bounds checks, so malformed files (indices out of range, short
//! buffers, cyclic node graphs) become a [`SceneError`] instead of a panic. Images are not
//! decoded: buffer-view and `data:` images become `TextureSource::Encoded`, file URIs
//! `TextureSource::File` (a file that cannot be read is left out with a note, the policy of
//! `files::note_not_loaded`; a buffer file is geometry, and an error).
//!
//! Before the `gltf` crate reads the file, its [`Preamble`] refuses glTF 1.0 and files that
//! require an extension missing from [`SUPPORTED_EXTENSIONS`], and lists the used extensions
//! that are ignored (a note each). Zero-length normals are repaired as in OBJ files
//! (`normals::repair_zero_normals`).
//!
//! Material mapping: base colour factor/texture (sRGB), the metallic-roughness model itself
//! (`MaterialModel::MetallicRoughness`, factors defaulting to 1, and the linear
//! metallic-roughness texture, B = metalness, G = roughness), emissive factor times
//! `KHR_materials_emissive_strength` with the emissive texture (sRGB), the normal texture
//! (linear) with its scale, `KHR_materials_transmission` factor, `KHR_materials_ior`,
//! `KHR_materials_volume` attenuation colour/distance (Beer's law, seed 004),
//! `KHR_texture_transform` on every texture, alpha mode MASK (BLEND is treated as MASK at
//! 0.5) with the base-colour texture's alpha as a linear alpha texture.
//! Texture coordinates: glTF's v points down, so `t = v` directly.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::{Affine2, Affine3A, DMat4, DQuat, DVec3, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};

use super::error::SceneError;
use super::files::{note_not_loaded, Files};
use super::merge::Transform;
use super::normals::repair_zero_normals;
use super::uri::{decode_data_uri, percent_decode};
use crate::scene::{
    CameraDesc, ColorSpace, Light, Material, MaterialModel, MetallicRoughnessModel, Projection,
    SceneDescription, TextureBinding, TextureDesc, TextureSource, TriangleMesh, WrapMode,
};

/// Loads the glTF file at `path` as a scene part: world-space meshes, materials, textures,
/// punctual lights and the first camera met in the node graph, and the fog of its `extras`.
pub(crate) fn load_gltf(files: &Files, path: &Path) -> Result<SceneDescription, SceneError> {
    load_gltf_with(files, path, true)
}

/// [`load_gltf`] without reading `extras.fog` when not `with_fog`: a file loaded as the
/// closed mesh that bounds fog gives only its triangles (its own fog, which may name the
/// file itself as its bounds, is not followed).
pub(crate) fn load_gltf_with(
    files: &Files,
    path: &Path,
    with_fog: bool,
) -> Result<SceneDescription, SceneError> {
    let label = path.display().to_string();
    let bytes = files.read(path)?;
    let err = |m: String| SceneError::invalid(&label, m);
    // Before the `gltf` crate deserialises the file: a glTF 1.0 file fails there with
    // whichever of its 1.0 constructs it meets first, and a required extension only after
    // full validation, among the problems it causes.
    let ignored_extensions = match Preamble::of(&bytes) {
        Some(preamble) => preamble.check().map_err(err)?,
        None => Vec::new(),
    };
    let gltf = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| err(format!("glTF parse error: {e}")))?;
    check_schema(gltf.document.as_json()).map_err(err)?;
    let local = files.with_base(path.parent().unwrap_or(Path::new("")));
    let buffers = load_buffers(&gltf, &local).map_err(err)?;
    let mut loader = Loader {
        document: &gltf.document,
        buffers: &buffers,
        files: &local,
        label: &label,
        part: SceneDescription {
            source: label.clone(),
            ..Default::default()
        },
        materials: HashMap::new(),
        textures: HashMap::new(),
        camera: None,
    };
    for extension in ignored_extensions {
        loader.part.notes.push(format!(
            "{label}: uses the glTF extension {extension}, which conetrace ignores"
        ));
    }
    loader.walk_nodes().map_err(err)?;
    if loader.part.meshes.is_empty() {
        return Err(err("no triangle meshes in the glTF file".into()));
    }
    loader.part.camera = loader
        .camera
        .as_ref()
        .map(|pose| pose.desc(loader.part.bounds()));
    if with_fog {
        loader.part.fog =
            super::fog::gltf_fog(gltf.document.as_json().extras.as_deref(), &local).map_err(err)?;
    }
    Ok(loader.part)
}

/// The `gltf` crate's validation (index ranges, required fields, supported required
/// extensions), except that missing POSITION `min`/`max` is tolerated: the specification
/// requires them, but this loader computes bounds itself and exporters often omit them.
fn check_schema(root: &gltf::json::Root) -> Result<(), String> {
    use gltf::json::validation::{Checked, Error, Validate};
    // gltf-json 1.4's validation indexes `accessors` with a primitive's POSITION index
    // before range-checking it, so an out-of-range POSITION would panic: report it first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(gltf::json::mesh::Semantic::Positions));
            if let Some(index) = position {
                if index.value() >= root.accessors.len() {
                    return Err(format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes.POSITION: \
                         accessor {} does not exist ({} accessors)",
                        index.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        let bounds = path.ends_with(".min") || path.ends_with(".max");
        if !(bounds && matches!(error, Error::Missing)) {
            problems.push(format!("{path}: {error}"));
        }
    });
    match problems.len() {
        0 => Ok(()),
        1 => Err(format!("invalid glTF: {}", problems[0])),
        n => Err(format!(
            "invalid glTF: {} (and {} more problems)",
            problems[0],
            n - 1
        )),
    }
}

/// Buffer contents by buffer index.
fn load_buffers(gltf: &gltf::Gltf, files: &Files) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for buffer in gltf.document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => gltf.blob.clone().ok_or_else(|| {
                format!("buffer {i} refers to a GLB binary chunk that is missing")
            })?,
            gltf::buffer::Source::Uri(uri) => match decode_data_uri(uri) {
                Some(decoded) => decoded.map_err(|e| format!("buffer {i}: {e}"))?,
                None => {
                    let path = files.resolve(&percent_decode(uri));
                    files.read(&path).map_err(|e| format!("buffer {i}: {e}"))?
                }
            },
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} holds {} bytes but declares byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a buffer view, bounds-checked.
fn view_bytes<'b>(view: &gltf::buffer::View, buffers: &'b [Vec<u8>]) -> Result<&'b [u8], String> {
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("buffer view {} names a missing buffer", view.index()))?;
    let end = view.offset().checked_add(view.length());
    end.and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| format!("buffer view {} lies outside its buffer", view.index()))
}

fn component(data_type: DataType, bytes: &[u8], normalized: bool) -> f32 {
    // Normalised integers follow the glTF 2.0 specification, section 3.11.
    match data_type {
        DataType::F32 => f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        DataType::U8 => {
            let v = f32::from(bytes[0]);
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        DataType::I8 => {
            let v = f32::from(bytes[0] as i8);
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = f32::from(u16::from_le_bytes([bytes[0], bytes[1]]));
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        DataType::I16 => {
            let v = f32::from(i16::from_le_bytes([bytes[0], bytes[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U32 => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as f32,
    }
}

/// The component types glTF allows for vertex and sparse indices (unsigned integers).
/// Choosing it once per accessor, and rejecting every other type there, leaves no index
/// that could be read as a stand-in value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum IndexType {
    U8,
    U16,
    U32,
}

impl IndexType {
    /// The index type of an accessor's component type; `None` for signed or float types.
    fn of(data_type: DataType) -> Option<IndexType> {
        match data_type {
            DataType::U8 => Some(IndexType::U8),
            DataType::U16 => Some(IndexType::U16),
            DataType::U32 => Some(IndexType::U32),
            DataType::I8 | DataType::I16 | DataType::F32 => None,
        }
    }

    fn of_sparse(index_type: gltf::accessor::sparse::IndexType) -> IndexType {
        match index_type {
            gltf::accessor::sparse::IndexType::U8 => IndexType::U8,
            gltf::accessor::sparse::IndexType::U16 => IndexType::U16,
            gltf::accessor::sparse::IndexType::U32 => IndexType::U32,
        }
    }

    fn size(self) -> usize {
        match self {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        }
    }

    /// The little-endian index at the start of `bytes` (at least [`Self::size`] long).
    fn read(self, bytes: &[u8]) -> u32 {
        match self {
            IndexType::U8 => u32::from(bytes[0]),
            IndexType::U16 => u32::from(u16::from_le_bytes([bytes[0], bytes[1]])),
            IndexType::U32 => u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
        }
    }
}

/// Strided elements of an accessor (or of a sparse values block), bounds-checked once.
struct Elements<'b> {
    data: &'b [u8],
    stride: usize,
    element_size: usize,
}

impl<'b> Elements<'b> {
    fn new(
        data: &'b [u8],
        offset: usize,
        stride: usize,
        element_size: usize,
        count: usize,
        what: &str,
    ) -> Result<Self, String> {
        let needed = match count {
            0 => Some(offset),
            n => (n - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(offset))
                .and_then(|v| v.checked_add(element_size)),
        };
        match needed {
            Some(end) if end <= data.len() => Ok(Elements {
                data: &data[offset..],
                stride,
                element_size,
            }),
            _ => Err(format!("{what} reads past the end of its buffer view")),
        }
    }

    fn get(&self, i: usize) -> &'b [u8] {
        &self.data[i * self.stride..i * self.stride + self.element_size]
    }
}

/// Reads an accessor as `count * components` floats (sparse substitution applied).
fn read_floats(
    accessor: &gltf::Accessor,
    buffers: &[Vec<u8>],
    components: usize,
) -> Result<Vec<f32>, String> {
    let what = format!("accessor {}", accessor.index());
    if accessor.dimensions().multiplicity() != components {
        return Err(format!(
            "{what} has {:?} elements, expected {components} components",
            accessor.dimensions()
        ));
    }
    let data_type = accessor.data_type();
    let size = data_type.size();
    let element_size = size * components;
    let count = accessor.count();
    let normalized = accessor.normalized();
    let read_element = |out: &mut [f32], bytes: &[u8]| {
        for (c, value) in out.iter_mut().enumerate() {
            *value = component(data_type, &bytes[c * size..], normalized);
        }
    };
    let total = count
        .checked_mul(components)
        .filter(|&n| n <= 1 << 28)
        .ok_or_else(|| format!("{what} has an implausible count {count}"))?;
    let mut out = vec![0.0f32; total];
    if let Some(view) = accessor.view() {
        let bytes = view_bytes(&view, buffers)?;
        let stride = view.stride().unwrap_or(element_size).max(element_size);
        let elements = Elements::new(bytes, accessor.offset(), stride, element_size, count, &what)?;
        for (i, chunk) in out.chunks_exact_mut(components).enumerate() {
            read_element(chunk, elements.get(i));
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        let indices = sparse.indices();
        let index_type = IndexType::of_sparse(indices.index_type());
        let index_size = index_type.size();
        let index_bytes = view_bytes(&indices.view(), buffers)?;
        let index_elements = Elements::new(
            index_bytes,
            indices.offset(),
            index_size,
            index_size,
            n,
            &what,
        )?;
        let values = sparse.values();
        let value_bytes = view_bytes(&values.view(), buffers)?;
        let value_elements = Elements::new(
            value_bytes,
            values.offset(),
            element_size,
            element_size,
            n,
            &what,
        )?;
        for j in 0..n {
            let target = index_type.read(index_elements.get(j)) as usize;
            let slot = out
                .get_mut(target * components..(target + 1) * components)
                .ok_or_else(|| format!("{what}: sparse index {target} out of range"))?;
            read_element(slot, value_elements.get(j));
        }
    }
    Ok(out)
}

/// Reads an index accessor (unsigned scalar integers).
fn read_indices(accessor: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, String> {
    let what = format!("index accessor {}", accessor.index());
    let data_type = accessor.data_type();
    let index_type = match (accessor.dimensions(), IndexType::of(data_type)) {
        (Dimensions::Scalar, Some(index_type)) => index_type,
        (dimensions, _) => {
            return Err(format!(
                "{what} holds {dimensions:?} of {data_type:?}; indices must be unsigned \
                 scalar integers (5121, 5123 or 5125)"
            ))
        }
    };
    if accessor.sparse().is_some() {
        return Err(format!("{what}: sparse index accessors are not supported"));
    }
    let view = accessor
        .view()
        .ok_or_else(|| format!("{what} has no buffer view"))?;
    let bytes = view_bytes(&view, buffers)?;
    let size = index_type.size();
    let stride = view.stride().unwrap_or(size).max(size);
    let elements = Elements::new(
        bytes,
        accessor.offset(),
        stride,
        size,
        accessor.count(),
        &what,
    )?;
    Ok((0..accessor.count())
        .map(|i| index_type.read(elements.get(i)))
        .collect())
}

struct Loader<'a> {
    document: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
    files: &'a Files,
    label: &'a str,
    part: SceneDescription,
    /// glTF material index (`None` = the default material) -> index in `part.materials`.
    materials: HashMap<Option<usize>, usize>,
    /// (glTF texture index, colour space) -> index in `part.textures`.
    textures: HashMap<(usize, bool), usize>,
    /// The first camera met, placed once the scene's extent is known.
    camera: Option<CameraPose>,
}

impl Loader<'_> {
    /// Visits the scene's node forest iteratively, after checking it really is a forest.
    fn walk_nodes(&mut self) -> Result<(), String> {
        let node_count = self.document.nodes().len();
        let mut parent = vec![None; node_count];
        for node in self.document.nodes() {
            for child in node.children() {
                let c = child.index();
                if let Some(p) = parent[c] {
                    return Err(format!(
                        "node {c} is a child of both node {p} and node {}",
                        node.index()
                    ));
                }
                parent[c] = Some(node.index());
            }
        }
        // With at most one parent each, a cycle shows as a parent chain longer than the node count.
        for start in 0..node_count {
            let mut current = start;
            let mut steps = 0;
            while let Some(p) = parent[current] {
                current = p;
                steps += 1;
                if steps > node_count {
                    return Err(format!(
                        "node graph is recursive (node {start} is its own ancestor)"
                    ));
                }
            }
        }
        let roots: Vec<usize> = match self
            .document
            .default_scene()
            .or_else(|| self.document.scenes().next())
        {
            Some(scene) => scene.nodes().map(|n| n.index()).collect(),
            None => (0..node_count).filter(|&n| parent[n].is_none()).collect(),
        };
        if let Some(&r) = roots.iter().find(|&&r| parent[r].is_some()) {
            return Err(format!(
                "scene root node {r} is also a child of another node"
            ));
        }
        let nodes: Vec<gltf::Node> = self.document.nodes().collect();
        // Composed in f64: a camera's view direction comes from its world matrix, and must
        // keep its precision at any distance from the origin.
        let mut stack: Vec<(usize, DMat4)> =
            roots.iter().rev().map(|&r| (r, DMat4::IDENTITY)).collect();
        let mut cameras_seen = 0;
        while let Some((index, parent_matrix)) = stack.pop() {
            let node = &nodes[index];
            let world = parent_matrix * local_matrix(node);
            let world_f32 = world.as_mat4();
            if !world_f32.is_finite() {
                return Err(format!("node {index} has a non-finite transform"));
            }
            let affine = Affine3A::from_mat4(world_f32);
            if let Some(mesh) = node.mesh() {
                match Transform::new(affine) {
                    Some(transform) => self.add_mesh(&mesh, &transform)?,
                    None => self.part.notes.push(format!(
                        "{}: node {index} has a singular transform: its mesh is skipped",
                        self.label
                    )),
                }
            }
            if let Some(camera) = node.camera() {
                cameras_seen += 1;
                if self.camera.is_none() {
                    self.camera = Some(CameraPose::new(&camera, &world)?);
                }
            }
            if let Some(light) = node.light() {
                self.part.lights.push(convert_light(&light, &affine)?);
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child.index(), world));
            }
        }
        if cameras_seen > 1 {
            self.part.notes.push(format!(
                "{}: {cameras_seen} cameras, using the first",
                self.label
            ));
        }
        Ok(())
    }

    fn add_mesh(&mut self, mesh: &gltf::Mesh, transform: &Transform) -> Result<(), String> {
        let mesh_name = mesh
            .name()
            .map_or_else(|| format!("mesh{}", mesh.index()), str::to_owned);
        for primitive in mesh.primitives() {
            let what = format!("mesh '{mesh_name}' primitive {}", primitive.index());
            let mode = primitive.mode();
            if !matches!(
                mode,
                gltf::mesh::Mode::Triangles
                    | gltf::mesh::Mode::TriangleStrip
                    | gltf::mesh::Mode::TriangleFan
            ) {
                self.part.notes.push(format!(
                    "{}: {what} uses mode {mode:?}, skipped",
                    self.label
                ));
                continue;
            }
            let positions_accessor = primitive
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| format!("{what} has no POSITION attribute"))?;
            let positions = read_floats(&positions_accessor, self.buffers, 3)?;
            let vertex_count = positions.len() / 3;
            let positions: Vec<Vec3> = positions.chunks_exact(3).map(Vec3::from_slice).collect();
            let mut normals = match primitive.get(&gltf::Semantic::Normals) {
                Some(accessor) => {
                    let n = read_floats(&accessor, self.buffers, 3)?;
                    if n.len() / 3 != vertex_count {
                        return Err(format!(
                            "{what}: {} normals for {vertex_count} positions",
                            n.len() / 3
                        ));
                    }
                    n.chunks_exact(3).map(Vec3::from_slice).collect()
                }
                None => Vec::new(),
            };
            let st = match primitive.get(&gltf::Semantic::TexCoords(0)) {
                Some(accessor) => {
                    let uv = read_floats(&accessor, self.buffers, 2)?;
                    if uv.len() / 2 != vertex_count {
                        return Err(format!(
                            "{what}: {} texture coordinates for {vertex_count} positions",
                            uv.len() / 2
                        ));
                    }
                    // glTF's v already points down: t = v.
                    uv.chunks_exact(2).map(Vec2::from_slice).collect()
                }
                None => Vec::new(),
            };
            let indices = match primitive.indices() {
                Some(accessor) => read_indices(&accessor, self.buffers)?,
                None => (0..vertex_count as u32).collect(),
            };
            if let Some(bad) = indices.iter().find(|&&i| i as usize >= vertex_count) {
                return Err(format!(
                    "{what}: index {bad} out of range ({vertex_count} vertices)"
                ));
            }
            let triangles = match mode {
                gltf::mesh::Mode::TriangleStrip => strip_triangles(&indices),
                gltf::mesh::Mode::TriangleFan => fan_triangles(&indices),
                _ => {
                    if indices.len() % 3 != 0 {
                        return Err(format!(
                            "{what}: {} indices is not a whole number of triangles",
                            indices.len()
                        ));
                    }
                    indices
                        .chunks_exact(3)
                        .map(|t| [t[0], t[1], t[2]])
                        .collect()
                }
            };
            if let Some(note) = repair_zero_normals(&positions, &triangles, &mut normals) {
                self.part
                    .notes
                    .push(format!("{}: {what}: {note}", self.label));
            }
            let material = self.material(&primitive.material())?;
            let mut placed = TriangleMesh {
                name: format!("{mesh_name}#{}", primitive.index()),
                positions,
                normals,
                st,
                triangles,
                material,
            };
            // Into the world; a mirroring node's winding is reversed (glTF 2.0, "Meshes":
            // the determinant of the node's global transform defines the winding order).
            transform.mesh(&mut placed);
            self.part.meshes.push(placed);
        }
        Ok(())
    }

    fn material(&mut self, m: &gltf::Material) -> Result<usize, String> {
        if let Some(&i) = self.materials.get(&m.index()) {
            return Ok(i);
        }
        check_material_ranges(m)?;
        let pbr = m.pbr_metallic_roughness();
        let factor = pbr.base_color_factor();
        let mut material = Material {
            name: m.name().map_or_else(
                || format!("material{}", m.index().map_or(-1, |i| i as i64)),
                str::to_owned,
            ),
            base_color: Vec3::new(factor[0], factor[1], factor[2]),
            alpha: factor[3],
            ..Material::default()
        };
        // The metallic-roughness model itself (glTF 2.0, Appendix B); the factors default to
        // 1 when `pbrMetallicRoughness` leaves them out.
        let mut model = MetallicRoughnessModel::new(pbr.roughness_factor(), pbr.metallic_factor());
        if let Some(info) = pbr.metallic_roughness_texture() {
            model.metallic_roughness_texture = self.binding(&info, ColorSpace::Linear)?;
        }
        material.model = MaterialModel::MetallicRoughness(model);
        // KHR_materials_emissive_strength scales the emissive factor beyond [0, 1].
        material.emission = Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0);
        // Double-sided materials are lit, and emit, on both sides (glTF 2.0, 3.9.5).
        material.two_sided = m.double_sided();
        if let Some(info) = m.emissive_texture() {
            material.emission_texture = self.binding(&info, ColorSpace::Srgb)?;
        }
        if let Some(normal) = m.normal_texture() {
            material.normal_texture = self.normal_binding(&normal)?;
            material.normal_scale = normal.scale();
        }
        if let Some(t) = m.transmission() {
            material.transmission = t.transmission_factor();
        }
        match m.ior() {
            // KHR_materials_ior admits 0 for legacy materials (a Fresnel term of 1 at every
            // angle), which the dielectric model here cannot express.
            Some(0.0) => self.part.notes.push(format!(
                "{}: material '{}' has KHR_materials_ior ior 0, rendered with ior 1.5",
                self.label, material.name
            )),
            Some(ior) => material.ior = ior,
            None => {}
        }
        if let Some(volume) = m.volume() {
            material.attenuation_color = Vec3::from(volume.attenuation_color());
            material.attenuation_distance = volume.attenuation_distance();
        }
        if let Some(info) = pbr.base_color_texture() {
            material.base_color_texture = self.binding(&info, ColorSpace::Srgb)?;
            if matches!(
                m.alpha_mode(),
                gltf::material::AlphaMode::Mask | gltf::material::AlphaMode::Blend
            ) {
                material.alpha_texture = self.binding(&info, ColorSpace::Linear)?;
            }
        }
        match m.alpha_mode() {
            gltf::material::AlphaMode::Opaque => {}
            gltf::material::AlphaMode::Mask => {
                material.alpha_cutoff = Some(m.alpha_cutoff().unwrap_or(0.5))
            }
            gltf::material::AlphaMode::Blend => {
                material.alpha_cutoff = Some(0.5);
                self.part.notes.push(format!(
                    "{}: material '{}' uses alphaMode BLEND, rendered as MASK at 0.5",
                    self.label, material.name
                ));
            }
        }
        self.part.materials.push(material);
        let index = self.part.materials.len() - 1;
        self.materials.insert(m.index(), index);
        Ok(index)
    }

    /// The binding of a texture reference; `None` when its image file cannot be read.
    fn binding(
        &mut self,
        info: &gltf::texture::Info,
        color_space: ColorSpace,
    ) -> Result<Option<TextureBinding>, String> {
        let mut transform = Affine2::IDENTITY;
        let mut tex_coord = info.tex_coord();
        if let Some(t) = info.texture_transform() {
            transform = texture_transform(t.offset(), t.rotation(), t.scale());
            tex_coord = t.tex_coord().unwrap_or(tex_coord);
        }
        if tex_coord != 0 {
            self.part.notes.push(format!(
                "{}: a texture uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is read",
                self.label
            ));
        }
        let texture = self.texture(&info.texture(), color_space)?;
        Ok(texture.map(|texture| TextureBinding { texture, transform }))
    }

    /// The binding of a `normalTexture` (linear data). Its `KHR_texture_transform`, which the
    /// `gltf` crate exposes on colour textures only, is read from the extension's JSON.
    fn normal_binding(
        &mut self,
        normal: &gltf::material::NormalTexture,
    ) -> Result<Option<TextureBinding>, String> {
        let mut transform = Affine2::IDENTITY;
        let mut tex_coord = normal.tex_coord();
        if let Some(t) = normal.extension_value("KHR_texture_transform") {
            let pair = |key: &str, default: [f32; 2]| {
                t.get(key).and_then(|v| v.as_array()).map_or(default, |a| {
                    let get = |i: usize, d: f32| {
                        a.get(i).and_then(|x| x.as_f64()).map_or(d, |x| x as f32)
                    };
                    [get(0, default[0]), get(1, default[1])]
                })
            };
            let rotation = t.get("rotation").and_then(|v| v.as_f64()).unwrap_or(0.0) as f32;
            transform = texture_transform(
                pair("offset", [0.0, 0.0]),
                rotation,
                pair("scale", [1.0, 1.0]),
            );
            if let Some(tc) = t.get("texCoord").and_then(|v| v.as_u64()) {
                tex_coord = tc as u32;
            }
        }
        if tex_coord != 0 {
            self.part.notes.push(format!(
                "{}: a texture uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is read",
                self.label
            ));
        }
        let texture = self.texture(&normal.texture(), ColorSpace::Linear)?;
        Ok(texture.map(|texture| TextureBinding { texture, transform }))
    }

    /// The index in `part.textures` of a glTF texture in `color_space`; `None` (with a note,
    /// `files::note_not_loaded`) when its image is a file that cannot be read.
    fn texture(
        &mut self,
        texture: &gltf::Texture,
        color_space: ColorSpace,
    ) -> Result<Option<usize>, String> {
        let key = (texture.index(), color_space == ColorSpace::Srgb);
        if let Some(&i) = self.textures.get(&key) {
            return Ok(Some(i));
        }
        let image = texture.source();
        let image_label = format!("{}#image{}", self.label, image.index());
        let source = match image.source() {
            gltf::image::Source::View { view, .. } => TextureSource::Encoded {
                label: image_label,
                bytes: Arc::new(view_bytes(&view, self.buffers)?.to_vec()),
            },
            gltf::image::Source::Uri { uri, .. } => match decode_data_uri(uri) {
                Some(decoded) => TextureSource::Encoded {
                    label: image_label,
                    bytes: Arc::new(decoded.map_err(|e| format!("image {}: {e}", image.index()))?),
                },
                None => {
                    let path = self.files.resolve(&percent_decode(uri));
                    match self.files.texture_source(&path) {
                        Ok(source) => source,
                        Err(e) => {
                            let what = format!("image {} '{uri}'", image.index());
                            let consequence = "textures using it are left out";
                            note_not_loaded(
                                &mut self.part.notes,
                                self.label,
                                &what,
                                &e,
                                consequence,
                            );
                            return Ok(None);
                        }
                    }
                }
            },
        };
        let sampler = texture.sampler();
        self.part.textures.push(TextureDesc {
            name: texture
                .name()
                .or(image.name())
                .map_or_else(|| format!("texture{}", texture.index()), str::to_owned),
            source,
            // glTF states it by the texture's role.
            color_space: Some(color_space),
            wrap_s: wrap_mode(sampler.wrap_s()),
            wrap_t: wrap_mode(sampler.wrap_t()),
        });
        let index = self.part.textures.len() - 1;
        self.textures.insert(key, index);
        Ok(Some(index))
    }
}

/// A triangle strip as triangles; every second one is flipped to keep the winding.
fn strip_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    (0..indices.len().saturating_sub(2))
        .map(|i| {
            let (a, b, c) = (indices[i], indices[i + 1], indices[i + 2]);
            if i % 2 == 0 {
                [a, b, c]
            } else {
                [b, a, c]
            }
        })
        .collect()
}

/// A triangle fan around its first index as triangles.
fn fan_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    (1..indices.len().saturating_sub(1))
        .map(|i| [indices[0], indices[i], indices[i + 1]])
        .collect()
}

/// The glTF extensions this loader reads (`load_gltf`'s material, texture and light
/// mapping); others in `extensionsUsed` are ignored with a note, others in
/// `extensionsRequired` refuse the file.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_texture_transform",
];

/// What is read of a glTF file before the `gltf` crate deserialises it: its version, its
/// extension lists and whether its collections are glTF 1.0's id-keyed objects.
#[derive(Debug, Default, serde::Deserialize)]
#[serde(rename_all = "camelCase")]
struct Preamble {
    asset: Option<serde_json::Value>,
    extensions_required: Option<serde_json::Value>,
    extensions_used: Option<serde_json::Value>,
    nodes: Option<Collection>,
    meshes: Option<Collection>,
    accessors: Option<Collection>,
    /// Set for a binary file whose header gives container version 1.
    #[serde(skip)]
    binary_version_1: bool,
}

/// How a top-level collection is written; its contents are skipped unread.
#[derive(Debug)]
struct Collection {
    /// A JSON object keyed by id (glTF 1.0) rather than an array (glTF 2.0).
    keyed: bool,
}

impl<'de> serde::Deserialize<'de> for Collection {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{IgnoredAny, MapAccess, SeqAccess, Visitor};
        struct Kind;
        impl<'de> Visitor<'de> for Kind {
            type Value = Collection;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON value")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Collection, A::Error> {
                while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
                Ok(Collection { keyed: true })
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Collection, A::Error> {
                while seq.next_element::<IgnoredAny>()?.is_some() {}
                Ok(Collection { keyed: false })
            }
            // Wrong types are left to the `gltf` crate's messages.
            fn visit_bool<E>(self, _: bool) -> Result<Collection, E> {
                Ok(Collection { keyed: false })
            }
            fn visit_i64<E>(self, _: i64) -> Result<Collection, E> {
                Ok(Collection { keyed: false })
            }
            fn visit_u64<E>(self, _: u64) -> Result<Collection, E> {
                Ok(Collection { keyed: false })
            }
            fn visit_f64<E>(self, _: f64) -> Result<Collection, E> {
                Ok(Collection { keyed: false })
            }
            fn visit_str<E>(self, _: &str) -> Result<Collection, E> {
                Ok(Collection { keyed: false })
            }
            fn visit_unit<E>(self) -> Result<Collection, E> {
                Ok(Collection { keyed: false })
            }
        }
        d.deserialize_any(Kind)
    }
}

impl Preamble {
    /// The preamble of a `.gltf` (JSON) or `.glb` (binary container) file; `None` when the
    /// JSON cannot be read, which the `gltf` crate then reports.
    fn of(bytes: &[u8]) -> Option<Preamble> {
        if !bytes.starts_with(b"glTF") {
            return serde_json::from_slice(bytes).ok();
        }
        // GLB header: magic, container version, length; then the JSON chunk's length and
        // type (glTF 2.0, "Binary glTF Layout").
        let word = |at: usize| {
            let b = bytes.get(at..at + 4)?;
            Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        };
        if word(4)? == 1 {
            return Some(Preamble {
                binary_version_1: true,
                ..Preamble::default()
            });
        }
        let json_length = word(12)?;
        let json = bytes.get(20..20usize.checked_add(json_length)?)?;
        serde_json::from_slice(json).ok()
    }

    /// Whether the file is glTF 1.0: by its version, or, without a readable version, by
    /// collections written as id-keyed objects.
    fn is_version_1(&self) -> bool {
        let version = self.asset.as_ref().and_then(|a| a.get("version"));
        let major = match version {
            Some(serde_json::Value::String(s)) => s.split('.').next().map(str::trim),
            Some(serde_json::Value::Number(n)) => return n.as_f64().is_some_and(|v| v < 2.0),
            _ => None,
        };
        match major {
            Some(major) => major == "1",
            None => {
                self.binary_version_1
                    || [&self.nodes, &self.meshes, &self.accessors]
                        .into_iter()
                        .flatten()
                        .any(|c| c.keyed)
            }
        }
    }

    /// The version a file needs beyond 2.0, if any: its `asset.version` of another major
    /// version, or an `asset.minVersion` above 2.0 (glTF 2.0, "Versioning": a 2.0 loader must
    /// not load either).
    fn later_version(&self) -> Option<String> {
        let field = |name: &str| {
            let text = self.asset.as_ref()?.get(name)?.as_str()?.trim().to_owned();
            let (major, minor) = text.split_once('.').unwrap_or((text.as_str(), "0"));
            Some((
                major.parse::<u64>().ok()?,
                minor.parse::<u64>().ok()?,
                text.clone(),
            ))
        };
        if let Some((major, _, text)) = field("version") {
            if major > 2 {
                return Some(text);
            }
        }
        match field("minVersion") {
            Some((major, minor, text)) if (major, minor) > (2, 0) => Some(text),
            _ => None,
        }
    }

    /// Refuses a glTF 1.0 file and one that requires an extension this loader lacks;
    /// returns the used extensions it ignores, in the file's order.
    fn check(&self) -> Result<Vec<String>, String> {
        if self.is_version_1() {
            return Err("glTF 1.0 files are not supported (only glTF 2.0)".into());
        }
        if let Some(version) = self.later_version() {
            return Err(format!(
                "the file needs glTF {version}, which is not supported (only glTF 2.0)"
            ));
        }
        let unsupported = |list: &Option<serde_json::Value>| -> Vec<String> {
            let names = list.as_ref().and_then(|l| l.as_array());
            let mut out: Vec<String> = Vec::new();
            for name in names.into_iter().flatten().filter_map(|n| n.as_str()) {
                if !SUPPORTED_EXTENSIONS.contains(&name) && !out.iter().any(|o| o == name) {
                    out.push(name.to_owned());
                }
            }
            out
        };
        let required = unsupported(&self.extensions_required);
        match required.len() {
            0 => {}
            1 => {
                return Err(format!(
                    "requires the glTF extension {}, which conetrace does not support",
                    required[0]
                ))
            }
            _ => {
                return Err(format!(
                    "requires the glTF extensions {}, which conetrace does not support",
                    required.join(", ")
                ))
            }
        }
        Ok(unsupported(&self.extensions_used))
    }
}

fn wrap_mode(mode: gltf::texture::WrappingMode) -> WrapMode {
    match mode {
        gltf::texture::WrappingMode::Repeat => WrapMode::Periodic,
        gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
        gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
    }
}

/// `KHR_texture_transform`: `uv' = T(offset) * R(rotation) * S(scale) * uv`, with the
/// rotation matrix as the extension writes it, rows (cos, sin) and (-sin, cos):
/// `u' = cos u + sin v`, `v' = -sin u + cos v`. (The extension prints the matrix inside a
/// GLSL `mat3(...)` constructor, which would read the rows as columns; its own example, "the
/// lower left quadrant rotated clockwise 90 degrees" from offset (0, 1), rotation pi/2 and
/// scale 0.5, and Khronos' TextureTransformTest model hold only for the rows.) Seen on the
/// image, whose v points down, the uv axes turn counter-clockwise and the texture clockwise.
/// glTF's uv is OpenImageIO's st unchanged (`t = v`, in `Loader::add_mesh`), so the same
/// matrix applies to st.
pub(crate) fn texture_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Affine2 {
    let (sin, cos) = rotation.sin_cos();
    let [scale_u, scale_v] = scale;
    // Columns of R * S: the images of (1, 0) and (0, 1).
    Affine2::from_cols(
        Vec2::new(cos, -sin) * scale_u,
        Vec2::new(sin, cos) * scale_v,
        Vec2::from(offset),
    )
}

/// A node's local transform in f64. The `gltf` crate composes translation, rotation and scale
/// in f32; here the f32 values of the file are composed in f64.
fn local_matrix(node: &gltf::Node) -> DMat4 {
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|column| column.map(f64::from)))
        }
        gltf::scene::Transform::Decomposed {
            translation,
            rotation: [x, y, z, w],
            scale,
        } => DMat4::from_scale_rotation_translation(
            DVec3::from(scale.map(f64::from)),
            DQuat::from_xyzw(x.into(), y.into(), z.into(), w.into()),
            DVec3::from(translation.map(f64::from)),
        ),
    }
}

/// A glTF camera as its node places it, in f64. A glTF camera looks down its node's -Z with
/// +Y up.
struct CameraPose {
    eye: DVec3,
    forward: DVec3,
    up: DVec3,
    projection: Projection,
}

impl CameraPose {
    fn new(camera: &gltf::Camera, world: &DMat4) -> Result<CameraPose, String> {
        let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
        let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
        if forward == DVec3::ZERO || up == DVec3::ZERO {
            return Err(format!(
                "camera {} has a degenerate node transform",
                camera.index()
            ));
        }
        let projection = match camera.projection() {
            gltf::camera::Projection::Perspective(p) => Projection::Pinhole {
                vfov_degrees: p.yfov().to_degrees(),
            },
            gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
                height: 2.0 * o.ymag(),
            },
        };
        Ok(CameraPose {
            eye: world.transform_point3(DVec3::ZERO),
            forward,
            up,
            projection,
        })
    }

    /// The camera with its target on the view axis at the scene's distance: at least the
    /// distance from the eye to the centre of the scene's `bounds`, half their diagonal and
    /// one unit. The view direction is `target - eye` in f32, so rounding both points turns
    /// it by about an ulp of their coordinates over that distance: a target one unit from an
    /// eye 1e4 units from the origin turned the view by up to 5e-4 radians.
    fn desc(&self, bounds: Option<(Vec3, Vec3)>) -> CameraDesc {
        let reach = bounds
            .filter(|(lower, upper)| lower.is_finite() && upper.is_finite())
            .map_or(0.0, |(lower, upper)| {
                let (lower, upper) = (lower.as_dvec3(), upper.as_dvec3());
                let to_centre = (0.5 * (lower + upper) - self.eye).length();
                to_centre.max(0.5 * (upper - lower).length())
            });
        let distance = if reach.is_finite() {
            reach.max(1.0)
        } else {
            1.0
        };
        CameraDesc {
            eye: self.eye.as_vec3(),
            target: (self.eye + self.forward * distance).as_vec3(),
            up: self.up.as_vec3(),
            projection: self.projection.clone(),
        }
    }
}

/// How a material is named in messages: `material 'name' (materials[i])`.
fn material_label(m: &gltf::Material) -> String {
    let index = m.index().map_or_else(
        || "the default material".to_owned(),
        |i| format!("materials[{i}]"),
    );
    match m.name() {
        Some(name) => format!("material '{name}' ({index})"),
        None => format!("material {index}"),
    }
}

/// Refuses factors outside the ranges the glTF 2.0 schema and its material extensions give
/// them: `baseColorFactor`, `emissiveFactor`, `metallicFactor`, `roughnessFactor`,
/// `transmissionFactor` and `attenuationColor` in [0, 1], `alphaCutoff` >= 0, `ior` >= 1
/// (or exactly 0, see the caller), `attenuationDistance` > 0.
fn check_material_ranges(m: &gltf::Material) -> Result<(), String> {
    let what = material_label(m);
    let unit = |x: f32| (0.0..=1.0).contains(&x);
    let pbr = m.pbr_metallic_roughness();
    let vectors: [(&str, &[f32]); 2] = [
        (
            "pbrMetallicRoughness.baseColorFactor",
            &pbr.base_color_factor(),
        ),
        ("emissiveFactor", &m.emissive_factor()),
    ];
    for (key, values) in vectors {
        if !values.iter().all(|&x| unit(x)) {
            return Err(format!("{what}: {key} {values:?} must lie in [0, 1]"));
        }
    }
    let mut scalars = vec![
        ("pbrMetallicRoughness.metallicFactor", pbr.metallic_factor()),
        (
            "pbrMetallicRoughness.roughnessFactor",
            pbr.roughness_factor(),
        ),
    ];
    if let Some(t) = m.transmission() {
        scalars.push((
            "KHR_materials_transmission.transmissionFactor",
            t.transmission_factor(),
        ));
    }
    for (key, value) in scalars {
        if !unit(value) {
            return Err(format!("{what}: {key} {value} must lie in [0, 1]"));
        }
    }
    if let Some(strength) = m.emissive_strength() {
        if !(strength >= 0.0 && strength.is_finite()) {
            return Err(format!(
                "{what}: KHR_materials_emissive_strength.emissiveStrength {strength} must be a finite number >= 0"
            ));
        }
    }
    if let Some(normal) = m.normal_texture() {
        if !normal.scale().is_finite() {
            return Err(format!(
                "{what}: normalTexture.scale {} must be finite",
                normal.scale()
            ));
        }
    }
    if let Some(cutoff) = m.alpha_cutoff() {
        if cutoff < 0.0 {
            return Err(format!("{what}: alphaCutoff {cutoff} must be >= 0"));
        }
    }
    if let Some(ior) = m.ior() {
        if !(ior >= 1.0 || ior == 0.0) {
            return Err(format!(
                "{what}: KHR_materials_ior.ior {ior} must be >= 1 (or exactly 0)"
            ));
        }
    }
    if let Some(volume) = m.volume() {
        let color = volume.attenuation_color();
        if !color.iter().all(|&x| unit(x)) {
            return Err(format!(
                "{what}: KHR_materials_volume.attenuationColor {color:?} must lie in [0, 1]"
            ));
        }
        let distance = volume.attenuation_distance();
        if distance <= 0.0 {
            return Err(format!(
                "{what}: KHR_materials_volume.attenuationDistance {distance} must be > 0"
            ));
        }
    }
    Ok(())
}

/// Refuses `KHR_lights_punctual` values outside the extension's ranges: `color` components
/// in [0, 1], `intensity` >= 0, `range` > 0.
fn check_light_ranges(light: &gltf::khr_lights_punctual::Light) -> Result<(), String> {
    let what = match light.name() {
        Some(name) => format!(
            "light '{name}' (KHR_lights_punctual.lights[{}])",
            light.index()
        ),
        None => format!("light KHR_lights_punctual.lights[{}]", light.index()),
    };
    let color = light.color();
    if !color.iter().all(|x| (0.0..=1.0).contains(x)) {
        return Err(format!("{what}: color {color:?} must lie in [0, 1]"));
    }
    let intensity = light.intensity();
    if intensity < 0.0 {
        return Err(format!("{what}: intensity {intensity} must be >= 0"));
    }
    if let Some(range) = light.range() {
        if range <= 0.0 {
            return Err(format!("{what}: range {range} must be > 0"));
        }
    }
    Ok(())
}

/// `KHR_lights_punctual`: lights shine down their node's -Z; spot cone angles are radians.
fn convert_light(
    light: &gltf::khr_lights_punctual::Light,
    world: &Affine3A,
) -> Result<Light, String> {
    check_light_ranges(light)?;
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let color = Vec3::from(light.color());
    let intensity = light.intensity();
    if direction == Vec3::ZERO {
        return Err(format!(
            "light {} has a degenerate node transform",
            light.index()
        ));
    }
    Ok(match light.kind() {
        gltf::khr_lights_punctual::Kind::Point => Light::Point {
            position,
            color,
            intensity,
        },
        gltf::khr_lights_punctual::Kind::Directional => Light::Directional {
            direction,
            color,
            intensity,
        },
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => Light::Spot {
            position,
            direction,
            color,
            intensity,
            inner_angle: inner_cone_angle,
            outer_angle: outer_cone_angle,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::FRAC_PI_2;

    #[test]
    fn texture_transform_matches_the_extension_formula() {
        let (offset, rotation, scale) = ([0.25, -0.5], 0.3f32, [2.0, 3.0]);
        let m = texture_transform(offset, rotation, scale);
        let uv = Vec2::new(0.7, 0.2);
        // T * R * S with R's rows (cos, sin) and (-sin, cos), as the extension writes it.
        let (s, c) = rotation.sin_cos();
        let scaled = Vec2::new(uv.x * scale[0], uv.y * scale[1]);
        let rotated = Vec2::new(c * scaled.x + s * scaled.y, -s * scaled.x + c * scaled.y);
        let expected = rotated + Vec2::from(offset);
        assert!((m.transform_point2(uv) - expected).length() < 1e-6);
        // A quarter turn takes u to -v: up on the image, whose v points down.
        let quarter = texture_transform([0.0, 0.0], FRAC_PI_2, [1.0, 1.0]);
        assert!((quarter.transform_point2(Vec2::X) - Vec2::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn texture_transform_reproduces_the_extension_example() {
        // Offset (0, 1), a quarter turn and half scale read the lower left quadrant of the
        // image (u in [0, 0.5], v in [0.5, 1] with v down), turned clockwise by 90 degrees:
        // the quad's top edge (v = 0, left to right) shows the quadrant's left edge (u = 0)
        // from bottom to top.
        let m = texture_transform([0.0, 1.0], FRAC_PI_2, [0.5, 0.5]);
        let corners = [
            (Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0)),
            (Vec2::new(1.0, 0.0), Vec2::new(0.0, 0.5)),
            (Vec2::new(1.0, 1.0), Vec2::new(0.5, 0.5)),
            (Vec2::new(0.0, 1.0), Vec2::new(0.5, 1.0)),
        ];
        for (uv, expected) in corners {
            let got = m.transform_point2(uv);
            assert!(
                (got - expected).length() < 1e-6,
                "{uv} -> {got}, not {expected}"
            );
        }
    }

    fn base64(bytes: &[u8]) -> String {
        const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let v = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
            for k in 0..4 {
                if k <= chunk.len() {
                    out.push(char::from(ALPHABET[((v >> (18 - 6 * k)) & 63) as usize]));
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    /// A one-triangle glTF with every feature the loader maps; `edit` changes the JSON.
    fn synthetic(
        edit: impl FnOnce(&mut serde_json::Value),
        vertices: [[f32; 3]; 3],
    ) -> Result<SceneDescription, SceneError> {
        let mut buffer = Vec::new();
        for p in vertices {
            p.iter().for_each(|x| buffer.extend(x.to_le_bytes()));
        }
        for _ in 0..3 {
            [0.0f32, 0.0, 1.0]
                .iter()
                .for_each(|x| buffer.extend(x.to_le_bytes()));
        }
        for uv in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
            uv.iter().for_each(|x| buffer.extend(x.to_le_bytes()));
        }
        for i in [0u16, 1, 2, 0] {
            buffer.extend(i.to_le_bytes());
        }
        let png = b"\x89PNG fake image bytes";
        let mut json = serde_json::json!({
            "asset": {"version": "2.0"},
            "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior",
                               "KHR_materials_volume", "KHR_texture_transform"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1, 0.5, 0.25], "intensity": 10},
                {"type": "spot", "intensity": 5, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}},
                {"type": "directional", "intensity": 2}
            ]}},
            "scene": 0,
            "scenes": [{"nodes": [0, 3]}],
            "nodes": [
                {"translation": [10, 0, 0], "scale": [2, 1, 1], "children": [1, 2], "mesh": 0},
                {"camera": 0, "translation": [0, 0, 5]},
                {"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-std::f32::consts::FRAC_1_SQRT_2, 0, 0, std::f32::consts::FRAC_1_SQRT_2]},
                {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 3, 0]}
            ],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
            "meshes": [{"name": "tri", "primitives": [{
                "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]}],
            "materials": [{
                "name": "jelly",
                "pbrMetallicRoughness": {
                    "baseColorFactor": [0.5, 0.6, 0.7, 0.8],
                    "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform":
                        {"offset": [0.5, 0.25], "rotation": 0.0, "scale": [2, 4]}}},
                    "metallicFactor": 0.0
                },
                "alphaMode": "MASK", "alphaCutoff": 0.3,
                "emissiveFactor": [0.1, 0.2, 0.3],
                "extensions": {
                    "KHR_materials_transmission": {"transmissionFactor": 0.9},
                    "KHR_materials_ior": {"ior": 1.33},
                    "KHR_materials_volume": {"attenuationColor": [0.5, 1.0, 1.0], "attenuationDistance": 2.0}
                }
            }],
            "textures": [{"source": 0, "sampler": 0}],
            "samplers": [{"wrapS": 33071, "wrapT": 33648}],
            "images": [{"uri": format!("data:image/png;base64,{}", base64(png))}],
            "buffers": [{"byteLength": buffer.len(), "uri": format!("data:application/octet-stream;base64,{}", base64(&buffer))}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96}, {"buffer": 0, "byteOffset": 96, "byteLength": 8}],
            "accessors": [
                {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 0]},
                {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 3, "type": "VEC2"},
                {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 3, "type": "SCALAR"}
            ]
        });
        edit(&mut json);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("synthetic.gltf");
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        load_gltf(&Files::disk(dir.path()), &path)
    }

    const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn synthetic_file_maps_every_feature() {
        let part = synthetic(|_| {}, TRIANGLE).unwrap_or_else(|e| panic!("{e}"));
        let mesh = &part.meshes[0];
        // Node 0: scale x by 2, then translate by 10.
        assert_eq!(mesh.positions[1], Vec3::new(12.0, 0.0, 0.0));
        assert_eq!(mesh.normals[0], Vec3::Z);
        assert_eq!(mesh.st[2], Vec2::new(0.0, 1.0), "glTF v is t directly");
        let m = &part.materials[mesh.material];
        assert_eq!(m.base_color, Vec3::new(0.5, 0.6, 0.7));
        assert_eq!(m.alpha, 0.8);
        assert_eq!(m.alpha_cutoff, Some(0.3));
        assert_eq!(m.transmission, 0.9);
        assert_eq!(m.ior, 1.33);
        assert_eq!(m.attenuation_color, Vec3::new(0.5, 1.0, 1.0));
        assert_eq!(m.attenuation_distance, 2.0);
        assert_eq!(m.emission, Vec3::new(0.1, 0.2, 0.3));
        assert_eq!(m.mirror, 0.0);
        let color = m.base_color_texture.as_ref().unwrap();
        let alpha = m.alpha_texture.as_ref().unwrap();
        assert_eq!(
            color.transform.transform_point2(Vec2::ONE),
            Vec2::new(2.5, 4.25)
        );
        assert_eq!(color.transform, alpha.transform);
        let (ct, at) = (&part.textures[color.texture], &part.textures[alpha.texture]);
        assert_eq!(
            (ct.color_space, at.color_space),
            (Some(ColorSpace::Srgb), Some(ColorSpace::Linear))
        );
        assert_eq!((ct.wrap_s, ct.wrap_t), (WrapMode::Clamp, WrapMode::Mirror));
        let TextureSource::Encoded { bytes, .. } = &ct.source else {
            panic!("data URI image should stay encoded")
        };
        assert_eq!(&bytes[..4], b"\x89PNG");
        // Camera at node 1 (child of node 0): eye = (10, 0, 5), looking down -z.
        let camera = part.camera.as_ref().unwrap();
        assert_eq!(camera.eye, Vec3::new(10.0, 0.0, 5.0));
        // Its target is on the view axis, as far as the centre of the scene's bounds
        // (the triangle scaled by node 0 spans (10, 0, 0)-(12, 1, 0)).
        let distance = Vec3::new(1.0, 0.5, -5.0).length();
        assert!((camera.target - (camera.eye + Vec3::NEG_Z * distance)).length() < 1e-5);
        assert!(
            matches!(camera.projection, Projection::Pinhole { vfov_degrees } if (vfov_degrees - 0.5f32.to_degrees()).abs() < 1e-4)
        );
        // Lights: the spot at node 2 is rotated -90 deg about x, so it shines down -y.
        assert_eq!(part.lights.len(), 2);
        let Light::Spot {
            direction,
            position,
            inner_angle,
            outer_angle,
            ..
        } = part.lights[0]
        else {
            panic!("spot first")
        };
        assert!((direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
        assert_eq!(position, Vec3::new(10.0, 0.0, 0.0));
        assert_eq!((inner_angle, outer_angle), (0.1, 0.5));
        assert!(
            matches!(part.lights[1], Light::Point { position, intensity, .. } if position == Vec3::new(0.0, 3.0, 0.0) && intensity == 10.0)
        );
    }

    #[test]
    fn metallic_roughness_factors_select_the_model() {
        // Factors left out of pbrMetallicRoughness default to 1 (glTF 2.0, material schema).
        let part = synthetic(
            |j| {
                let pbr = j["materials"][0]["pbrMetallicRoughness"]
                    .as_object_mut()
                    .unwrap();
                pbr.remove("metallicFactor");
            },
            TRIANGLE,
        )
        .unwrap();
        let m = &part.materials[0];
        let factors = m
            .model
            .metallic_roughness()
            .map(|mr| (mr.roughness, mr.metallic));
        assert_eq!(factors, Some((1.0, 1.0)));
        assert_eq!(m.base_color, Vec3::new(0.5, 0.6, 0.7), "no longer scaled");
        assert_eq!(m.mirror, 0.0);
        let part = synthetic(
            |j| {
                let pbr = &mut j["materials"][0]["pbrMetallicRoughness"];
                pbr["metallicFactor"] = 0.25.into();
                pbr["roughnessFactor"] = 0.5.into();
            },
            TRIANGLE,
        )
        .unwrap();
        let m = &part.materials[0];
        let factors = m
            .model
            .metallic_roughness()
            .map(|mr| (mr.roughness, mr.metallic));
        assert_eq!(factors, Some((0.5, 0.25)));
        let maps = m.model.metallic_roughness().unwrap();
        assert!(maps.metallic_roughness_texture.is_none() && m.normal_texture.is_none());
    }

    #[test]
    fn textured_inputs_are_bound_with_their_colour_spaces() {
        let part = synthetic(
            |j| {
                j["extensionsUsed"]
                    .as_array_mut()
                    .unwrap()
                    .push("KHR_materials_emissive_strength".into());
                let image = j["images"][0].clone();
                j["images"].as_array_mut().unwrap().push(image);
                j["textures"] = serde_json::json!([{"source": 0, "sampler": 0}, {"source": 1}]);
                let m = &mut j["materials"][0];
                m["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
                    serde_json::json!({"index": 1});
                m["emissiveTexture"] = serde_json::json!({"index": 0});
                m["normalTexture"] = serde_json::json!({"index": 1, "scale": 0.5,
                    "extensions": {"KHR_texture_transform": {"scale": [3, 3]}}});
                m["extensions"]["KHR_materials_emissive_strength"] =
                    serde_json::json!({"emissiveStrength": 8.0});
            },
            TRIANGLE,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let m = &part.materials[0];
        assert_eq!(m.emission, Vec3::new(0.1, 0.2, 0.3) * 8.0);
        assert_eq!(m.normal_scale, 0.5);
        let space =
            |b: &Option<TextureBinding>| part.textures[b.as_ref().unwrap().texture].color_space;
        let model = m
            .model
            .metallic_roughness()
            .expect("the metallic-roughness model");
        assert_eq!(
            space(&model.metallic_roughness_texture),
            Some(ColorSpace::Linear)
        );
        assert_eq!(space(&m.normal_texture), Some(ColorSpace::Linear));
        assert_eq!(space(&m.emission_texture), Some(ColorSpace::Srgb));
        // The same image as data (metallic-roughness, normal) is one texture.
        assert_eq!(
            model.metallic_roughness_texture.as_ref().unwrap().texture,
            m.normal_texture.as_ref().unwrap().texture
        );
        let normal = m.normal_texture.as_ref().unwrap();
        assert_eq!(
            normal.transform.transform_point2(Vec2::ONE),
            Vec2::splat(3.0)
        );
    }

    #[test]
    fn bad_textured_input_values_are_errors() {
        type Edit = Box<dyn FnOnce(&mut serde_json::Value)>;
        let cases: Vec<(Edit, &str)> = vec![
            (
                Box::new(|j| {
                    j["materials"][0]["extensions"]["KHR_materials_emissive_strength"] =
                        serde_json::json!({"emissiveStrength": -1.0})
                }),
                "emissiveStrength -1 must be a finite number >= 0",
            ),
            (
                Box::new(|j| {
                    j["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = 1.5.into()
                }),
                "roughnessFactor 1.5 must lie in [0, 1]",
            ),
        ];
        for (edit, expected) in cases {
            let e = synthetic(edit, TRIANGLE).unwrap_err().to_string();
            assert!(e.contains("synthetic.gltf") && e.contains(expected), "{e}");
            assert_eq!(e.lines().count(), 1, "{e}");
        }
    }

    /// An image file that cannot be read is left out with one note, as an MTL map or a TOML
    /// texture is; the material keeps its factors. A missing buffer stays an error
    /// (`malformed_synthetic_files_are_errors`).
    #[test]
    fn missing_image_files_are_left_out_with_a_note() {
        let part = synthetic(
            |j| {
                j["images"]
                    .as_array_mut()
                    .unwrap()
                    .push(serde_json::json!({"uri": "no_such_normals.png"}));
                j["textures"]
                    .as_array_mut()
                    .unwrap()
                    .push(serde_json::json!({"source": 1}));
                let m = &mut j["materials"][0];
                m["normalTexture"] = serde_json::json!({"index": 1});
                m["emissiveTexture"] = serde_json::json!({"index": 1});
            },
            TRIANGLE,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let m = &part.materials[0];
        assert!(m.normal_texture.is_none() && m.emission_texture.is_none());
        assert!(
            m.base_color_texture.is_some(),
            "the data: image still loads"
        );
        assert_eq!(m.emission, Vec3::new(0.1, 0.2, 0.3));
        let notes: Vec<&String> = part
            .notes
            .iter()
            .filter(|n| n.contains("no_such_normals.png"))
            .collect();
        assert_eq!(notes.len(), 1, "{:?}", part.notes);
        assert!(
            notes[0].ends_with(
                "synthetic.gltf: image 1 'no_such_normals.png' not loaded (no such file): \
                 textures using it are left out"
            ),
            "{}",
            notes[0]
        );
    }

    /// A camera node 1e4 units from the origin looking obliquely at it: the view direction
    /// the camera gets (`target - eye`, in f32) is the node's -Z to f32 precision. With the
    /// target one unit in front of the eye it was off by 1.6e-4 radians.
    #[test]
    fn a_distant_camera_keeps_its_view_direction() {
        let away = DVec3::new(0.3, 0.5, 0.8).normalize();
        let x_axis = DVec3::Y.cross(away).normalize();
        let rotation = DQuat::from_mat3(&glam::DMat3::from_cols(x_axis, away.cross(x_axis), away));
        let eye = away * 1e4;
        let part = synthetic(
            |j| {
                j["nodes"][1] = serde_json::json!({"camera": 0,
                    "translation": eye.to_array(), "rotation": rotation.to_array()});
                j["scenes"][0]["nodes"] = serde_json::json!([0, 1]);
                j["nodes"][0]["children"] = serde_json::json!([2]);
            },
            TRIANGLE,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let camera = part.camera.unwrap();
        let view = (camera.target - camera.eye).as_dvec3().normalize();
        let error = view.angle_between(-away);
        assert!(error < 2e-7, "view direction off by {error} radians");
    }

    #[test]
    fn orthographic_cameras_use_twice_ymag() {
        let part = synthetic(
            |j| j["cameras"][0] = serde_json::json!({"type": "orthographic", "orthographic": {"xmag": 3, "ymag": 2, "znear": 0, "zfar": 10}}),
            TRIANGLE,
        )
        .unwrap();
        assert_eq!(
            part.camera.unwrap().projection,
            Projection::Orthographic { height: 4.0 }
        );
    }

    #[test]
    fn malformed_synthetic_files_are_errors() {
        type Edit = Box<dyn FnOnce(&mut serde_json::Value)>;
        let cases: Vec<(Edit, &str)> = vec![
            (
                Box::new(|j| j["nodes"][3]["children"] = serde_json::json!([1])),
                "child of both",
            ),
            (
                Box::new(|j| j["nodes"][1]["children"] = serde_json::json!([0])),
                "recursive",
            ),
            (
                Box::new(|j| j["accessors"][0]["count"] = 9.into()),
                "past the end",
            ),
            (
                Box::new(|j| j["bufferViews"][1]["byteLength"] = 200.into()),
                "outside its buffer",
            ),
            (
                Box::new(|j| j["buffers"][0]["uri"] = "missing.bin".into()),
                "missing.bin",
            ),
            (
                Box::new(|j| j["meshes"][0]["primitives"][0]["material"] = 7.into()),
                "Index out of bounds",
            ),
            (
                Box::new(|j| j["accessors"][3]["componentType"] = 5122.into()),
                "index accessor 3 holds Scalar of I16; indices must be unsigned",
            ),
            (
                Box::new(|j| j["accessors"][3]["componentType"] = 5126.into()),
                "index accessor 3 holds Scalar of F32; indices must be unsigned",
            ),
            (
                Box::new(|j| j["accessors"][3]["type"] = "VEC2".into()),
                "index accessor 3 holds Vec2 of U16; indices must be unsigned",
            ),
        ];
        for (edit, expected) in cases {
            let e = synthetic(edit, TRIANGLE).unwrap_err().to_string();
            assert!(e.contains("synthetic.gltf") && e.contains(expected), "{e}");
        }
        let nan = [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let part = synthetic(|_| {}, nan).unwrap();
        let scene = SceneDescription {
            source: "synthetic.gltf".into(),
            ..part
        };
        assert!(super::super::validate(&scene)
            .unwrap_err()
            .to_string()
            .contains("not finite"));
    }

    /// A zero normal (Khronos' BoxBadNormals has four) is repaired with a note, as in OBJ.
    #[test]
    fn zero_normals_are_replaced_by_the_face_normal() {
        // The NORMAL accessor reads the positions: vertex 0's normal is (0, 0, 0).
        let part = synthetic(|j| j["accessors"][1]["byteOffset"] = 0.into(), TRIANGLE)
            .unwrap_or_else(|e| panic!("{e}"));
        let mesh = &part.meshes[0];
        assert!(
            (mesh.normals[0] - Vec3::Z).length() < 1e-6,
            "{}",
            mesh.normals[0]
        );
        assert!(
            part.notes.iter().any(|n| n.contains(
                "synthetic.gltf: mesh 'tri' primitive 0: 1 zero-length normals replaced"
            )),
            "{:?}",
            part.notes
        );
        let scene = SceneDescription {
            source: "synthetic.gltf".into(),
            ..part
        };
        super::super::validate(&scene).unwrap_or_else(|e| panic!("{e}"));
    }

    #[test]
    fn indices_of_every_unsigned_width_are_read_little_endian() {
        let bytes = [0xfe, 0xdc, 0xba, 0x98];
        assert_eq!(IndexType::U8.read(&bytes), 0xfe);
        assert_eq!(IndexType::U16.read(&bytes), 0xdcfe);
        assert_eq!(IndexType::U32.read(&bytes), 0x98ba_dcfe);
        for (data_type, index_type) in [
            (DataType::U8, Some(IndexType::U8)),
            (DataType::U16, Some(IndexType::U16)),
            (DataType::U32, Some(IndexType::U32)),
            (DataType::I8, None),
            (DataType::I16, None),
            (DataType::F32, None),
        ] {
            assert_eq!(IndexType::of(data_type), index_type, "{data_type:?}");
            if let Some(index_type) = index_type {
                assert_eq!(index_type.size(), data_type.size());
            }
        }
    }

    #[test]
    fn strips_and_fans_become_triangles() {
        assert_eq!(strip_triangles(&[0, 1, 2, 3]), vec![[0, 1, 2], [2, 1, 3]]);
        assert_eq!(fan_triangles(&[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
        assert!(strip_triangles(&[0, 1]).is_empty());
        assert!(fan_triangles(&[]).is_empty());
    }

    /// Every way a 1.0 file shows itself: the version as a string or as a number (as
    /// CesiumMilkTruck writes it), id-keyed collections, a version 1 binary container, and a
    /// 1.0 JSON chunk in a version 2 container.
    #[test]
    fn gltf_1_files_are_named_as_such() {
        let version_1 = |bytes: &[u8]| Preamble::of(bytes).unwrap().is_version_1();
        assert!(version_1(br#"{"asset": {"version": "1.0"}}"#));
        assert!(version_1(br#"{"asset": {"version": 1}}"#));
        assert!(version_1(br#"{"asset": {}, "meshes": {"mesh_1": {}}}"#));
        assert!(version_1(b"glTF\x01\0\0\0"));
        assert!(!version_1(
            br#"{"asset": {"version": "2.0"}, "meshes": []}"#
        ));
        assert!(!version_1(br#"{"asset": {}, "meshes": [{}]}"#));
        let mut glb = b"glTF\x02\0\0\0\0\0\0\0".to_vec();
        let json = br#"{"asset": {"version": "1.0"}}"#;
        glb.extend((json.len() as u32).to_le_bytes());
        glb.extend(b"JSON");
        glb.extend(json);
        assert!(version_1(&glb));
        let e = Preamble::of(br#"{"asset": {"version": 1}}"#)
            .unwrap()
            .check()
            .unwrap_err();
        assert_eq!(e, "glTF 1.0 files are not supported (only glTF 2.0)");
    }

    /// A file of a later major version, or whose minVersion is above 2.0, is refused naming
    /// the version; 2.0 files with a minVersion of 2.0 load.
    #[test]
    fn later_gltf_versions_are_refused() {
        let check = |json: &[u8]| Preamble::of(json).unwrap().check();
        for (json, version) in [
            (&br#"{"asset": {"version": "3.0"}}"#[..], "3.0"),
            (
                br#"{"asset": {"version": "2.0", "minVersion": "2.1"}}"#,
                "2.1",
            ),
        ] {
            let e = check(json).unwrap_err();
            assert_eq!(
                e,
                format!("the file needs glTF {version}, which is not supported (only glTF 2.0)")
            );
        }
        assert!(check(br#"{"asset": {"version": "2.0", "minVersion": "2.0"}}"#).is_ok());
        assert!(check(br#"{"asset": {"version": "2.1"}}"#).is_ok());
    }

    /// A required extension the loader lacks is named, not the validation problems it causes
    /// (a Draco-compressed accessor has no buffer view); used ones it ignores are noted.
    #[test]
    fn required_extensions_refuse_and_used_ones_are_noted() {
        let e = synthetic(
            |j| {
                j["extensionsRequired"] = serde_json::json!(["KHR_draco_mesh_compression"]);
                j["extensionsUsed"]
                    .as_array_mut()
                    .unwrap()
                    .push("KHR_draco_mesh_compression".into());
                j["accessors"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("bufferView");
            },
            TRIANGLE,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.ends_with(
                "synthetic.gltf: requires the glTF extension KHR_draco_mesh_compression, \
                 which conetrace does not support"
            ),
            "{e}"
        );
        let part = synthetic(
            |j| {
                let used = j["extensionsUsed"].as_array_mut().unwrap();
                used.push("KHR_materials_clearcoat".into());
                used.push("KHR_materials_sheen".into());
                j["extensionsRequired"] = serde_json::json!(["KHR_texture_transform"]);
            },
            TRIANGLE,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let ignored: Vec<&String> = part
            .notes
            .iter()
            .filter(|n| n.contains("which conetrace ignores"))
            .collect();
        assert_eq!(ignored.len(), 2, "{:?}", part.notes);
        assert!(ignored[0].contains("uses the glTF extension KHR_materials_clearcoat"));
        assert!(ignored[1].contains("KHR_materials_sheen"));
    }

    #[test]
    fn accessor_elements_are_bounds_checked() {
        let data = [0u8; 24];
        assert!(Elements::new(&data, 0, 12, 12, 2, "a").is_ok());
        assert!(Elements::new(&data, 4, 12, 12, 2, "a").is_err());
        assert!(Elements::new(&data, 0, usize::MAX, 12, 3, "a").is_err());
    }

    #[test]
    fn normalized_components_decode_per_spec() {
        assert_eq!(component(DataType::U8, &[255], true), 1.0);
        assert_eq!(component(DataType::I8, &[0x80], true), -1.0);
        assert_eq!(component(DataType::U16, &[0xff, 0xff], true), 1.0);
        assert_eq!(component(DataType::U16, &[2, 0], false), 2.0);
    }
}
