//! A scene made ready to render: decoded textures, the committed Embree scene, the camera,
//! and the lookups that turn an Embree hit back into a [`SurfaceHit`].

use std::sync::Arc;

use glam::{Affine2, Vec2, Vec3};

use crate::hit::{Patch, SurfaceHit};
use crate::render::tracer::TraceHit;
use crate::scene::{Environment, Material, SceneDescription, TextureDesc, TextureSource};
use crate::shading::ray_offset::SpawnPoint;
use crate::texture::{FilterMode, FilterOptions, Texture, TextureQuery, TileCache};

/// What an Embree geometry id stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryRef {
    Mesh(usize),
    /// All spheres live in one geometry; the primitive id indexes `SceneDescription::spheres`.
    Spheres,
    /// All curved patches live in one user geometry; the primitive id indexes
    /// `SceneDescription::patches`.
    Patches,
    /// All height patches live in one user geometry traced by marching; the primitive id
    /// indexes `SceneDescription::height_patches`.
    HeightPatches,
}

/// Per-material values the integrator needs on every hit, computed once.
#[derive(Clone, Debug)]
pub struct MaterialTable {
    /// Beer's-law absorption coefficient per material (zero when it has no medium).
    pub sigma: Vec<Vec3>,
}

/// Failure to prepare a scene for rendering (textures that do not decode, Embree errors).
#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    #[error("{0}")]
    Texture(#[from] crate::texture::TextureError),
    #[error("{source_label}: Embree: {message}")]
    Embree {
        source_label: String,
        message: String,
    },
    #[error("{source_label}: {message}")]
    Invalid {
        source_label: String,
        message: String,
    },
}

/// Decode every texture of `scene` (sRGB colour textures are decoded to linear on load),
/// `.tx` files opened tile by tile through the process-wide texture cache.
pub fn decode_textures(scene: &SceneDescription) -> Result<Vec<Arc<Texture>>, PrepareError> {
    decode_textures_in(scene, &TileCache::shared())
}

/// [`decode_textures`] with the tiles of `.tx` files kept in `cache`, under its cap.
pub fn decode_textures_in(
    scene: &SceneDescription,
    cache: &Arc<TileCache>,
) -> Result<Vec<Arc<Texture>>, PrepareError> {
    scene
        .textures
        .iter()
        .map(|desc| Ok(Arc::new(decode_texture_in(desc, cache)?)))
        .collect()
}

/// Decode one texture of a scene from its file or embedded bytes.
pub fn decode_texture(desc: &TextureDesc) -> Result<Texture, crate::texture::TextureError> {
    decode_texture_in(desc, &TileCache::shared())
}

/// [`decode_texture`] with the tiles of a `.tx` file kept in `cache`.
pub fn decode_texture_in(
    desc: &TextureDesc,
    cache: &Arc<TileCache>,
) -> Result<Texture, crate::texture::TextureError> {
    match &desc.source {
        TextureSource::File(path) => Texture::from_file_in(path, desc.color_space, cache),
        TextureSource::Encoded { label, bytes } => {
            Texture::from_encoded(bytes, label, desc.color_space)
        }
    }
}

impl MaterialTable {
    pub fn new(materials: &[Material]) -> MaterialTable {
        MaterialTable {
            sigma: materials
                .iter()
                .map(|m| {
                    crate::shading::sigma_from_attenuation(
                        m.attenuation_color,
                        m.attenuation_distance,
                    )
                })
                .collect(),
        }
    }
}

/// Surface data of a prepared scene, independent of Embree: turns Embree's
/// (geometry, primitive, u, v, t) back into a [`SurfaceHit`].
pub struct SurfaceLookup {
    pub scene: Arc<SceneDescription>,
    pub geometries: Vec<GeometryRef>,
    /// Per material: whether shading it reads a texture (so hits need texture coordinates).
    pub textured_materials: Vec<bool>,
    /// Per material: whether it has a normal map (whose tangent frame needs dP/ds, dP/dt).
    pub normal_mapped_materials: Vec<bool>,
    /// Bounds of every surface (`None` for an empty scene): camera rays start tracing
    /// where they enter them (`crate::shading::entry_distance`).
    pub bounds: Option<(Vec3, Vec3)>,
}

