#!/usr/bin/env python3
"""conetrace (1 sample per pixel, footprint-filtered textures) against Mitsuba 3 (many samples
per pixel, point-sampled bilinear texture) on the same scene: texture colour at the first hit,
error against the same ground truth, and the time each needs to reach a given error.

Called by run.sh, which installs Mitsuba into a virtual environment and builds conetrace;
see bench/peers/README.md. Not part of the test suite.

Scene: bench/peers/scene/grazing_plane.toml (conetrace) and the dictionary built by
`mitsuba_scene` below (Mitsuba): the same OBJ plane, the same sRGB PNG texture (decoded to
linear by both, periodic wrap, bilinear reconstruction with texel centres at (i + 0.5) / n),
the same pinhole camera (vertical field of view 40 degrees, look-at, 320 x 180) and a box
pixel filter on both sides.

Ground truth: conetrace at --spp 4096 (64 x 64 jittered strata per pixel), --lod mip0
--filter bilinear; its averaged colour equals the texture colour because the scene has no
lights and a white environment (colour = albedo x environment mean). Ours: conetrace at
1 spp with ray cones / differentials and mip-mapped filters, its colour (which equals its
texcolor AOV bit for bit here; timed renders write colour alone, `--aov none`). Mitsuba: the
`aov` integrator's albedo output at N spp (the bitmap texture evaluated at each sample's
hit point, averaged by the box filter).
"""

import argparse
import csv
import json
import math
import os
import platform
import subprocess
import sys
import time

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
PEERS = os.path.dirname(HERE)
SCENE_DIR = os.path.join(PEERS, "scene")
SCENE_TOML = os.path.join(SCENE_DIR, "grazing_plane.toml")

WIDTH, HEIGHT = 320, 180  # --width / --height override
EYE, TARGET, UP, VFOV = [0.0, 1.0, 0.0], [0.0, 0.0, -2.25], [0.0, 1.0, 0.0], 40.0
# The grazing band: the top third of the image (rays 4 to 17 degrees below the horizon),
# where the texture is minified most and most anisotropically.
FAR_ROWS = HEIGHT // 3

OURS = [
    ("mip0", "bilinear"),
    ("distance", "trilinear"),
    ("cone", "trilinear"),
    ("cone", "aniso"),
    ("cone", "ewa"),
    ("differential", "ewa"),
]


def log(message):
    print(message, flush=True)


# ----------------------------------------------------------------------------- images


