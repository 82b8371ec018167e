//! Emissive geometry as lights: every triangle and sphere whose material has a non-zero
//! `emission` is an area light an integrator can sample (next-event estimation) and find
//! again when a sampled ray hits it (for multiple importance sampling).
//!
//! Emission is one-sided, as pbrt-v4's `DiffuseAreaLight` and Mitsuba 3's `area` emitter
//! are by default: a triangle emits on the side its geometric normal points to (its
//! winding, counter-clockwise seen from the front), a sphere outward. A material marked
//! `two_sided` (glTF's `doubleSided`) emits from both sides ([`emits_towards`]): its
//! triangles are sampled from either side, with twice the power. The emitted radiance
//! is the material's `emission` factor, times its emission texture where it has one.
//!
//! Textured emitters: a sample carries the texture coordinates of its point (the triangle's
//! st interpolated with the sample's barycentrics, or the sphere's lat-long st of the point,
//! as `render::prepared` computes them for a hit), and the integrator looks the texture up
//! there (`render::surface_textures::area_light_radiance`), the same way for a light sample
//! and for a BSDF-sampled ray that hits the light, so both halves of multiple importance
//! sampling estimate the same emitted radiance.
//!
//! Sampling, for a shading point `p`:
//! - a sphere seen from outside is sampled by the cone of directions it subtends,
//!   uniformly in solid angle: `cos theta` uniform in `[cos theta_max, 1]` with
//!   `sin^2 theta_max = r^2 / d^2`, density `1 / (2 pi (1 - cos theta_max))` (pbrt-v4,
//!   section 6.2.4). The cone and the sampled point are computed in f64 (`SphereCone`):
//!   close to the sphere they are small differences of nearly equal values. From inside,
//!   a one-sided sphere sends no light (its emission faces out); a two-sided one is sampled
//!   uniformly by area, all of it being in view, with the solid-angle density
//!   `d^2 / (A |cos theta_l|)`;
//! - a triangle is sampled uniformly in the solid angle it subtends
//!   ([`super::spherical_triangle`], Arvo's method), density `1 / Omega`, where that solid
//!   angle `Omega` lies between [`MIN_SPHERICAL_SOLID_ANGLE`] and
//!   [`MAX_SPHERICAL_SOLID_ANGLE`] (pbrt-v4, section 6.5.4, uses the same method with a
//!   lower bound of 3e-4 sr; the bound here was measured, see its doc): nearer, the `1 / d^2`
//!   and `cos theta_l` factors that area sampling leaves in the estimate vary over the
//!   triangle and add variance; the sampled direction is turned into its point on the
//!   triangle by intersecting the triangle's plane;
//! - a triangle subtending less (small or far: the factors are nearly constant over it, and
//!   Arvo's trigonometry loses precision) or more (nearly a hemisphere) is sampled uniformly
//!   by area (pbrt-v4, section A.5.4: `b0 = 1 - sqrt(u0)`, `b1 = u1 sqrt(u0)`), and the area
//!   density `1 / A` turned into a solid-angle one, `d^2 / (A |cos theta_l|)`, with
//!   `theta_l` the angle at the light. [`AreaLight::pdf`] makes the same choice from the
//!   same point, so both halves of multiple importance sampling agree.
//!
//! Power (for choosing a light in proportion to it): `luminance(L) * area * pi`, the flux of
//! a one-sided Lambertian emitter, with `L` the emission factor times the mean of the
//! emission texture's level 0 for a textured emitter (the mean over the whole texture, not
//! over the part the triangle maps: choosing a light by an approximate power only changes
//! the variance, never the expectation).
//!
//! Meshes with an alpha cut-out are not made lights (their emitting area depends on the
//! mask); rays that hit them still see their emission, unweighted, which stays unbiased as
//! no light sample ever reaches them.

use std::f32::consts::PI;

use glam::{DVec3, Vec2, Vec3};

use super::bsdf::orthonormal_basis;
use super::ray_offset::shadow_ray_end;
use super::spherical_triangle;
use crate::scene::{Material, SceneDescription};
use crate::texture::Texture;

/// Luminance of a linear Rec. 709 colour.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The shape of one area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// A triangle with its unit front normal and area.
    Triangle {
        p: [Vec3; 3],
        normal: Vec3,
        area: f32,
        /// The centroid and its distance to the farthest corner (the bound that keeps far
        /// triangles off the solid-angle computation, `spherical_corners`).
        centroid: Vec3,
        reach: f32,
    },
    Sphere {
        center: Vec3,
        radius: f32,
    },
}

/// Below this solid angle (steradians) a triangle light is sampled by area. pbrt-v4 samples
/// by solid angle from 3e-4 sr (`MinSphericalSampleArea`); here that bound made the Cornell
/// box's path-traced renders 1.3 times slower for no change in noise, while 0.1 sr keeps
/// the noise gain where lights are near (docs/path-tracing.md, "Area lights").
pub const MIN_SPHERICAL_SOLID_ANGLE: f32 = 0.1;
/// Above this solid angle (steradians; a hemisphere is 2 pi = 6.283) a triangle light is
/// sampled by area: pbrt-v4's `MaxSphericalSampleArea`.
pub const MAX_SPHERICAL_SOLID_ANGLE: f32 = 6.22;