/// How much of the surface a caller needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SurfaceDetail {
    /// Position and normals only (shadow-ray walks, untextured materials).
    Geometry,
    /// Also texture coordinates, without dP/ds and dP/dt (lookups that no footprint filters
    /// and no normal map bends, the uv AOV).
    TextureCoordinates,
    /// Also texture coordinates and dP/ds, dP/dt (footprints, normal maps).
    Texturing,
}

impl SurfaceLookup {
    pub fn new(scene: Arc<SceneDescription>, geometries: Vec<GeometryRef>) -> SurfaceLookup {
        let textured_materials = scene
            .materials
            .iter()
            .map(crate::render::surface_textures::reads_textures)
            .collect();
        let normal_mapped_materials = scene
            .materials
            .iter()
            .map(|material| material.normal_texture.is_some())
            .collect();
        let bounds = scene.bounds();
        SurfaceLookup {
            scene,
            geometries,
            textured_materials,
            normal_mapped_materials,
            bounds,
        }
    }

    /// How much of the surface at `hit` is needed: texture coordinates when its material
    /// reads a texture or `coordinates_wanted` (the camera hit's AOVs); dP/ds and dP/dt as
    /// well when `footprints` are filtered or the material's normal map needs its tangent
    /// frame.
    #[inline]
    pub fn detail_needed(
        &self,
        hit: &TraceHit,
        coordinates_wanted: bool,
        footprints: bool,
    ) -> SurfaceDetail {
        let material = self.material_index(hit);
        if !(coordinates_wanted || self.textured_materials[material]) {
            SurfaceDetail::Geometry
        } else if footprints || self.normal_mapped_materials[material] {
            SurfaceDetail::Texturing
        } else {
            SurfaceDetail::TextureCoordinates
        }
    }

    /// The index of the material at `hit`.
    #[inline]
    fn material_index(&self, hit: &TraceHit) -> usize {
        match self.geometries[hit.geometry as usize] {
            GeometryRef::Mesh(index) => self.scene.meshes[index].material,
            GeometryRef::Spheres => self.scene.spheres[hit.primitive as usize].material,
            GeometryRef::Patches => self.scene.patches[hit.primitive as usize].material,
            GeometryRef::HeightPatches => {
                self.scene.height_patches[hit.primitive as usize].material
            }
        }
    }

