#!/usr/bin/env python3
"""Direct lighting: conetrace's camera-plus-shadow rendering (`--max-depth 0`) against
Mitsuba 3's `direct` integrator (one emitter sample, no BSDF sample) on the same scene, in
one run: time per sample side by side, and at 1280 x 720 the time each renderer needs to
reach the error of our 1-spp footprint-filtered images.

Scene (bench/peers/scene/direct_light.toml for conetrace, `mitsuba_scene` below for Mitsuba):
the textured ground of the albedo benchmark (plane.obj, tiles.png), a displaced sphere of
about 300 000 triangles written by this script as displaced_sphere.obj (vertex normals
given, so both renderers interpolate the same shading normals), one point light, a black
environment, a pinhole camera and a box pixel filter. Both renderers read the same OBJ and
PNG files.

Called by run.sh (`bash bench/peers/mitsuba/run.sh direct [options]`); see
bench/peers/README.md. Not part of the test suite; nothing here asserts a time. Writes
<results>/direct.{csv,md}.
"""

import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run as peers  # noqa: E402  (EXR reading, time to error, machine facts)

SCENE_TOML = os.path.join(peers.SCENE_DIR, "direct_light.toml")
MESH_OBJ = os.path.join(peers.SCENE_DIR, "displaced_sphere.obj")

# Must equal direct_light.toml (checked by `check_toml`).
EYE, TARGET, UP, VFOV = [0.0, 1.6, 3.0], [0.0, 0.7, -3.5], [0.0, 1.0, 0.0], 40.0
LIGHT_POSITION, LIGHT_INTENSITY = [2.5, 4.0, -1.0], 40.0
SPHERE_CENTRE, SPHERE_RADIUS = [0.0, 1.1, -3.5], 1.0
MESH_ALBEDO = 0.7

SIZES = [(512, 512), (1280, 720)]
# Our configurations: (label, --lod, --filter). "mip0+bilinear" does the texture work
# Mitsuba's bitmap does (one bilinear lookup of the full-resolution texture per sample);
# "cone+aniso" is conetrace's default.
EQUAL_WORK = ("mip0+bilinear", "mip0", "bilinear")
DEFAULT = ("cone+aniso", "cone", "aniso")
FOOTPRINT_METHODS = [("cone+trilinear", "cone", "trilinear"), DEFAULT,
                     ("cone+ewa", "cone", "ewa")]


def log(message):
    print(message, flush=True)


def load_average():
    with open("/proc/loadavg") as f:
        return f.read().strip()


# ------------------------------------------------------------------------------- mesh