/// The unit directions from `p` to a triangle's corners and the solid angle they span, when
/// it is in the range sampled by solid angle.
///
/// The solid angle is computed (an arctangent and three normalisations) only where a cheap
/// bound does not already put it below the range: seen from `h` off the triangle's plane,
/// every point of the triangle is at some distance `d >= d_min` and contributes
/// `cos theta_l / d^2 = h / d^3` per unit area, so `Omega <= area h / d_min^3`, with
/// `d_min` at least `h` and at least the distance to the centroid minus the centroid's
/// farthest corner.
#[inline]
fn spherical_corners(p: Vec3, triangle: &AreaShape) -> Option<([DVec3; 3], f32)> {
    let AreaShape::Triangle {
        p: v,
        normal,
        area,
        centroid,
        reach,
    } = *triangle
    else {
        return None;
    };
    let height = normal.dot(p - centroid).abs();
    let nearest = ((p - centroid).length() - reach).max(height);
    if nearest > 0.0 && area * height < MIN_SPHERICAL_SOLID_ANGLE * nearest * nearest * nearest {
        return None;
    }
    let [a, b, c] = spherical_triangle::corner_directions(p, v)?;
    let omega = spherical_triangle::solid_angle(a, b, c);
    (omega.is_finite() && (MIN_SPHERICAL_SOLID_ANGLE..=MAX_SPHERICAL_SOLID_ANGLE).contains(&omega))
        .then_some(([a, b, c], omega))
}

/// Whether `material`'s emission at a surface with the outward geometric normal
/// `geometric_normal` reaches a viewer looking along `ray_direction`: from the front side
/// (`SurfaceHit::is_front_face`), or from either side of a `two_sided` material.
#[inline]
pub fn emits_towards(material: &Material, geometric_normal: Vec3, ray_direction: Vec3) -> bool {
    material.two_sided || ray_direction.dot(geometric_normal) < 0.0
}

/// One emissive triangle or sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    pub shape: AreaShape,
    /// A triangle or sphere that emits from both sides (its material's `two_sided`): a
    /// sphere's inside then emits too, and is sampled from within.
    pub two_sided: bool,
    /// Radiance emitted from the front side: the material's emission factor, to be
    /// multiplied by the emission texture at the point when [`AreaLight::textured`] is set.
    pub radiance: Vec3,
    /// The emission texture, when the material has one.
    pub textured: Option<TexturedEmission>,
}

/// Where an area light's emission texture is looked up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturedEmission {
    /// The light's material (whose `emission_texture` binding is looked up).
    pub material: u32,
    /// A triangle's texture coordinates at its three corners (`None`: the mesh has none,
    /// and the texture is read at st = 0 as for a hit); unused for spheres.
    pub corner_st: Option<[Vec2; 3]>,
    /// Mean RGB of the texture's level 0, for the light's power.
    pub mean: Vec3,
}

/// A point on an area light as seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLightSample {
    /// Unit direction from the shading point to the point on the light.
    pub direction_to_light: Vec3,
    /// Distance to that point.
    pub distance: f32,
    /// The point on the light (where shadow rays stop short of), in f64: rounded to f32
    /// far from the origin (by up to 5e-4 at 1e4) it would lie off the surface, and a
    /// shadow ray grazing the light on its way there would meet the light first.
    pub point: DVec3,
    /// The light's emission factor along `direction_to_light` (zero from the back side),
    /// untextured: a textured light's radiance is this times its texture at `st`
    /// (`render::surface_textures::area_light_radiance`).
    pub radiance: Vec3,
    /// Solid-angle density of the direction.
    pub pdf: f32,
    /// Texture coordinates of the point (zero when the light is not textured).
    pub st: Vec2,
}

impl AreaShape {
    /// The triangle with corners `p`: its unit front normal (counter-clockwise winding) and
    /// area (zero for a degenerate one), with its centroid and reach.
    pub fn triangle(p: [Vec3; 3]) -> AreaShape {
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let area = 0.5 * cross.length();
        let centroid = (p[0] + p[1] + p[2]) / 3.0;
        let reach2 = (p[0] - centroid)
            .length_squared()
            .max((p[1] - centroid).length_squared())
            .max((p[2] - centroid).length_squared());
        AreaShape::Triangle {
            p,
            normal: cross.normalize_or(Vec3::Y),
            area: if area.is_finite() { area } else { 0.0 },
            centroid,
            reach: reach2.sqrt(),
        }
    }
}

impl AreaLight {
    /// Surface area.
    pub fn area(&self) -> f32 {
        match self.shape {
            AreaShape::Triangle { area, .. } => area,
            AreaShape::Sphere { radius, .. } => 4.0 * PI * radius * radius,
        }
    }

    /// The emitted power by luminance, `luminance(L) * A * pi`, with `L` the factor times
    /// the texture's mean for a textured light (see the module doc).
    pub fn power(&self) -> f32 {
        let mean = self.textured.map_or(Vec3::ONE, |t| t.mean);
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        luminance(self.radiance * mean) * self.area() * PI * sides
    }

    /// Texture coordinates of the point with barycentrics `(b0, b1)` of a triangle light
    /// (`b0 p0 + b1 p1 + (1 - b0 - b1) p2`), or of the point `point` of a sphere light:
    /// those a hit at the same point gets (`render::prepared`). Zero for an untextured light.
    fn st_at(&self, b0: f32, b1: f32, point: Vec3) -> Vec2 {
        let Some(textured) = self.textured else {
            return Vec2::ZERO;
        };
        match self.shape {
            AreaShape::Triangle { .. } => textured.corner_st.map_or(Vec2::ZERO, |t| {
                t[0] * b0 + t[1] * b1 + t[2] * (1.0 - b0 - b1)
            }),
            AreaShape::Sphere { center, radius } => {
                let normal = ((point - center) / radius).normalize_or(Vec3::Y);
                crate::footprint::lat_long_frame(normal, radius).0
            }
        }
    }