    /// The surface at `hit` of the ray (`origin`, unit `direction`).
    ///
    /// The position is recomputed from the surface, not taken as `origin + t * direction`:
    /// that point carries rounding errors of the ray's origin and length (a camera 1e4 units
    /// away puts it some 1e-3 off a unit sphere), while the recomputed point's error bound
    /// depends only on the surface (`crate::shading::ray_offset`). `t` stays as the
    /// intersector reported it.
    pub fn surface_hit(
        &self,
        origin: Vec3,
        direction: Vec3,
        hit: &TraceHit,
        detail: SurfaceDetail,
    ) -> SurfaceHit {
        let texturing = detail != SurfaceDetail::Geometry;
        let derivatives = detail == SurfaceDetail::Texturing;
        match self.geometries[hit.geometry as usize] {
            GeometryRef::Mesh(index) => {
                let mesh = &self.scene.meshes[index];
                let [i0, i1, i2] = mesh.triangles[hit.primitive as usize];
                let (i0, i1, i2) = (i0 as usize, i1 as usize, i2 as usize);
                let p = [mesh.positions[i0], mesh.positions[i1], mesh.positions[i2]];
                let (u, v) = (hit.u, hit.v);
                let w = 1.0 - u - v;
                let position = SpawnPoint::on_triangle(p, u, v).position;
                let e1 = p[1] - p[0];
                let e2 = p[2] - p[0];
                let geometric_normal = e1.cross(e2).normalize_or(Vec3::Y);
                let n = (!mesh.normals.is_empty())
                    .then(|| [mesh.normals[i0], mesh.normals[i1], mesh.normals[i2]]);
                let mut shading_normal = match n {
                    Some(n) => {
                        let interpolated = n[0] * w + n[1] * u + n[2] * v;
                        if interpolated.is_finite() {
                            interpolated.normalize_or(geometric_normal)
                        } else {
                            geometric_normal
                        }
                    }
                    None => geometric_normal,
                };
                // Interpolated normals may face away from the geometry: keep them on its side.
                if shading_normal.dot(geometric_normal) < 0.0 {
                    shading_normal = -shading_normal;
                }
                let st_vertices =
                    (!mesh.st.is_empty()).then(|| [mesh.st[i0], mesh.st[i1], mesh.st[i2]]);
                let (st, dpds, dpdt) = match st_vertices {
                    Some(t) if texturing => {
                        let st = t[0] * w + t[1] * u + t[2] * v;
                        let (dpds, dpdt) = if derivatives {
                            triangle_position_derivatives(p, t)
                        } else {
                            (Vec3::ZERO, Vec3::ZERO)
                        };
                        (st, dpds, dpdt)
                    }
                    _ => (Vec2::ZERO, Vec3::ZERO, Vec3::ZERO),
                };
                SurfaceHit {
                    t: hit.t,
                    position,
                    geometric_normal,
                    shading_normal,
                    barycentric: Vec2::new(u, v),
                    st,
                    dpds,
                    dpdt,
                    material: mesh.material as u32,
                    patch: Patch::Triangle {
                        p,
                        n,
                        st: st_vertices,
                    },
                }
            }
            GeometryRef::Spheres => {
                let sphere = &self.scene.spheres[hit.primitive as usize];
                // Project the ray's point onto the sphere: the ray only picks the direction
                // from the centre, so the point's error does not depend on the ray.
                let (spawn, normal) =
                    SpawnPoint::on_sphere(sphere.center, sphere.radius, origin + direction * hit.t);
                let position = spawn.position;
                // The lat-long frame costs two inverse trigonometric functions: only when needed.
                let (st, dpds, dpdt) = if texturing {
                    crate::footprint::lat_long_frame(normal, sphere.radius)
                } else {
                    (Vec2::ZERO, Vec3::ZERO, Vec3::ZERO)
                };
                SurfaceHit {
                    t: hit.t,
                    position,
                    geometric_normal: normal,
                    shading_normal: normal,
                    barycentric: st,
                    st,
                    dpds,
                    dpdt,
                    material: sphere.material as u32,
                    patch: Patch::Sphere {
                        center: sphere.center,
                        radius: sphere.radius,
                    },
                }
            }
            GeometryRef::Patches => crate::render::patch_geometry::patch_surface_hit(
                &self.scene.patches[hit.primitive as usize],
                hit,
                texturing,
            ),
            // The marched hit's (u, v) are those of the same surface as a Bezier patch.
            GeometryRef::HeightPatches => crate::render::patch_geometry::patch_surface_hit(
                &self.scene.height_patches[hit.primitive as usize].to_bezier(),
                hit,
                texturing,
            ),
        }
    }
}

/// dP/ds and dP/dt of a triangle with texture coordinates `t` (zero if the st mapping is
/// degenerate).
pub(crate) fn triangle_position_derivatives(p: [Vec3; 3], t: [Vec2; 3]) -> (Vec3, Vec3) {
    let dp1 = p[1] - p[0];
    let dp2 = p[2] - p[0];
    let dt1 = t[1] - t[0];
    let dt2 = t[2] - t[0];
    let det = dt1.x * dt2.y - dt1.y * dt2.x;
    if !det.is_finite() || det.abs() < 1e-20 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let inv = 1.0 / det;
    let dpds = (dp1 * dt2.y - dp2 * dt1.y) * inv;
    let dpdt = (dp2 * dt1.x - dp1 * dt2.x) * inv;
    if dpds.is_finite() && dpdt.is_finite() {
        (dpds, dpdt)
    } else {
        (Vec3::ZERO, Vec3::ZERO)
    }
}