def make_mesh(path, segments=548, rings=274):
    """A sphere with smooth bumps, 2 * segments * (rings - 1) triangles (299 208 by
    default): a pole vertex at each end, `rings - 1` rings of `segments` vertices between,
    radius modulated by a product of sines of the unit direction. Vertex normals are the
    area-weighted means of the faces around each vertex. Deterministic bytes."""
    theta = np.pi * np.arange(1, rings) / rings              # polar angle of each ring
    phi = 2.0 * np.pi * np.arange(segments) / segments
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    directions = np.stack([st * np.cos(phi)[None, :], ct.repeat(segments, 1),
                           st * np.sin(phi)[None, :]], axis=-1).reshape(-1, 3)
    directions = np.concatenate([[[0.0, 1.0, 0.0]], directions, [[0.0, -1.0, 0.0]]])
    x, y, z = directions.T
    bumps = 0.06 * np.sin(7.0 * x + 1.0) * np.sin(6.0 * y + 0.5) * np.sin(5.0 * z + 2.0)
    positions = (np.asarray(SPHERE_CENTRE)[None, :]
                 + SPHERE_RADIUS * (1.0 + bumps)[:, None] * directions)
    top, bottom = 0, len(directions) - 1

    def ring(r, s):
        return 1 + r * segments + (s % segments)

    s = np.arange(segments)
    faces = [np.stack([np.full(segments, top), ring(0, s + 1), ring(0, s)], axis=1)]
    for r in range(rings - 2):
        a, b = ring(r, s), ring(r, s + 1)
        c, d = ring(r + 1, s), ring(r + 1, s + 1)
        faces.append(np.stack([a, b, d], axis=1))
        faces.append(np.stack([a, d, c], axis=1))
    faces.append(np.stack([np.full(segments, bottom), ring(rings - 2, s),
                           ring(rings - 2, s + 1)], axis=1))
    faces = np.concatenate(faces)
    p0, p1, p2 = positions[faces[:, 0]], positions[faces[:, 1]], positions[faces[:, 2]]
    face_normals = np.cross(p1 - p0, p2 - p0)
    outward = np.einsum("ij,ij->", face_normals,
                        (p0 + p1 + p2) / 3.0 - np.asarray(SPHERE_CENTRE)[None, :])
    if outward < 0.0:  # wind every triangle counter-clockwise seen from outside
        faces = faces[:, [0, 2, 1]]
        face_normals = -face_normals
    normals = np.zeros_like(positions)
    for corner in range(3):
        np.add.at(normals, faces[:, corner], face_normals)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    with open(path + ".tmp", "w") as f:
        f.write(f"# Displaced sphere, {len(faces)} triangles, written by "
                "bench/peers/mitsuba/direct.py (make_mesh).\n")
        np.savetxt(f, positions, fmt="v %.7f %.7f %.7f")
        np.savetxt(f, normals, fmt="vn %.7f %.7f %.7f")
        one = faces + 1
        np.savetxt(f, np.stack([one, one], axis=2).reshape(-1, 6), fmt="f %d//%d %d//%d %d//%d")
    os.replace(path + ".tmp", path)
    return len(faces)


def check_toml():
    """The numbers shared with Mitsuba must be the TOML's."""
    import tomllib
    with open(SCENE_TOML, "rb") as f:
        toml = tomllib.load(f)
    camera, light = toml["camera"], toml["light"][0]
    assert camera["eye"] == EYE and camera["target"] == TARGET and camera["fov"] == VFOV, camera
    assert light["position"] == LIGHT_POSITION and light["intensity"] == LIGHT_INTENSITY, light
    grey = next(m for m in toml["material"] if m["name"] == "grey")
    assert grey["base_color"] == [MESH_ALBEDO] * 3, grey


# ------------------------------------------------------------------------- renderers


def conetrace_render(binary, out_exr, width, height, spp, lod, filt, threads, seed=0):
    """One render, colour alone (`--aov none`: Mitsuba's `direct` computes no AOVs either);
    returns (image, render seconds from --stats, camera rays)."""
    stats_path = out_exr + ".json"
    command = [binary, "render", SCENE_TOML, "-o", out_exr, "--no-png", "--quiet",
               "--width", str(width), "--height", str(height), "--spp", str(spp),
               "--max-depth", "0", "--lod", lod, "--filter", filt, "--threads", str(threads),
               "--seed", str(seed), "--aov", "none", "--stats", stats_path]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()}")
    with open(stats_path) as f:
        stats = json.load(f)
    return peers.rgb(peers.read_exr(out_exr)), float(stats["seconds"]), stats


def conetrace_floor(binary, width, height, threads, repeat, scene=SCENE_TOML, spp=1):
    """`conetrace bench render` of `scene` at `spp` samples per pixel: (raw camera-ray
    traversal seconds, camera + shadow rays traced with nothing shaded seconds), medians of
    `repeat` runs. Both passes trace the render's own camera rays, every sample of every
    pixel in the packets the renderer builds."""
    command = [binary, "bench", "render", scene, "--width", str(width), "--height",
               str(height), "--spp", str(spp), "--max-depth", "0", "--threads", str(threads),
               "--repeat", str(repeat)]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()}")
    raw = re.search(r"^\| raw packet traversal[^|]*\| ([0-9.]+) \|", done.stdout, re.M)
    shadow = re.search(r"^\| camera \+ shadow rays traced, nothing shaded[^|]*\| ([0-9.]+) \|",
                       done.stdout, re.M)
    if not raw or not shadow:
        raise RuntimeError(f"unexpected `conetrace bench render` output:\n{done.stdout}")
    return float(raw.group(1)), float(shadow.group(1))