    /// A direction towards the light from `p`, drawn from the uniform numbers `u`; `None`
    /// when nothing of the light can be seen from `p` in that way (inside a sphere,
    /// degenerate sample), or when its density overflows: a sliver seen edge-on from afar,
    /// `d^2 / (A cos theta_l)` beyond the largest f32, whose sample would be worth nothing
    /// (and [`AreaLight::pdf`] is zero there, so BSDF sampling alone finds it).
    pub fn sample(&self, p: Vec3, u: Vec2) -> Option<AreaLightSample> {
        self.sample_shape(p, u).filter(|s| s.pdf.is_finite())
    }

    /// [`AreaLight::sample`] before its density is checked.
    fn sample_shape(&self, p: Vec3, u: Vec2) -> Option<AreaLightSample> {
        match self.shape {
            AreaShape::Triangle {
                p: v, normal, area, ..
            } => {
                let spherical = spherical_corners(p, &self.shape);
                let (b0, b1) = match spherical {
                    Some(([a, b, c], _)) => {
                        let w = spherical_triangle::sample(a, b, c, u)?;
                        // The sampler's barycentrics weigh (v0, v1, v2); ours (v0, v1) and
                        // the rest on v2.
                        let (w1, w2) = spherical_triangle::ray_barycentrics(p, w, v)?;
                        (1.0 - w1 - w2, w1)
                    }
                    None => {
                        let s = u.x.sqrt();
                        (1.0 - s, u.y * s)
                    }
                };
                let point = f64::from(b0) * v[0].as_dvec3()
                    + f64::from(b1) * v[1].as_dvec3()
                    + f64::from(1.0 - b0 - b1) * v[2].as_dvec3();
                let to_light = (point - p.as_dvec3()).as_vec3();
                let distance2 = to_light.length_squared();
                if distance2.is_nan() || distance2 <= 0.0 || !distance2.is_finite() {
                    return None;
                }
                let distance = distance2.sqrt();
                let wi = to_light / distance;
                let cos_light = self.facing_cosine(-wi.dot(normal));
                if cos_light <= 0.0 {
                    // The back of a one-sided emitter.
                    return None;
                }
                let pdf = match spherical {
                    Some((_, omega)) => 1.0 / omega,
                    None => distance2 / (area * cos_light),
                };
                Some(AreaLightSample {
                    direction_to_light: wi,
                    distance,
                    point,
                    radiance: self.radiance,
                    pdf,
                    st: self.st_at(b0, b1, point.as_vec3()),
                })
            }
            AreaShape::Sphere { center, radius } => {
                let Some(cone) = SphereCone::seen_from(p, center, radius) else {
                    return self.sample_sphere_inside(p, center, radius, u);
                };
                let one_minus_cos = f64::from(u.x) * cone.one_minus_cos_max;
                let cos_theta = 1.0 - one_minus_cos;
                let sin2_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0);
                let sin_theta = sin2_theta.sqrt();
                let phi = 2.0 * std::f64::consts::PI * f64::from(u.y);
                let (t, b) = orthonormal_basis(cone.axis.as_vec3());
                let (t, b) = (t.as_dvec3(), b.as_dvec3());
                let wi = (cone.axis * cos_theta + (t * phi.cos() + b * phi.sin()) * sin_theta)
                    .normalize();
                // Nearest intersection along wi, d cos - sqrt(r^2 - d^2 sin^2), written as
                // (d^2 - r^2) / (d cos + sqrt(...)) (the product of the two roots): the
                // difference cancels when the point is close to the sphere, and an error in
                // it of one f32 rounding of d put sampled points inside the sphere, whose
                // shadow rays it then blocked.
                let root = (cone.r2 - cone.d2 * sin2_theta).max(0.0).sqrt();
                let distance = cone.d2_minus_r2 / (cone.d * cos_theta + root);
                let point = p.as_dvec3() + wi * distance;
                Some(AreaLightSample {
                    direction_to_light: wi.as_vec3().normalize(),
                    distance: distance as f32,
                    point,
                    radiance: self.radiance,
                    pdf: cone.pdf(),
                    st: self.st_at(0.0, 0.0, point.as_vec3()),
                })
            }
        }
    }

    /// Solid-angle density with which [`AreaLight::sample`] picks the direction from `p`
    /// that reaches the light at `point` (a hit on the light's front side): zero where the
    /// density overflows, as `sample` never picks such a direction.
    pub fn pdf(&self, p: Vec3, point: Vec3) -> f32 {
        let pdf = self.shape_pdf(p, point);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// [`AreaLight::pdf`] before overflow is checked.
    fn shape_pdf(&self, p: Vec3, point: Vec3) -> f32 {
        match self.shape {
            AreaShape::Triangle { normal, area, .. } => {
                let to_light = point - p;
                let distance2 = to_light.length_squared();
                if distance2.is_nan() || distance2 <= 0.0 {
                    return 0.0;
                }
                let cos_light = self.facing_cosine(-to_light.dot(normal) / distance2.sqrt());
                if cos_light <= 0.0 || area <= 0.0 {
                    return 0.0;
                }
                match spherical_corners(p, &self.shape) {
                    Some((_, omega)) => 1.0 / omega,
                    None => distance2 / (area * cos_light),
                }
            }
            AreaShape::Sphere { center, radius } => {
                match SphereCone::seen_from(p, center, radius) {
                    Some(cone) => cone.pdf(),
                    None if self.two_sided => {
                        let normal = (point - center).as_dvec3().normalize_or_zero();
                        inside_sphere_pdf(p, point.as_dvec3(), normal, radius).unwrap_or(0.0)
                    }
                    None => 0.0,
                }
            }
        }
    }

    /// A point drawn uniformly by area on a two-sided sphere light, seen from `p` inside it
    /// (all of the sphere is in view from there); `None` for a one-sided sphere, whose
    /// inside is dark, or a degenerate sample (`p` on the sampled point).
    fn sample_sphere_inside(
        &self,
        p: Vec3,
        center: Vec3,
        radius: f32,
        u: Vec2,
    ) -> Option<AreaLightSample> {
        if !self.two_sided {
            return None;
        }
        let normal = super::bsdf::sample_uniform_sphere(u).as_dvec3();
        let point = center.as_dvec3() + normal * f64::from(radius);
        let pdf = inside_sphere_pdf(p, point, normal, radius)?;
        let to_light = point - p.as_dvec3();
        let distance = to_light.length();
        Some(AreaLightSample {
            direction_to_light: (to_light / distance).as_vec3().normalize(),
            distance: distance as f32,
            point,
            radiance: self.radiance,
            pdf,
            st: self.st_at(0.0, 0.0, point.as_vec3()),
        })
    }

    /// The far end of a shadow ray (`origin`, unit `direction`, up to `tfar`) towards a point
    /// sampled on this light from a surface point near `origin`: shortened, for a sphere,
    /// to just before where the ray enters the sphere (0 when `origin` is inside it). The
    /// sample was visible from the surface point, and a sphere cannot block its own visible
    /// side; but the offset origin is nearer, and near the sphere's outline the segment
    /// from there cuts through the sphere before it reaches the sample (a floor 1e-2 radii
    /// under a sphere lamp at 1e4 lost 0.4 % of its light this way). Triangles are flat and
    /// keep `tfar`.
    pub fn clip_shadow_ray(&self, origin: Vec3, direction: Vec3, tfar: f32) -> f32 {
        let AreaShape::Sphere { center, radius } = self.shape else {
            return tfar;
        };
        let to_center = center.as_dvec3() - origin.as_dvec3();
        let r2 = f64::from(radius) * f64::from(radius);
        let outside = to_center.length_squared() - r2;
        if outside.is_nan() || outside <= 0.0 {
            return 0.0;
        }
        let direction = direction.as_dvec3();
        let along = to_center.dot(direction);
        let perpendicular2 = (to_center - direction * along).length_squared();
        if along <= 0.0 || perpendicular2 >= r2 {
            return tfar;
        }
        // Nearest root, written without cancellation as outside / (along + half chord).
        let entry = outside / (along + (r2 - perpendicular2).sqrt());
        let entry_point = origin.as_dvec3() + direction * entry;
        let end = shadow_ray_end(entry as f32, entry_point.as_vec3(), self.coordinate_scale());
        tfar.min(end)
    }

    /// The cosine between the light's front normal and the direction towards the viewer as
    /// the light's emission sees it: negative (no light) behind a one-sided triangle,
    /// mirrored to the front for a two-sided one.
    #[inline]
    fn facing_cosine(&self, cos_front: f32) -> f32 {
        if self.two_sided {
            cos_front.abs()
        } else {
            cos_front
        }
    }

    /// The magnitude of the coordinates the light's surface is computed from: its
    /// vertices, or its centre and radius. Rounding places the surface (as an intersector
    /// finds it, and a sampled point on it) a few roundings of this size off, wherever on
    /// the surface the point is; a shadow ray stops that much short of its light
    /// (`shading::shadow_ray_end`).
    pub fn coordinate_scale(&self) -> f32 {
        match self.shape {
            AreaShape::Triangle { p, .. } => {
                p.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max)
            }
            AreaShape::Sphere { center, radius } => center.abs().max_element() + radius.abs(),
        }
    }
}