def read_exr(path):
    """{channel name: HxW float32 array} of an EXR file."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise RuntimeError(f"{path}: {oiio.geterror()}")
    spec = inp.spec()
    pixels = inp.read_image(0, 0, 0, spec.nchannels, "float")
    inp.close()
    pixels = np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels)
    return {name: pixels[:, :, i] for i, name in enumerate(spec.channelnames)}


def rgb(channels, prefix=""):
    return np.stack([channels[prefix + c] for c in "RGB"], axis=-1).astype(np.float64)


def errors(image, truth, mask):
    """RMSE and PSNR (peak 1, linear values) over all channels: whole image, masked pixels
    (textured), the grazing band."""
    diff = image - truth
    out = {}
    for name, sel in (
        ("all", np.ones(mask.shape, bool)),
        ("textured", mask),
        ("far", np.arange(HEIGHT)[:, None].repeat(WIDTH, 1) < FAR_ROWS),
    ):
        rmse = float(np.sqrt(np.mean(diff[sel] ** 2)))
        out[f"rmse_{name}"] = rmse
        out[f"psnr_{name}"] = 20.0 * math.log10(1.0 / rmse) if rmse > 0 else float("inf")
    return out


def to_srgb8(image):
    c = np.clip(image, 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return (s * 255.0 + 0.5).astype(np.uint8)


def write_png(path, image):
    data = to_srgb8(image)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], 3, "uint8")
    out = oiio.ImageOutput.create(path)
    if out is None or not out.open(path, spec):
        raise RuntimeError(f"{path}: {oiio.geterror()}")
    out.write_image(data)
    out.close()


# --------------------------------------------------------------------------- conetrace


def conetrace_arguments(spp, lod, filt, threads, aov="none"):
    """The render options of every conetrace run here. Timed renders write colour and alpha
    alone (`--aov none`: Mitsuba's `aov` integrator computes the albedo and nothing else);
    the ground truth adds the footprint layers, whose texcolor.A marks textured pixels."""
    return ["--width", str(WIDTH), "--height", str(HEIGHT), "--no-png", "--quiet",
            "--spp", str(spp), "--lod", lod, "--filter", filt, "--aov", aov,
            "--threads", str(threads)]


def conetrace_render(binary, out_exr, stats_json, spp, lod, filt, threads, aov="none"):
    """Runs one conetrace render; returns (render seconds from --stats, wall seconds)."""
    command = ([binary, "render", SCENE_TOML, "-o", out_exr]
               + conetrace_arguments(spp, lod, filt, threads, aov) + ["--stats", stats_json])
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()}")
    with open(stats_json) as f:
        stats = json.load(f)
    return float(stats["seconds"]), wall


# ----------------------------------------------------------------------------- Mitsuba


def mitsuba_scene(mi, sampler, spp):
    return {
        "type": "scene",
        "integrator": {"type": "aov", "aovs": "albedo:albedo"},
        "sensor": {
            "type": "perspective",
            "fov": VFOV,
            "fov_axis": "y",
            "near_clip": 1e-3,
            "to_world": mi.ScalarTransform4f().look_at(origin=EYE, target=TARGET, up=UP),
            "sampler": {"type": sampler, "sample_count": spp},
            "film": {
                "type": "hdrfilm",
                "width": WIDTH,
                "height": HEIGHT,
                "pixel_format": "rgb",
                "rfilter": {"type": "box"},
            },
        },
        "plane": {
            "type": "obj",
            "filename": os.path.join(SCENE_DIR, "plane.obj"),
            "bsdf": {
                "type": "diffuse",
                "reflectance": {
                    "type": "bitmap",
                    "filename": os.path.join(SCENE_DIR, "tiles.png"),
                    "filter_type": "bilinear",
                    "wrap_mode": "repeat",
                    "raw": False,
                },
            },
        },
    }


def loaded_llvm():
    try:
        with open("/proc/self/maps") as f:
            libs = {line.split()[-1] for line in f if "libLLVM" in line}
        return ", ".join(sorted(libs)) or "none"
    except OSError:
        return "unknown"


# ------------------------------------------------------------------------ time to error


def time_to_error(points, target):
    """points: [(spp, seconds, rmse)] in increasing spp. Returns (first spp reaching target,
    its seconds, seconds interpolated log-log between the bracketing points) or None."""
    previous = None
    for spp, seconds, rmse in points:
        if rmse <= target:
            interpolated = seconds
            if previous is not None and previous[2] > target:
                s0, t0, e0 = previous
                f = (math.log(target) - math.log(e0)) / (math.log(rmse) - math.log(e0))
                interpolated = math.exp(math.log(t0) + f * (math.log(seconds) - math.log(t0)))
            return spp, seconds, interpolated
        previous = (spp, seconds, rmse)
    return None


# -------------------------------------------------------------------------------- main


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--conetrace", required=True, help="release conetrace binary")
    parser.add_argument("--work", required=True, help="directory for intermediate EXRs")
    parser.add_argument("--results", default=os.path.join(PEERS, "results"))
    parser.add_argument("--gt-spp", type=int, default=4096)
    parser.add_argument("--max-spp", type=int, default=4096, help="Mitsuba's largest N")
    parser.add_argument("--check-spp", type=int, default=4096,
                        help="Mitsuba spp of the convention check against the ground truth")
    parser.add_argument("--repeats", type=int, default=5, help="timed rounds after the first")
    parser.add_argument("--reuse-ground-truth", action="store_true",
                        help="keep the work directory's ground truth if its --stats match")
    parser.add_argument("--variant", default="llvm_ad_rgb")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=180)
    parser.add_argument("--brute-max-spp", type=int, default=256,
                        help="conetrace mip0+bilinear supersampling: largest N (squares up to it)")
    args = parser.parse_args()
    global WIDTH, HEIGHT, FAR_ROWS
    WIDTH, HEIGHT, FAR_ROWS = args.width, args.height, args.height // 3
    suffix = "" if (WIDTH, HEIGHT) == (320, 180) else f"_{WIDTH}x{HEIGHT}"
    args.stem = "mitsuba" + suffix
    args.work = os.path.join(args.work, f"{WIDTH}x{HEIGHT}")

    os.makedirs(args.work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)
    threads = os.cpu_count() or 1
    info = {
        "machine": f"{threads} logical CPUs ({cpu_model()}), {os_name()}, "
                   f"{platform.system()} {platform.release()}",
        "threads": threads,
    }

    # Ground truth.
    gt_exr = os.path.join(args.work, "ground_truth.exr")
    reused = False
    if args.reuse_ground_truth and os.path.exists(gt_exr + ".json"):
        with open(gt_exr + ".json") as f:
            stats = json.load(f)
        wanted = dict(width=WIDTH, height=HEIGHT, spp=args.gt_spp, lod="mip0", filter="bilinear")
        reused = all(stats.get(k) == v for k, v in wanted.items())
        gt_seconds = gt_wall = float(stats["seconds"])
    if not reused:
        gt_seconds, gt_wall = conetrace_render(
            args.conetrace, gt_exr, gt_exr + ".json", args.gt_spp, "mip0", "bilinear", threads,
            aov="footprint")
    gt = read_exr(gt_exr)
    truth = rgb(gt)
    mask = gt["texcolor.A"] > 0.5
    shown = ["conetrace", "render", "bench/peers/scene/grazing_plane.toml", "-o", "gt.exr"]
    shown += conetrace_arguments(args.gt_spp, "mip0", "bilinear", threads, aov="footprint")
    info["ground_truth"] = f"`{' '.join(shown)}` ({gt_seconds:.2f} s render, {gt_wall:.2f} s wall" \
        + (", reused from an earlier run)" if reused else ")")
    info["textured_pixels"] = int(mask.sum())
    log(f"ground truth: {args.gt_spp} spp mip0+bilinear, {gt_seconds:.2f} s, "
        f"textured pixels {mask.sum()} of {mask.size}")

    # Mitsuba set-up.
    import mitsuba as mi
    import drjit as dr

    mi.set_log_level(mi.LogLevel.Error)  # not the multijitter sample-count rounding notes
    variant = args.variant
    try:
        mi.set_variant(variant)
        mi.render(mi.load_dict(mitsuba_scene(mi, "independent", 1)), spp=1)
    except Exception as error:  # noqa: BLE001 - any LLVM failure means: fall back
        log(f"variant {variant} failed ({error}); falling back to scalar_rgb")
        variant = "scalar_rgb"
        mi.set_variant(variant)
    info["mitsuba"] = (f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}, variant {variant}, "
                       f"{dr.thread_count()} threads, LLVM library loaded: {loaded_llvm()}")
    log(info["mitsuba"])
    scenes = {}
    for sampler in ("independent", "multijitter"):
        start = time.perf_counter()
        scenes[sampler] = mi.load_dict(mitsuba_scene(mi, sampler, 1))
        info[f"load_{sampler}"] = time.perf_counter() - start
    log(f"mi.load_dict: {info['load_independent']:.3f} s (independent), "
        f"{info['load_multijitter']:.3f} s (multijitter)")

    # Every timed configuration. Each is run once in a first round (images, errors, and
    # Mitsuba's first-render time), then in `repeats` further rounds; all configurations
    # take turns within a round, so a busy spell on the shared machine hits both renderers
    # alike. A configuration whose render took over 2 s runs in one further round only.
    configs = []
    for lod, filt in OURS:
        configs.append(dict(renderer="conetrace", method=f"{lod}+{filt}", sampler="centre",
                            spp=1, lod=lod, filt=filt))
    # conetrace brute force (its own supersampling, the same work Mitsuba does). Perfect
    # squares, as in the committed results (conetrace's grids for other counts left cells
    # unsampled before the fix described in README.md, caveats). The averaged colour =
    # averaged texture colour here.
    for n in (1, 2, 3, 4, 6, 8, 12, 16, 24, 32):
        if n * n <= args.brute_max_spp:
            configs.append(dict(renderer="conetrace", method="mip0+bilinear",
                                sampler="stratified" if n > 1 else "centre", spp=n * n,
                                lod="mip0", filt="bilinear"))
    for sampler in ("independent", "multijitter"):
        requested = 1
        while requested <= args.max_spp:
            configs.append(dict(renderer="mitsuba", method="albedo AOV (bilinear, no mip)",
                                sampler=sampler, spp=requested))
            requested *= 2

    def run(config):
        """One render of `config`: (seconds, wall seconds, image)."""
        if config["renderer"] == "conetrace":
            name = f"conetrace_{config['method'].replace('+', '_')}_{config['spp']}spp.exr"
            exr = os.path.join(args.work, name)
            seconds, wall = conetrace_render(args.conetrace, exr, exr + ".json", config["spp"],
                                             config["lod"], config["filt"], threads)
            return seconds, wall, rgb(read_exr(exr))
        scene = scenes[config["sampler"]]
        start = time.perf_counter()
        image = np.array(mi.render(scene, spp=config["spp"], seed=0), dtype=np.float64)
        seconds = time.perf_counter() - start
        # multijitter rounds some counts up (32 -> 35): record what was rendered.
        config["spp"] = scene.sensors()[0].sampler().sample_count()
        return seconds, seconds, image[:, :, :3]

    images = {}
    for config in configs:
        requested = config["spp"]
        seconds, wall, image = run(config)
        config["first"], config["times"], config["walls"] = seconds, [], [wall]
        if config["renderer"] == "conetrace":  # nothing to compile: the first run counts
            config["times"].append(seconds)
        images[(config["renderer"], config["method"], config["sampler"], config["spp"])] = image
        config["errors"] = errors(image, truth, mask)
        note = f" (asked {requested})" if config["spp"] != requested else ""
        log(f"{config['renderer']} {config['method']} {config['sampler']} "
            f"{config['spp']} spp{note}: {seconds:.3f} s first, RMSE "
            f"{config['errors']['rmse_all']:.5f} (far band {config['errors']['rmse_far']:.5f})")
    for round_index in range(args.repeats):
        for config in configs:
            if round_index > 0 and max(config["times"] + [config["first"]]) > 2.0:
                continue
            seconds, wall, _ = run(config)
            config["times"].append(seconds)
            config["walls"].append(wall)
        log(f"timing round {round_index + 1} of {args.repeats} done")
    rows = []
    for c in configs:
        rows.append(dict(renderer=c["renderer"], method=c["method"], sampler=c["sampler"],
                         spp=c["spp"], seconds=min(c["times"]), seconds_first=c["first"],
                         wall=min(c["walls"]), **c["errors"]))
        log(f"{c['renderer']} {c['method']} {c['sampler']} {c['spp']} spp: "
            f"{rows[-1]['seconds']:.3f} s (fastest of {len(c['times'])}), "
            f"RMSE {c['errors']['rmse_all']:.5f}")
    ours_images = {(lod, filt): images[("conetrace", f"{lod}+{filt}", "centre", 1)]
                   for lod, filt in OURS}
    mitsuba_images = {(k[2], k[3]): v for k, v in images.items() if k[0] == "mitsuba"}

    # Convention check: Mitsuba at many samples against the ground truth.
    scene = mi.load_dict(mitsuba_scene(mi, "multijitter", args.check_spp))
    check = np.array(mi.render(scene, spp=args.check_spp, seed=7), dtype=np.float64)[:, :, :3]
    check_errors = errors(check, truth, mask)
    gt2_exr = os.path.join(args.work, "ground_truth_b.exr")
    conetrace_render(args.conetrace, gt2_exr, gt2_exr + ".json", args.gt_spp // 4, "mip0",
                     "bilinear", threads)
    self_errors = errors(rgb(read_exr(gt2_exr)), truth, mask)
    check_spp = scene.sensors()[0].sampler().sample_count()
    info["check"] = (
        f"Mitsuba multijitter {check_spp} spp vs the ground truth: RMSE "
        f"{check_errors['rmse_all']:.2e} (PSNR {check_errors['psnr_all']:.1f} dB; far band "
        f"{check_errors['rmse_far']:.2e}), max abs difference {np.max(np.abs(check - truth)):.3f}, "
        f"mean difference {np.mean(check - truth):+.1e}; for scale, conetrace {args.gt_spp // 4} "
        f"spp vs the ground truth: RMSE {self_errors['rmse_all']:.2e}")
    log(info["check"])

    write_results(args, rows, info, truth, ours_images, mitsuba_images)


def os_name():
    try:
        with open("/etc/os-release") as f:
            for line in f:
                if line.startswith("PRETTY_NAME="):
                    return line.split("=", 1)[1].strip().strip('"')
    except OSError:
        pass
    return "unknown OS"


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def side_by_side(png, top_left, top_right, bottom_left, bottom_right):
    """Writes the four images, 2 x 2, cropped to the far part of the plane (at most 320 x
    180 pixels each, from the top, centred) to keep the file small; returns the window."""
    height, width = top_left.shape[:2]
    w, h = min(width, 320), min(height // 2, 180)
    x0 = (width - w) // 2

    def crop(image):
        return image[:h, x0:x0 + w]

    top = np.concatenate([crop(top_left), crop(top_right)], axis=1)
    bottom = np.concatenate([crop(bottom_left), crop(bottom_right)], axis=1)
    write_png(png, np.concatenate([top, bottom], axis=0))
    return f"each panel pixels x {x0}..{x0 + w - 1}, y 0..{h - 1} of the image"


def write_results(args, rows, info, truth, ours_images, mitsuba_images):
    fields = ["renderer", "method", "sampler", "spp", "seconds", "seconds_first", "wall",
              "rmse_all", "psnr_all", "rmse_textured", "psnr_textured", "rmse_far", "psnr_far"]
    csv_path = os.path.join(args.results, args.stem + ".csv")
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v)
                             for k, v in row.items()})

    def find(method):
        return next(r for r in rows if r["renderer"] == "conetrace" and r["method"] == method
                    and r["spp"] == 1 and r["sampler"] == "centre")

    curves = {
        "Mitsuba, independent": [r for r in rows if r["sampler"] == "independent"],
        "Mitsuba, multijitter": [r for r in rows if r["sampler"] == "multijitter"],
        "conetrace mip0+bilinear, N spp": [r for r in rows if r["renderer"] == "conetrace"
                                           and r["method"] == "mip0+bilinear"],
    }
    targets = []
    for method in ("cone+trilinear", "cone+aniso", "cone+ewa"):
        targets.append((f"{method}'s", find(method)["rmse_all"], "rmse_all"))
    targets.append(("cone+ewa's far-band", find("cone+ewa")["rmse_far"], "rmse_far"))
    targets.append(("tighter (fixed)", 0.01, "rmse_all"))
    footprint_rows = [r for r in rows if r["renderer"] == "conetrace" and r["spp"] == 1
                      and r["method"] != "mip0+bilinear"]

    lines = ["# conetrace vs Mitsuba 3: texture colour at the first hit", ""]
    lines += [
        "Generated by `bash bench/peers/mitsuba/run.sh` (bench/peers/mitsuba/run.py); see "
        "bench/peers/README.md for the set-up and what is compared.", "",
        f"- Image {WIDTH} x {HEIGHT}. Machine: {info['machine']} (a shared VM: other jobs "
        "ran at the same time, so single timings carry noise); both renderers use "
        f"{info['threads']} threads.",
        f"- {info['mitsuba']}. `mi.load_dict` of the scene: {info['load_independent']:.3f} s "
        "(not included below).",
        f"- Ground truth: {info['ground_truth']}; textured pixels: "
        f"{info['textured_pixels']} of {WIDTH * HEIGHT} (the plane fills the image).",
        f"- Convention check: {info['check']}.",
        "- seconds: every configuration runs once, then once per timing round "
        f"({args.repeats} rounds; a configuration that took over 2 s joins the first only), "
        "all configurations of both renderers taking turns within a round; the fastest run "
        "counts. conetrace = the `seconds` field of `--stats` (render only; its first run "
        "counts too); wall = the whole process (scene load, mip pyramid, EXR write). "
        "Mitsuba = `mi.render` plus the copy into numpy, first run excluded; first = that "
        "first render (includes tracing the kernel and compiling it, or loading it from "
        "Dr.Jit's on-disk kernel cache).",
        f"- RMSE over RGB in linear units, PSNR = 20 log10(1 / RMSE); far = the top {FAR_ROWS} "
        "rows (grazing band).", "",
        "## Time to reach an error", "",
        "Target errors are those our 1-spp footprint methods reach, and 0.01. For the "
        "supersampled curves: the first N of the sequence (Mitsuba: powers of two, "
        "multijitter rounds some up; conetrace: squares) whose RMSE is at or below the "
        "target, its seconds, and seconds interpolated log-log between the two bracketing "
        "N.", "",
        "| target | RMSE | conetrace 1 spp, fastest footprint method reaching it | "
        + " | ".join(curves) + " |",
        "|---|---|---|" + "---|" * len(curves),
    ]
    for label, value, metric in targets:
        reaching = [r for r in footprint_rows if r[metric] <= value]
        best = min(reaching, key=lambda r: r["seconds"]) if reaching else None
        cells = ["not reached (bias)" if best is None else
                 f"{best['method']}: {best['seconds']:.3f} s"]
        for points in curves.values():
            pts = [(r["spp"], r["seconds"], r[metric]) for r in points]
            hit = time_to_error(pts, value)
            cells.append("not reached" if hit is None else
                         f"N = {hit[0]}: {hit[1]:.3f} s (interp. {hit[2]:.3f} s)")
        lines.append(f"| {label} {metric.replace('rmse_', '')} | {value:.4f} | "
                     + " | ".join(cells) + " |")
    lines += ["", "## All runs", "",
              "| renderer | method | sampler | spp | seconds | first / wall | RMSE | PSNR dB "
              "| far RMSE | far PSNR dB |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        second = r["wall"] if r["renderer"] == "conetrace" else r["seconds_first"]
        lines.append(
            f"| {r['renderer']} | {r['method']} | {r['sampler']} | {r['spp']} | "
            f"{r['seconds']:.3f} | {second:.3f} | {r['rmse_all']:.5f} | {r['psnr_all']:.2f} | "
            f"{r['rmse_far']:.5f} | {r['psnr_far']:.2f} |")

    # Side by side: ground truth | conetrace cone+ewa 1 spp / Mitsuba 1 spp | Mitsuba at the
    # first N reaching cone+ewa's error.
    ewa = find("cone+ewa")
    hit = time_to_error([(r["spp"], r["seconds"], r["rmse_all"])
                         for r in curves["Mitsuba, multijitter"]], ewa["rmse_all"])
    n_equal = hit[0] if hit else max(k[1] for k in mitsuba_images if k[0] == "multijitter")
    png = os.path.join(args.results, args.stem + "_side_by_side.png")
    window = side_by_side(png, truth, ours_images[("cone", "ewa")],
                          mitsuba_images[("multijitter", 1)],
                          mitsuba_images[("multijitter", n_equal)])
    lines += ["", "## Images", "",
              f"`{args.stem}_side_by_side.png` ({window}): top left the ground truth, top "
              "right conetrace cone+ewa at 1 spp, bottom left Mitsuba at 1 spp (multijitter), "
              f"bottom right Mitsuba at {n_equal} spp (multijitter, "
              + ("the first N reaching cone+ewa's RMSE)." if hit else "its largest N)."),
              "", f"![side by side]({args.stem}_side_by_side.png)", ""]
    md_path = os.path.join(args.results, args.stem + ".md")
    with open(md_path, "w") as f:
        f.write("\n".join(lines))
    log(f"wrote {csv_path}, {md_path}, {png}")


if __name__ == "__main__":
    sys.exit(main())