def mitsuba_scene(mi, width, height, sampler, spp):
    return {
        "type": "scene",
        "integrator": {"type": "direct", "emitter_samples": 1, "bsdf_samples": 0},
        "sensor": {
            "type": "perspective",
            "fov": VFOV,
            "fov_axis": "y",
            "near_clip": 1e-3,
            "to_world": mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=UP),
            "sampler": {"type": sampler, "sample_count": spp},
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "pixel_format": "rgb", "rfilter": {"type": "box"}},
        },
        "light": {"type": "point", "position": LIGHT_POSITION,
                  "intensity": {"type": "uniform", "value": LIGHT_INTENSITY}},
        "ground": {
            "type": "obj",
            "filename": os.path.join(peers.SCENE_DIR, "plane.obj"),
            "bsdf": {"type": "diffuse", "reflectance": {
                "type": "bitmap", "filename": os.path.join(peers.SCENE_DIR, "tiles.png"),
                "filter_type": "bilinear", "wrap_mode": "repeat", "raw": False}},
        },
        "sphere": {
            "type": "obj",
            "filename": MESH_OBJ,
            "bsdf": {"type": "diffuse",
                     "reflectance": {"type": "rgb", "value": [MESH_ALBEDO] * 3}},
        },
    }


def rmse(image, truth):
    return float(np.sqrt(np.mean((image - truth) ** 2)))