/// Solid-angle density of reaching `point` (unit outward normal `normal`) on a sphere of
/// `radius` sampled uniformly by area from `p` inside it: `d^2 / (A |cos theta_l|)`. `None`
/// when the direction is degenerate.
fn inside_sphere_pdf(p: Vec3, point: DVec3, normal: DVec3, radius: f32) -> Option<f32> {
    let to_light = point - p.as_dvec3();
    let distance2 = to_light.length_squared();
    let area = 4.0 * std::f64::consts::PI * f64::from(radius) * f64::from(radius);
    let cos_light = (to_light.dot(normal) / distance2.sqrt()).abs();
    let pdf = distance2 / (area * cos_light);
    (distance2 > 0.0 && pdf.is_finite() && pdf > 0.0).then_some(pdf as f32)
}

/// The cone of directions a sphere light subtends from a point outside it, in f64: near the
/// sphere, `d^2 - r^2` and `1 - cos theta_max` are small differences of values near `r^2`
/// and 1, which f32 left with a relative error of a few times 1e-3 at a gap of 1e-4 radii.
struct SphereCone {
    /// Unit direction to the centre.
    axis: DVec3,
    d: f64,
    d2: f64,
    r2: f64,
    d2_minus_r2: f64,
    /// `1 - cos theta_max`, with `sin^2 theta_max = r^2 / d^2`.
    one_minus_cos_max: f64,
}