/// The query for a binding: st and gradients through the binding's affine transform.
#[inline]
pub fn binding_query(transform: &Affine2, st: Vec2, g: [f32; 4]) -> TextureQuery {
    let st = transform.transform_point2(st);
    let dx = transform.matrix2 * Vec2::new(g[0], g[1]);
    let dy = transform.matrix2 * Vec2::new(g[2], g[3]);
    TextureQuery {
        s: st.x,
        t: st.y,
        dsdx: dx.x,
        dtdx: dx.y,
        dsdy: dy.x,
        dtdy: dy.y,
    }
}

/// The render's filter options with each texture's own wrap modes, one per texture.
pub fn texture_filters(scene: &SceneDescription, filter: &FilterOptions) -> Vec<FilterOptions> {
    scene
        .textures
        .iter()
        .map(|desc| FilterOptions {
            wrap_s: desc.wrap_s,
            wrap_t: desc.wrap_t,
            ..*filter
        })
        .collect()
}

/// The environment seen in direction `dir` (unfiltered background colour or filtered lat-long
/// lookup with the given gradients), from `external` when given.
pub fn environment_radiance(
    environment: &Environment,
    textures: &[Arc<Texture>],
    dir: Vec3,
    gradients: [f32; 4],
    texture_filters: &[FilterOptions],
    external: Option<&dyn crate::render::ExternalTextures>,
) -> Vec3 {
    let options = |texture: usize| texture_filters[texture];
    environment_radiance_with(environment, textures, dir, gradients, options, external)
}

/// The environment as a light: the radiance of the level-0 texel `dir` falls in, the
/// piecewise-constant function its importance sampling is built on
/// (`crate::shading::environment_light`; pbrt-v4's image infinite light reads its nearest
/// texel too). A filtered lookup would spread a small sun into texels the sampling rarely
/// visits, and light sampling and a BSDF ray that escapes must read one function.
pub fn environment_light_radiance(
    environment: &Environment,
    textures: &[Arc<Texture>],
    dir: Vec3,
    texture_filters: &[FilterOptions],
    external: Option<&dyn crate::render::ExternalTextures>,
) -> Vec3 {
    let options = |texture: usize| FilterOptions {
        filter: FilterMode::Closest,
        ..texture_filters[texture]
    };
    environment_radiance_with(environment, textures, dir, [0.0; 4], options, external)
}

fn environment_radiance_with(
    environment: &Environment,
    textures: &[Arc<Texture>],
    dir: Vec3,
    gradients: [f32; 4],
    texture_options: impl Fn(usize) -> FilterOptions,
    external: Option<&dyn crate::render::ExternalTextures>,
) -> Vec3 {
    match environment {
        Environment::Color(c) => *c,
        Environment::LatLong { texture, intensity } => {
            let options = &texture_options(*texture);
            let st = crate::footprint::direction_to_lat_long(dir);
            let q = TextureQuery {
                s: st.x,
                t: st.y,
                dsdx: gradients[0],
                dtdx: gradients[1],
                dsdy: gradients[2],
                dtdy: gradients[3],
            };
            let texel = match external {
                Some(external) => crate::render::external_textures::sample_external(
                    external, *texture, &q, options,
                ),
                None => textures[*texture].sample(&q, options),
            };
            // Radiance is never negative; a filtered lookup of stored levels made with a
            // ringing filter (`maketx --filter lanczos3`) can be.
            (texel.truncate() * *intensity).max(Vec3::ZERO)
        }
    }
}