# ------------------------------------------------------------------------------ main


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--conetrace", required=True, help="release conetrace binary")
    parser.add_argument("--work", required=True, help="directory for intermediate EXRs")
    parser.add_argument("--results", default=os.path.join(peers.PEERS, "results"))
    parser.add_argument("--gt-spp", type=int, default=256,
                        help="ground truth at 1280 x 720: conetrace mip0+bilinear samples")
    parser.add_argument("--gt-seed", type=int, default=1_000_003)
    parser.add_argument("--max-spp", type=int, default=256, help="Mitsuba curve's largest N")
    parser.add_argument("--repeats", type=int, default=3, help="timed rounds after the first")
    parser.add_argument("--reuse-ground-truth", action="store_true")
    parser.add_argument("--variant", default="llvm_ad_rgb")
    args = parser.parse_args()
    work = os.path.join(args.work, "direct")
    os.makedirs(work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)
    threads = os.cpu_count() or 1
    info = {"load_before": load_average(),
            "machine": f"{threads} logical CPUs ({peers.cpu_model()}), {peers.os_name()}"}
    log(f"load average before: {info['load_before']}")

    if not os.path.exists(MESH_OBJ):
        count = make_mesh(MESH_OBJ)
        log(f"wrote {MESH_OBJ}: {count} triangles")
    with open(MESH_OBJ) as f:
        info["triangles"] = sum(1 for line in f if line.startswith("f "))
    check_toml()

    # Ground truth at 1280 x 720: conetrace mip0+bilinear at many samples, with a seed
    # unlike the compared renders' (conetrace's sample i is the same at every count).
    gw, gh = SIZES[1]
    gt_exr = os.path.join(work, "ground_truth.exr")
    reused = False
    if args.reuse_ground_truth and os.path.exists(gt_exr + ".json"):
        with open(gt_exr + ".json") as f:
            stats = json.load(f)
        reused = (stats.get("spp"), stats.get("width"), stats.get("height")) == (
            args.gt_spp, gw, gh)
    if reused:
        truth = peers.rgb(peers.read_exr(gt_exr))
        gt_seconds = float(stats["seconds"])
    else:
        truth, gt_seconds, _ = conetrace_render(args.conetrace, gt_exr, gw, gh, args.gt_spp,
                                                "mip0", "bilinear", threads, args.gt_seed)
    info["ground_truth"] = (f"conetrace --lod mip0 --filter bilinear --spp {args.gt_spp} "
                            f"--seed {args.gt_seed} --max-depth 0 at {gw} x {gh} "
                            f"({gt_seconds:.1f} s render"
                            + (", reused from an earlier run)" if reused else ")"))
    log(f"ground truth: {info['ground_truth']}")

    import mitsuba as mi
    import drjit as dr
    mi.set_log_level(mi.LogLevel.Error)
    variant = args.variant
    try:
        mi.set_variant(variant)
        mi.render(mi.load_dict(mitsuba_scene(mi, 16, 16, "independent", 1)), spp=1)
    except Exception as error:  # noqa: BLE001 - any LLVM failure means: fall back
        log(f"variant {variant} failed ({error}); falling back to scalar_rgb")
        variant = "scalar_rgb"
        mi.set_variant(variant)
    info["mitsuba"] = (f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}, variant {variant}, "
                       f"{dr.thread_count()} threads, LLVM library loaded: "
                       f"{peers.loaded_llvm()}")
    log(info["mitsuba"])
    scenes = {}
    for size in SIZES:
        start = time.perf_counter()
        scenes[size] = mi.load_dict(mitsuba_scene(mi, *size, "multijitter", 1))
        info[f"load_{size[0]}x{size[1]}"] = time.perf_counter() - start

    # The timed configurations. Per-sample table: both sizes, 1 and 16 spp, ours at equal
    # texture work and at the default. Equal-error table (1280 x 720): our 1-spp footprint
    # methods and Mitsuba's multijitter curve.
    configs = []
    for size in SIZES:
        for spp in (1, 16):
            for label, lod, filt in (EQUAL_WORK, DEFAULT):
                configs.append(dict(renderer="conetrace", method=label, lod=lod, filt=filt,
                                    size=size, spp=spp))
    for label, lod, filt in FOOTPRINT_METHODS:
        if not any(c["method"] == label and c["size"] == SIZES[1] and c["spp"] == 1
                   for c in configs):
            configs.append(dict(renderer="conetrace", method=label, lod=lod, filt=filt,
                                size=SIZES[1], spp=1))
    mitsuba_counts = {SIZES[0]: [1, 16]}
    mitsuba_counts[SIZES[1]] = sorted({1, 16} | {2 ** k for k in range(20)
                                                  if 2 ** k <= args.max_spp})
    for size, counts in mitsuba_counts.items():
        for spp in counts:
            configs.append(dict(renderer="mitsuba", method="direct (bilinear, no mip)",
                                size=size, spp=spp))

    def run(config):
        width, height = config["size"]
        if config["renderer"] == "conetrace":
            exr = os.path.join(work, f"{config['method'].replace('+', '_')}_{width}x{height}"
                                     f"_{config['spp']}spp.exr")
            image, seconds, stats = conetrace_render(args.conetrace, exr, width, height,
                                                     config["spp"], config["lod"],
                                                     config["filt"], threads)
            config["shadow_rays"] = stats["counters"]["shadow_rays"]
            return seconds, image
        scene = scenes[config["size"]]
        start = time.perf_counter()
        image = np.array(mi.render(scene, spp=config["spp"], seed=0), dtype=np.float64)
        seconds = time.perf_counter() - start
        config["spp_rendered"] = scene.sensors()[0].sampler().sample_count()
        return seconds, image[:, :, :3]

    for config in configs:
        seconds, image = run(config)
        config["first"] = seconds
        config["times"] = [seconds] if config["renderer"] == "conetrace" else []
        if config["size"] == SIZES[1]:
            config["rmse"] = rmse(image, truth)
        log(f"{config['renderer']} {config['method']} {config['size'][0]}x{config['size'][1]} "
            f"{config['spp']} spp: {seconds:.3f} s first"
            + (f", RMSE {config['rmse']:.5f}" if "rmse" in config else ""))
    floors = {}
    for round_index in range(args.repeats):
        for config in configs:
            if round_index > 0 and max(config["times"] + [config["first"]]) > 5.0:
                continue
            seconds, _ = run(config)
            config["times"].append(seconds)
        for size in SIZES:
            for spp in (1, 16):
                raw, shadow = conetrace_floor(args.conetrace, *size, threads, 3, spp=spp)
                floors.setdefault((size, spp), []).append((raw, shadow))
        log(f"timing round {round_index + 1} of {args.repeats} done")
    for c in configs:
        c["seconds"] = min(c["times"])
    floor = {key: (min(r for r, _ in v), min(s for _, s in v)) for key, v in floors.items()}

    # Convention check: Mitsuba at the ground truth's sample count against it.
    check_scene = mi.load_dict(mitsuba_scene(mi, gw, gh, "multijitter", args.gt_spp))
    check = np.array(mi.render(check_scene, spp=args.gt_spp, seed=7),
                     dtype=np.float64)[:, :, :3]
    diff = check - truth
    info["check"] = (f"Mitsuba multijitter {check_scene.sensors()[0].sampler().sample_count()} "
                     f"spp vs the ground truth: RMSE {rmse(check, truth):.2e}, mean difference "
                     f"{np.mean(diff):+.1e}, pixels differing by more than 0.05 in a channel: "
                     f"{int(np.sum(np.max(np.abs(diff), axis=2) > 0.05))} of {gw * gh}")
    log(info["check"])
    info["load_after"] = load_average()
    log(f"load average after: {info['load_after']}")
    write_results(args, configs, floor, info)