impl SphereCone {
    /// The cone from `p`; `None` from inside the sphere or on it.
    #[inline]
    fn seen_from(p: Vec3, center: Vec3, radius: f32) -> Option<SphereCone> {
        let to_center = center.as_dvec3() - p.as_dvec3();
        let d2 = to_center.length_squared();
        let r = f64::from(radius);
        let r2 = r * r;
        let d2_minus_r2 = d2 - r2;
        if d2_minus_r2.is_nan() || d2_minus_r2 <= 0.0 || !d2.is_finite() {
            return None;
        }
        let d = d2.sqrt();
        let sin2_max = r2 / d2;
        let cos_max = (d2_minus_r2 / d2).sqrt();
        Some(SphereCone {
            axis: to_center / d,
            d,
            d2,
            r2,
            d2_minus_r2,
            // 1 - cos theta_max without cancellation.
            one_minus_cos_max: sin2_max / (1.0 + cos_max),
        })
    }

    /// Uniform density over the cone's solid angle.
    #[inline]
    fn pdf(&self) -> f32 {
        (1.0 / (2.0 * std::f64::consts::PI * self.one_minus_cos_max)) as f32
    }
}

/// All area lights of a scene, and which light a hit on a mesh triangle or sphere is.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AreaLights {
    pub lights: Vec<AreaLight>,
    /// Per mesh (scene order): the light index of its first triangle when it emits.
    /// Degenerate triangles keep their slot (with zero area, never chosen).
    mesh_first: Vec<Option<u32>>,
    /// Per sphere (scene order): its light index when it emits.
    sphere_light: Vec<Option<u32>>,
    /// Emissive triangles and spheres, for reports.
    pub triangle_count: usize,
    pub sphere_count: usize,
}

impl AreaLights {
    /// The area lights of `scene` (see the module doc for which surfaces qualify), with the
    /// scene's decoded `textures` (for the mean of emission textures; a texture missing
    /// from them, e.g. one an external texture system serves, counts with mean 1).
    pub fn new(scene: &SceneDescription, textures: &[std::sync::Arc<Texture>]) -> AreaLights {
        // The mean of each emission texture, computed once per texture.
        let mut means: Vec<Option<Vec3>> = vec![None; scene.textures.len()];
        let mut textured = |material: usize| {
            let binding = scene.materials[material].emission_texture.as_ref()?;
            let mean = match means.get_mut(binding.texture) {
                Some(Some(mean)) => *mean,
                Some(slot) => {
                    let mean = textures
                        .get(binding.texture)
                        .map_or(Vec3::ONE, |t| level0_mean(t));
                    *slot = Some(mean);
                    mean
                }
                None => Vec3::ONE,
            };
            Some(TexturedEmission {
                material: material as u32,
                corner_st: None,
                mean,
            })
        };
        let emissive = |material: usize| {
            scene.materials.get(material).is_some_and(|m| {
                super::material_features::emits(m)
                    && m.emission.is_finite()
                    && m.alpha_cutoff.is_none()
            })
        };
        let mut out = AreaLights::default();
        for mesh in &scene.meshes {
            if !emissive(mesh.material) || mesh.triangles.is_empty() {
                out.mesh_first.push(None);
                continue;
            }
            let radiance = scene.materials[mesh.material].emission;
            let texture = textured(mesh.material);
            out.mesh_first.push(Some(out.lights.len() as u32));
            for tri in &mesh.triangles {
                let p = tri.map(|i| {
                    mesh.positions
                        .get(i as usize)
                        .copied()
                        .unwrap_or(Vec3::ZERO)
                });
                let corner_st = (!mesh.st.is_empty())
                    .then(|| tri.map(|i| mesh.st.get(i as usize).copied().unwrap_or(Vec2::ZERO)));
                out.lights.push(AreaLight {
                    shape: AreaShape::triangle(p),
                    two_sided: scene.materials[mesh.material].two_sided,
                    radiance,
                    textured: texture.map(|t| TexturedEmission { corner_st, ..t }),
                });
                out.triangle_count += 1;
            }
        }
        for sphere in &scene.spheres {
            if !emissive(sphere.material) || sphere.radius.is_nan() || sphere.radius <= 0.0 {
                out.sphere_light.push(None);
                continue;
            }
            out.sphere_light.push(Some(out.lights.len() as u32));
            out.lights.push(AreaLight {
                two_sided: scene.materials[sphere.material].two_sided,
                shape: AreaShape::Sphere {
                    center: sphere.center,
                    radius: sphere.radius,
                },
                radiance: scene.materials[sphere.material].emission,
                textured: textured(sphere.material),
            });
            out.sphere_count += 1;
        }
        out
    }