/// Average radiance of the environment over the sphere of directions, (1 / 4pi) times the
/// integral of L over solid angle: the ambient term that lights diffuse surfaces.
///
/// A lat-long map's texel row j covers the band of polar angles [pi j / h, pi (j + 1) / h],
/// whose share of the sphere is (cos theta0 - cos theta1) / 2 (the integral of
/// sin theta dtheta dphi / 4pi). Each row is weighted by that exact share, so rows near the
/// poles, stretched over the full width of the map, count for the little sky they cover.
pub fn environment_mean(environment: &Environment, textures: &[Arc<Texture>]) -> Vec3 {
    match environment {
        Environment::Color(c) => *c,
        Environment::LatLong { texture, intensity } => {
            let level = &textures[*texture].pyramid().levels[0];
            let (width, height) = (level.width as usize, level.height as usize);
            let polar_angle = |row: usize| std::f64::consts::PI * row as f64 / height as f64;
            let mut mean = [0.0f64; 3];
            for row in 0..height {
                let band_share = (polar_angle(row).cos() - polar_angle(row + 1).cos()) / 2.0;
                let weight = band_share / width as f64;
                for column in 0..width {
                    for (sum, value) in mean.iter_mut().zip(level.texel(column, row)) {
                        *sum += weight * f64::from(value);
                    }
                }
            }
            Vec3::new(mean[0] as f32, mean[1] as f32, mean[2] as f32) * *intensity
        }
    }
}

#[cfg(test)]
mod environment_mean_tests {
    use super::*;

    /// A lat-long map that is dim everywhere except a bright band of rows near the +Y pole.
    fn polar_band_map() -> (Texture, impl Fn(usize, usize) -> Vec3) {
        let (w, h) = (64usize, 32usize);
        let texel = |_x: usize, y: usize| {
            if (2..4).contains(&y) {
                Vec3::new(10.0, 0.5, 4.0)
            } else {
                Vec3::new(0.1, 0.2, 0.3)
            }
        };
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| texel(x, y).extend(1.0).to_array())
            .collect();
        let texture = Texture::from_rgba_f32(w as u32, h as u32, texels).unwrap();
        (texture, texel)
    }

    #[test]
    fn the_mean_is_weighted_by_solid_angle() {
        let (texture, texel) = polar_band_map();
        let (w, h) = (texture.width() as f32, texture.height() as f32);
        let intensity = 2.0;
        let environment = Environment::LatLong {
            texture: 0,
            intensity,
        };
        let mean = environment_mean(&environment, &[Arc::new(texture)]);
        // Reference: (1 / 4pi) times the integral of the map over the sphere, by a fine
        // quadrature that is uniform in cos(theta) and phi (equal areas on the sphere), each
        // direction reading the texel it falls in through the lat-long mapping.
        // Rings far finer than the map's rows keep the band edges' misassignment below
        // 1/8000 of the sphere each.
        let (rings, segments) = (4000, 64);
        let mut sum = [0.0f64; 3];
        for ring in 0..rings {
            let cos_theta = 1.0 - 2.0 * (ring as f64 + 0.5) / rings as f64;
            let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
            for segment in 0..segments {
                let phi = std::f64::consts::TAU * (segment as f64 + 0.5) / segments as f64;
                let dir = Vec3::new(
                    (sin_theta * phi.cos()) as f32,
                    cos_theta as f32,
                    (sin_theta * phi.sin()) as f32,
                );
                let st = crate::footprint::direction_to_lat_long(dir);
                let x = ((st.x * w) as usize).min(w as usize - 1);
                let y = ((st.y * h) as usize).min(h as usize - 1);
                let value = texel(x, y);
                for (total, v) in sum.iter_mut().zip(value.to_array()) {
                    *total += f64::from(v);
                }
            }
        }
        let n = (rings * segments) as f64;
        let reference = Vec3::new(
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        ) * intensity;
        eprintln!("environment mean {mean} vs quadrature over the sphere {reference}");
        assert!(
            (mean - reference).abs().max_element() < 1e-2 * reference.max_element(),
            "mean {mean} vs the sphere's {reference}"
        );
    }

    #[test]
    fn a_uniform_map_has_its_own_value_as_mean() {
        let texels = vec![[0.25, 0.5, 0.75, 1.0]; 8 * 5];
        let texture = Arc::new(Texture::from_rgba_f32(8, 5, texels).unwrap());
        let environment = Environment::LatLong {
            texture: 0,
            intensity: 4.0,
        };
        let mean = environment_mean(&environment, &[texture]);
        assert!(
            (mean - Vec3::new(1.0, 2.0, 3.0)).abs().max_element() < 1e-5,
            "{mean}"
        );
    }
}
