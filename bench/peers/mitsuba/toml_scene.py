#!/usr/bin/env python3
"""A conetrace TOML scene as a Mitsuba 3 scene dictionary, for the path-tracing peer
comparisons (cornell.py, path.py): the TOML is the one place the scene's numbers are
written, and this module reads them for Mitsuba.

Only what those scenes use is converted, and any other key stops the conversion with an
error naming it, so a scene edited later cannot silently render differently in Mitsuba:

- `[render]` width, height, max_depth (conetrace's `max_depth` counts bounces after the
  camera hit, each hit taking one light sample; Mitsuba's `max_depth` counts path segments,
  2 being direct lighting, so Mitsuba gets `max_depth + 2`: both end their longest path
  with the light sample at hit `max_depth + 1`);
- `[camera]` pinhole: eye, target, up, vertical field of view (Mitsuba `fov_axis = "y"`);
- `[[texture]]` file (sRGB PNG, decoded to linear by both), wrap periodic or clamp;
- `[[material]]` as one lobe each: diffuse `base_color` (times its texture), `mirror = 1`
  (Mitsuba `conductor` with `material = "none"`: reflectance 1), `transmission = 1` (Mitsuba
  `dielectric`, inside `ior`, outside exactly 1 as conetrace's), `emission` (a one-sided
  `area` emitter of that radiance on the shape, over the diffuse `base_color`);
- `[[mesh]]` OBJ file with `scale`, `rotate` (degrees about x, then y, then z) and
  `translate`, composed `translate * rotate * scale` as conetrace does; `[[sphere]]`.
- no `[environment]`, no `[[light]]`: both renderers then see a black environment.
"""

import math
import os
import tomllib

import numpy as np

KNOWN_RENDER = {"width", "height", "spp", "max_depth"}
KNOWN_CAMERA = {"type", "eye", "target", "up", "fov"}
KNOWN_TEXTURE = {"name", "file", "wrap"}
KNOWN_MATERIAL = {"name", "base_color", "base_color_texture", "mirror", "transmission", "ior",
                  "emission"}
KNOWN_MESH = {"file", "material", "scale", "rotate", "translate"}
KNOWN_SPHERE = {"center", "radius", "material"}
KNOWN_TOP = {"render", "camera", "texture", "material", "mesh", "sphere"}


class UnsupportedScene(ValueError):
    pass


def _check_keys(where, table, known):
    extra = set(table) - known
    if extra:
        raise UnsupportedScene(f"{where}: keys not converted for Mitsuba: {sorted(extra)}")


def load(path):
    with open(path, "rb") as f:
        scene = tomllib.load(f)
    _check_keys(path, scene, KNOWN_TOP)
    return scene


def placement(mesh):
    """conetrace's `translate * rotate * scale` as a 4x4 matrix; the rotation turns about x,
    then y, then z (right-handed, degrees): R = Rz Ry Rx."""
    scale = mesh.get("scale", 1.0)
    scale = [scale] * 3 if isinstance(scale, (int, float)) else scale
    ax, ay, az = (math.radians(a) for a in mesh.get("rotate", [0.0, 0.0, 0.0]))
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    matrix = np.eye(4)
    matrix[:3, :3] = rz @ ry @ rx @ np.diag(scale)
    matrix[:3, 3] = mesh.get("translate", [0.0, 0.0, 0.0])
    return matrix


def mitsuba_dict(mi, toml_path, sampler="multijitter", spp=1, width=None, height=None,
                 max_depth=None):
    """The Mitsuba scene dictionary of the TOML at `toml_path`; `width`, `height` and
    `max_depth` (conetrace's convention) override the TOML's `[render]` values."""
    scene = load(toml_path)
    base = os.path.dirname(os.path.abspath(toml_path))
    render = scene.get("render", {})
    _check_keys(f"{toml_path} [render]", render, KNOWN_RENDER)
    camera = scene["camera"]
    _check_keys(f"{toml_path} [camera]", camera, KNOWN_CAMERA)
    if camera.get("type", "pinhole") != "pinhole":
        raise UnsupportedScene(f"{toml_path}: camera type {camera['type']} not converted")
    depth = render.get("max_depth", 8) if max_depth is None else max_depth

    textures = {}
    for texture in scene.get("texture", []):
        _check_keys(f"{toml_path} texture {texture.get('name')}", texture, KNOWN_TEXTURE)
        wrap = {"periodic": "repeat", "clamp": "clamp"}[texture.get("wrap", "periodic")]
        textures[texture["name"]] = {
            "type": "bitmap", "filename": os.path.join(base, texture["file"]),
            "filter_type": "bilinear", "wrap_mode": wrap, "raw": False}

    bsdfs, emitters = {}, {}
    for material in scene.get("material", []):
        name = material["name"]
        _check_keys(f"{toml_path} material {name}", material, KNOWN_MATERIAL)
        mirror = material.get("mirror", 0.0)
        transmission = material.get("transmission", 0.0)
        if mirror not in (0.0, 1.0) or transmission not in (0.0, 1.0) or mirror * transmission:
            raise UnsupportedScene(f"{toml_path} material {name}: only pure lobes convert")
        if mirror == 1.0:
            bsdfs[name] = {"type": "conductor", "material": "none"}
        elif transmission == 1.0:
            bsdfs[name] = {"type": "dielectric", "int_ior": float(material.get("ior", 1.5)),
                           "ext_ior": 1.0}
        else:
            colour = {"type": "rgb", "value": material.get("base_color", [0.8] * 3)}
            if "base_color_texture" in material:
                if material.get("base_color", [1.0] * 3) != [1.0] * 3:
                    raise UnsupportedScene(f"{toml_path} material {name}: tinted texture")
                colour = textures[material["base_color_texture"]]
            bsdfs[name] = {"type": "diffuse", "reflectance": colour}
        if any(material.get("emission", [0.0] * 3)):
            emitters[name] = {"type": "area",
                              "radiance": {"type": "rgb", "value": material["emission"]}}

    def with_material(shape, name):
        shape["bsdf"] = bsdfs[name]
        if name in emitters:
            shape["emitter"] = emitters[name]
        return shape

    out = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": depth + 2},
        "sensor": {
            "type": "perspective",
            "fov": float(camera.get("fov", 45.0)),
            "fov_axis": "y",
            "near_clip": 1e-3,
            "to_world": mi.ScalarTransform4f().look_at(
                origin=camera["eye"], target=camera["target"], up=camera.get("up", [0, 1, 0])),
            "sampler": {"type": sampler, "sample_count": spp},
            "film": {"type": "hdrfilm", "width": width or render.get("width", 640),
                     "height": height or render.get("height", 360), "pixel_format": "rgb",
                     "rfilter": {"type": "box"}},
        },
    }
    for index, mesh in enumerate(scene.get("mesh", [])):
        _check_keys(f"{toml_path} mesh {index}", mesh, KNOWN_MESH)
        out[f"mesh_{index}"] = with_material(
            {"type": "obj", "filename": os.path.join(base, mesh["file"]),
             "to_world": mi.ScalarTransform4f(placement(mesh).tolist())}, mesh["material"])
    for index, sphere in enumerate(scene.get("sphere", [])):
        _check_keys(f"{toml_path} sphere {index}", sphere, KNOWN_SPHERE)
        out[f"sphere_{index}"] = with_material(
            {"type": "sphere", "center": sphere["center"], "radius": float(sphere["radius"])},
            sphere["material"])
    return out