    pub fn len(&self) -> usize {
        self.lights.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    /// The light a hit on triangle `primitive` of mesh `mesh` is, if it emits.
    #[inline]
    pub fn mesh_light(&self, mesh: usize, primitive: u32) -> Option<usize> {
        let first = (*self.mesh_first.get(mesh)?)?;
        Some(first as usize + primitive as usize)
    }

    /// The light sphere `sphere` is, if it emits.
    #[inline]
    pub fn sphere_light(&self, sphere: usize) -> Option<usize> {
        self.sphere_light
            .get(sphere)
            .copied()
            .flatten()
            .map(|i| i as usize)
    }
}

/// Mean RGB of a texture's level 0 (accumulated in f64).
fn level0_mean(texture: &Texture) -> Vec3 {
    let Some(level) = texture.pyramid().levels.first() else {
        return Vec3::ONE;
    };
    let (width, height) = (level.width as usize, level.height as usize);
    let mut sum = [0.0f64; 3];
    for y in 0..height {
        for x in 0..width {
            let texel = level.texel(x, y);
            for c in 0..3 {
                sum[c] += f64::from(texel[c]);
            }
        }
    }
    let n = (width * height).max(1) as f64;
    Vec3::new(
        (sum[0] / n) as f32,
        (sum[1] / n) as f32,
        (sum[2] / n) as f32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    fn quad_triangle() -> AreaLight {
        AreaLight {
            two_sided: false,
            // Wound clockwise seen from above: it faces down.
            shape: AreaShape::triangle([
                Vec3::new(-1.0, 2.0, -1.0),
                Vec3::new(1.0, 2.0, -1.0),
                Vec3::new(1.0, 2.0, 1.0),
            ]),
            radiance: Vec3::ONE,
            textured: None,
        }
    }

    /// E = integral of L cos over the light's solid angle, estimated from light samples.
    fn irradiance(light: &AreaLight, p: Vec3, n: Vec3, count: usize) -> f32 {
        let mut u = Uniforms(3);
        let mut sum = 0.0f64;
        for _ in 0..count {
            if let Some(s) = light.sample(p, u.vec2()) {
                assert!(s.pdf > 0.0 && s.pdf.is_finite());
                assert!(
                    (light.pdf(p, s.point.as_vec3()) - s.pdf).abs() <= 2e-3 * s.pdf,
                    "pdf"
                );
                sum += (s.radiance.x * s.direction_to_light.dot(n).max(0.0) / s.pdf) as f64;
            }
        }
        (sum / count as f64) as f32
    }

    #[test]
    fn sphere_light_irradiance_is_l_pi_sin2() {
        // E = L pi sin^2(theta_max) for a surface facing a sphere light.
        let light = AreaLight {
            two_sided: false,
            shape: AreaShape::Sphere {
                center: Vec3::new(0.0, 3.0, 0.0),
                radius: 1.0,
            },
            radiance: Vec3::splat(2.0),
            textured: None,
        };
        let e = irradiance(&light, Vec3::ZERO, Vec3::Y, 50_000);
        let expected = 2.0 * PI / 9.0;
        assert!((e - expected).abs() < 2e-3 * expected, "{e} vs {expected}");
        assert!(light
            .sample(Vec3::new(0.0, 3.2, 0.0), Vec2::splat(0.5))
            .is_none());
    }

    #[test]
    fn a_two_sided_sphere_light_lights_its_inside_with_l_pi() {
        // Inside, every direction meets the emitting wall: E = L pi, whatever the point.
        // Estimated over a 500 x 500 grid of stratified sample positions.
        let light = AreaLight {
            two_sided: true,
            shape: AreaShape::Sphere {
                center: Vec3::new(0.5, 1.0, -0.25),
                radius: 2.0,
            },
            radiance: Vec3::splat(2.0),
            textured: None,
        };
        let n = Vec3::new(0.6, 0.8, 0.0);
        let side = 500;
        for p in [Vec3::new(0.5, 1.0, -0.25), Vec3::new(1.9, 1.2, 0.3)] {
            let mut sum = 0.0f64;
            for i in 0..side {
                for j in 0..side {
                    let u = (Vec2::new(i as f32, j as f32) + 0.5) / side as f32;
                    let s = light.sample(p, u).expect("inside a two-sided sphere");
                    assert!(
                        (light.pdf(p, s.point.as_vec3()) - s.pdf).abs() <= 2e-3 * s.pdf,
                        "pdf"
                    );
                    sum += f64::from(s.radiance.x * s.direction_to_light.dot(n).max(0.0) / s.pdf);
                }
            }
            let e = sum / (side * side) as f64;
            let expected = 2.0 * std::f64::consts::PI;
            assert!(
                (e - expected).abs() < 2e-3 * expected,
                "at {p}: {e} vs {expected}"
            );
        }
        let one_sided = AreaLight {
            two_sided: false,
            ..light
        };
        assert!(one_sided
            .sample(Vec3::new(0.5, 1.0, -0.25), Vec2::splat(0.3))
            .is_none());
        assert_eq!(
            one_sided.pdf(Vec3::new(0.5, 1.0, -0.25), Vec3::new(0.5, 3.0, -0.25)),
            0.0
        );
    }

    #[test]
    fn triangle_light_samples_integrate_to_its_solid_angle() {
        // The mean of 1/pdf over samples is the solid angle the triangle subtends, which
        // Van Oosterom and Strackee's formula (1983) gives exactly.
        let light = quad_triangle();
        let p = Vec3::new(0.3, 0.0, 0.1);
        let mut u = Uniforms(9);
        let count = 100_000;
        let estimate = (0..count)
            .filter_map(|_| light.sample(p, u.vec2()))
            .map(|s| 1.0 / s.pdf as f64)
            .sum::<f64>()
            / count as f64;
        let AreaShape::Triangle { p: v, .. } = light.shape else {
            unreachable!()
        };
        let [a, b, c] = v.map(|q| q - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let numerator = a.dot(b.cross(c)).abs();
        let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        let exact = 2.0 * numerator.atan2(denominator) as f64;
        assert!(
            (estimate - exact).abs() < 0.01 * exact,
            "{estimate} vs {exact}"
        );
    }

    #[test]
    fn a_point_close_under_a_huge_triangle_light_gets_its_irradiance() {
        // A triangle 20 000 units wide, 20 and 2 units above points under its long side and
        // beside it: light samples give L times the projected solid angle.
        for height in [20.0f32, 2.0] {
            let light = AreaLight {
                two_sided: false,
                // Wound clockwise seen from above: it faces down.
                shape: AreaShape::triangle([
                    Vec3::new(-1e4, height, -1e4),
                    Vec3::new(1e4, height, 1e4),
                    Vec3::new(-1e4, height, 1e4),
                ]),
                radiance: Vec3::ONE,
                textured: None,
            };
            let AreaShape::Triangle { p: v, .. } = light.shape else {
                unreachable!()
            };
            for offset in [0.0, 3.0] {
                let p = Vec3::new(offset * height, 0.0, -offset * height);
                let exact = spherical_triangle::tests::projected_solid_angle(
                    v.map(|q| q.as_dvec3() - p.as_dvec3()),
                );
                let e = irradiance(&light, p, Vec3::Y, 400_000) as f64;
                assert!(
                    (e / exact - 1.0).abs() < 5e-3,
                    "height {height}, offset {offset}: {e} against {exact}"
                );
            }
        }
    }

    /// Irradiance at `p` (normal `n`) from `light`, estimated by sampling its area
    /// uniformly whatever its solid angle: the mean and the variance of the estimate.
    fn area_sampled_irradiance(light: &AreaLight, p: Vec3, n: Vec3, count: usize) -> (f64, f64) {
        let AreaShape::Triangle {
            p: v, normal, area, ..
        } = light.shape
        else {
            unreachable!()
        };
        let mut u = Uniforms(17);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            let (u0, u1) = (u.next(), u.next());
            let s = u0.sqrt();
            let point = (1.0 - s) * v[0] + u1 * s * v[1] + (1.0 - (1.0 - s) - u1 * s) * v[2];
            let to_light = point - p;
            let wi = to_light.normalize();
            let cos_light = -wi.dot(normal);
            let value = if cos_light > 0.0 {
                (light.radiance.x * wi.dot(n).max(0.0) * area * cos_light
                    / to_light.length_squared()) as f64
            } else {
                0.0
            };
            sum += value;
            sum2 += value * value;
        }
        let mean = sum / count as f64;
        (mean, sum2 / count as f64 - mean * mean)
    }

    #[test]
    fn near_triangle_lights_are_sampled_by_solid_angle_with_less_variance() {
        // A shading point close under a large triangle (solid angle about 2 sr): the
        // solid-angle samples' estimate of the irradiance agrees with area sampling's, with
        // a fraction of its variance.
        let light = quad_triangle();
        let (p, n) = (Vec3::new(0.4, 1.6, -0.3), Vec3::Y);
        let (_, omega) = spherical_corners(p, &light.shape).expect("in the solid-angle range");
        assert!(omega > 1.0, "{omega}");
        let count = 200_000;
        let mut u = Uniforms(29);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            let s = light.sample(p, u.vec2()).expect("front side");
            assert!((s.pdf - 1.0 / omega).abs() <= 1e-6 * s.pdf);
            assert!(
                (light.pdf(p, s.point.as_vec3()) - s.pdf).abs() <= 1e-6 * s.pdf,
                "pdf"
            );
            // The point is on the triangle, where the direction points.
            assert!((s.point.y - 2.0).abs() < 1e-5, "{}", s.point);
            assert!((p + s.direction_to_light * s.distance - s.point.as_vec3()).length() < 1e-4);
            let value = (s.radiance.x * s.direction_to_light.dot(n).max(0.0) / s.pdf) as f64;
            sum += value;
            sum2 += value * value;
        }
        let mean = sum / count as f64;
        let variance = sum2 / count as f64 - mean * mean;
        let (area_mean, area_variance) = area_sampled_irradiance(&light, p, n, count);
        let standard_error = ((variance + area_variance) / count as f64).sqrt();
        assert!(
            (mean - area_mean).abs() < 5.0 * standard_error,
            "{mean} vs {area_mean} (standard error {standard_error})"
        );
        assert!(
            variance < 0.5 * area_variance,
            "variance {variance} vs area sampling's {area_variance}"
        );
    }

    #[test]
    fn far_triangle_lights_are_sampled_by_area() {
        // Far below the light the triangle subtends less than the solid-angle bound: the
        // area density, d^2 / (A cos), and the same choice in `pdf`.
        let light = quad_triangle();
        let p = Vec3::new(0.2, -150.0, 0.1);
        assert!(spherical_corners(p, &light.shape).is_none());
        let s = light.sample(p, Vec2::new(0.3, 0.7)).unwrap();
        let to_light = s.point.as_vec3() - p;
        let expected = to_light.length_squared() / (2.0 * s.direction_to_light.y);
        assert!(
            (s.pdf - expected).abs() < 1e-4 * expected,
            "{} vs {expected}",
            s.pdf
        );
        assert!((light.pdf(p, s.point.as_vec3()) - s.pdf).abs() < 1e-4 * s.pdf);
    }

    #[test]
    fn the_distance_bound_never_hides_a_triangle_in_the_solid_angle_range() {
        // Random triangles and points: whenever the cheap bound sends a triangle to area
        // sampling, its exact solid angle is below the range.
        let mut u = Uniforms(41);
        let mut point =
            |scale: f32| Vec3::new(u.next() - 0.5, u.next() - 0.5, u.next() - 0.5) * scale;
        let mut spherical = 0;
        for _ in 0..20_000 {
            let v = [point(2.0), point(2.0), point(2.0)];
            let p = point(5.0);
            let shape = AreaShape::triangle(v);
            let [a, b, c] = spherical_triangle::corner_directions(p, v).unwrap();
            let exact = spherical_triangle::solid_angle(a, b, c);
            match spherical_corners(p, &shape) {
                Some((_, omega)) => {
                    spherical += 1;
                    assert_eq!(omega, exact);
                }
                None => assert!(
                    !(MIN_SPHERICAL_SOLID_ANGLE..=MAX_SPHERICAL_SOLID_ANGLE).contains(&exact),
                    "{exact} sr from {p} to {v:?}"
                ),
            }
        }
        assert!(spherical > 1000, "{spherical} of 20000 in the range");
    }

    #[test]
    fn the_back_of_a_triangle_light_is_dark() {
        let light = quad_triangle();
        assert!(light
            .sample(Vec3::new(0.0, 3.0, 0.0), Vec2::splat(0.3))
            .is_none());
        assert_eq!(
            light.pdf(Vec3::new(0.0, 3.0, 0.0), Vec3::new(0.5, 2.0, -0.5)),
            0.0
        );
        assert!((light.power() - 2.0 * PI).abs() < 1e-5);
    }

    #[test]
    fn a_sliver_seen_edge_on_from_afar_is_not_sampled_and_has_no_density() {
        // A triangle 1e-22 wide, seen from 1e6 away at 1e-8 above its plane: d^2 / (A cos)
        // is about 2e42, beyond f32. Its light sample would carry an infinite density (which
        // next-event estimation took for a delta light, adding it whole).
        let light = AreaLight {
            two_sided: false,
            shape: AreaShape::triangle([
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.5, 0.0, 1e-22),
            ]),
            radiance: Vec3::ONE,
            textured: None,
        };
        assert!(
            light.area() > 0.0 && light.power() > 0.0,
            "it can be chosen"
        );
        let p = Vec3::new(0.5, -1e-2, 1e6);
        let mut u = Uniforms(13);
        for _ in 0..100 {
            let uv = u.vec2();
            let shape_sample = light.sample_shape(p, uv).expect("the front faces p");
            assert!(shape_sample.pdf.is_infinite(), "{shape_sample:?}");
            assert_eq!(light.sample(p, uv), None);
            assert_eq!(light.pdf(p, shape_sample.point.as_vec3()), 0.0);
        }
        // Nearer, the same sliver has a finite density, both ways.
        let near = Vec3::new(0.5, -1.0, 0.0);
        let s = light
            .sample(near, Vec2::splat(0.5))
            .expect("finite density");
        assert!((light.pdf(near, s.point.as_vec3()) - s.pdf).abs() < 1e-4 * s.pdf);
    }