def write_results(args, configs, floor, info):
    csv_path = os.path.join(args.results, "direct.csv")
    fields = ["renderer", "method", "width", "height", "spp", "spp_rendered", "seconds",
              "seconds_first", "runs", "rmse_1280x720"]
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        for c in configs:
            writer.writerow(dict(
                renderer=c["renderer"], method=c["method"], width=c["size"][0],
                height=c["size"][1], spp=c["spp"], spp_rendered=c.get("spp_rendered", c["spp"]),
                seconds=f"{c['seconds']:.6g}", seconds_first=f"{c['first']:.6g}",
                runs=len(c["times"]), rmse_1280x720=f"{c['rmse']:.6g}" if "rmse" in c else ""))
        for (size, spp), (raw, shadow) in floor.items():
            for label, value in (("raw camera-ray traversal", raw),
                                 ("camera + shadow rays traced, nothing shaded", shadow)):
                writer.writerow(dict(renderer="conetrace bench render", method=label,
                                     width=size[0], height=size[1], spp=spp, spp_rendered=spp,
                                     seconds=f"{value:.6g}", seconds_first="", runs="",
                                     rmse_1280x720=""))

    def find(renderer, method, size, spp):
        return next(c for c in configs if c["renderer"] == renderer and c["method"] == method
                    and c["size"] == size and c["spp"] == spp)

    lines = ["# conetrace vs Mitsuba 3: direct lighting (camera + shadow rays)", "",
             "Generated by `bash bench/peers/mitsuba/run.sh direct` "
             "(bench/peers/mitsuba/direct.py); set-up in bench/peers/README.md.", "",
             f"- Machine: {info['machine']}; both renderers use all its threads. The machine "
             "may be shared with other jobs: load average "
             f"`{info['load_before']}` before the run and `{info['load_after']}` after it "
             "(1, 5, 15 minutes; about 2 or more on 2 cores means other work ran). "
             "Configurations take turns in every timing round and the "
             "fastest run counts, so both renderers see the same conditions; ratios within "
             "about 1.5 read as \"about equal\".",
             f"- {info['mitsuba']}; `mi.load_dict` 512x512: "
             f"{info['load_512x512']:.2f} s, 1280x720: {info['load_1280x720']:.2f} s (not "
             "counted).",
             f"- Scene: bench/peers/scene/direct_light.toml, {info['triangles']} triangles in "
             "the displaced sphere plus the 2-triangle textured ground, one point light.",
             f"- Ground truth: {info['ground_truth']}.",
             f"- Convention check: {info['check']}.",
             "- Seconds: conetrace = `--stats` `seconds` (rendering only; scene load, BVH "
             "build and EXR writing excluded); Mitsuba = `mi.render` plus the copy into numpy, "
             "its first render at each size and count (kernel tracing and compilation) "
             f"excluded. Fastest of up to {args.repeats + 1} runs.", "",
             "## Time per sample, side by side", "",
             "ours / Mitsuba = the ratio of the two times at the same size and sample count "
             "(equal sample counts, so also the ratio per sample). Floor: conetrace's own "
             "`bench render` passes on the same scene at the same size and sample count, "
             "the render's own camera rays (raw = camera rays traced, nothing else; camera + "
             "shadow = also one occlusion ray per hit, nothing shaded); floor / Mitsuba is the "
             "camera + shadow floor over Mitsuba's whole render: the ratio no shading, "
             "however fast, can go below.",
             "",
             "| size | spp | Mitsuba s | ours mip0+bilinear s | ratio | ours cone+aniso s "
             "| ratio | raw traversal s | camera + shadow traversal s | floor / Mitsuba |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for size in SIZES:
        for spp in (1, 16):
            raw, shadow = floor[(size, spp)]
            m = find("mitsuba", "direct (bilinear, no mip)", size, spp)
            e = find("conetrace", EQUAL_WORK[0], size, spp)
            d = find("conetrace", DEFAULT[0], size, spp)
            lines.append(
                f"| {size[0]}x{size[1]} | {m.get('spp_rendered', spp)} | {m['seconds']:.4f} "
                f"| {e['seconds']:.4f} | {e['seconds'] / m['seconds']:.2f} | "
                f"{d['seconds']:.4f} | {d['seconds'] / m['seconds']:.2f} | {raw:.4f} | "
                f"{shadow:.4f} | {shadow / m['seconds']:.2f} |")

    curve = [(c.get("spp_rendered", c["spp"]), c["seconds"], c["rmse"]) for c in configs
             if c["renderer"] == "mitsuba" and c["size"] == SIZES[1]]
    lines += ["", "## Time to reach our 1-spp error (1280 x 720)", "",
              "For each of our 1-spp footprint-filtered images: its RMSE against the ground "
              "truth, its time, and the first N of Mitsuba's multijitter curve (powers of two) "
              "at or below that RMSE with its time (and the time interpolated log-log between "
              "the bracketing N); ours / Mitsuba = our time over Mitsuba's interpolated time.",
              "", "| ours, 1 spp | RMSE | ours s | Mitsuba N | Mitsuba s (interp.) | "
              "ours / Mitsuba |", "|---|---|---|---|---|---|"]
    for label, _, _ in [EQUAL_WORK] + FOOTPRINT_METHODS:
        c = find("conetrace", label, SIZES[1], 1)
        hit = peers.time_to_error(curve, c["rmse"])
        if hit is None:
            lines.append(f"| {label} | {c['rmse']:.5f} | {c['seconds']:.4f} | not reached "
                         f"by N = {curve[-1][0]} | | |")
        else:
            lines.append(f"| {label} | {c['rmse']:.5f} | {c['seconds']:.4f} | {hit[0]} | "
                         f"{hit[1]:.4f} ({hit[2]:.4f}) | {c['seconds'] / hit[2]:.2f} |")
    lines += ["", "## All runs", "", "| renderer | method | size | spp | seconds | first | "
              "RMSE (1280x720) |", "|---|---|---|---|---|---|---|"]
    for c in configs:
        lines.append(f"| {c['renderer']} | {c['method']} | {c['size'][0]}x{c['size'][1]} | "
                     f"{c.get('spp_rendered', c['spp'])} | {c['seconds']:.4f} | "
                     f"{c['first']:.4f} | " + (f"{c['rmse']:.5f}" if "rmse" in c else "") + " |")
    md_path = os.path.join(args.results, "direct.md")
    with open(md_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    log(f"wrote {csv_path} and {md_path}")


if __name__ == "__main__":
    sys.exit(main())