    /// A scene with one emissive triangle whose material has an emission texture, black in
    /// its left half (s < 0.5) and white in its right half, and the decoded texture.
    fn textured_triangle_scene() -> (SceneDescription, Vec<std::sync::Arc<Texture>>) {
        use crate::scene::{Material, TextureBinding, TextureDesc, TextureSource, TriangleMesh};
        let texels = vec![[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0]];
        let texture = Texture::from_rgba_f32(2, 1, texels).expect("texture");
        let scene = SceneDescription {
            textures: vec![TextureDesc {
                name: "half".to_string(),
                source: TextureSource::File("half.png".into()),
                color_space: Some(crate::texture::ColorSpace::Linear),
                wrap_s: crate::texture::WrapMode::Clamp,
                wrap_t: crate::texture::WrapMode::Clamp,
            }],
            materials: vec![Material {
                emission: Vec3::splat(2.0),
                emission_texture: Some(TextureBinding {
                    texture: 0,
                    transform: glam::Affine2::IDENTITY,
                }),
                ..Material::default()
            }],
            meshes: vec![TriangleMesh {
                positions: vec![
                    Vec3::new(0.0, 1.0, 0.0),
                    Vec3::new(1.0, 1.0, 0.0),
                    Vec3::new(0.0, 1.0, 1.0),
                ],
                st: vec![
                    Vec2::new(0.0, 0.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(0.0, 1.0),
                ],
                triangles: vec![[0, 1, 2]],
                material: 0,
                ..TriangleMesh::default()
            }],
            ..SceneDescription::default()
        };
        (scene, vec![std::sync::Arc::new(texture)])
    }

    #[test]
    fn a_textured_light_has_the_texture_mean_in_its_power_and_st_at_its_samples() {
        let (scene, textures) = textured_triangle_scene();
        let lights = AreaLights::new(&scene, &textures);
        assert_eq!(lights.len(), 1);
        let light = lights.lights[0];
        let textured = light.textured.expect("textured");
        assert_eq!(textured.mean, Vec3::splat(0.5));
        // L = 2 x mean 0.5 over a triangle of area 0.5, one-sided: 1 * 0.5 * pi.
        assert!((light.power() - 0.5 * PI).abs() < 1e-5, "{}", light.power());
        // Without the texture, the power of the factor alone.
        let (mut plain, _) = textured_triangle_scene();
        plain.materials[0].emission_texture = None;
        let plain = AreaLights::new(&plain, &[]).lights[0];
        assert!(plain.textured.is_none());
        assert!((plain.power() - PI).abs() < 1e-5);
        // A sample's st is the corners' st interpolated at its point (here st = (x, z)).
        let mut u = Uniforms(5);
        for _ in 0..100 {
            let s = light
                .sample(Vec3::ZERO, u.vec2())
                .expect("the front faces the origin");
            assert!(
                (s.st - Vec2::new(s.point.x as f32, s.point.z as f32)).length() < 1e-5,
                "{s:?}"
            );
        }
    }
}
