#!/usr/bin/env python3
"""Path tracing: conetrace's `--integrator path` against Mitsuba 3's `path` integrator on the
same scene (bench/peers/scene/path_peer.toml: textured ground, ~300k-triangle displaced
sphere, mirror sphere, glass sphere, one emissive quad, 512 x 512, max depth 8), in one run:
for N = 1, 2, 4, ..., --max-spp both render, each render is timed and scored against one
shared reference, and the script reports how long each needs for a given error (equal-RMSE
time ratio) and what error each reaches in a given time (equal-time RMSE ratio), ours over
Mitsuba's, both interpolated log-log between the bracketing sample counts.

Times: conetrace = the `seconds` of `--stats` (rendering only: process start, scene loading,
BVH build and EXR writing excluded); Mitsuba = `mi.render` plus the copy into numpy, after an
untimed first render (Dr.Jit traces and LLVM-compiles its kernel then, and reuses it at every
sample count; `mi.load_dict` is excluded too). Mitsuba's curve runs to 4 x --max-spp.
Every configuration runs once per timing round, both renderers taking turns, and the fastest
run counts.

Reference: the mean of four images at --ref-spp / 2 samples each, two by each renderer with
seeds unlike the curve's 0; before they are merged, the two renderers' halves are compared
as cornell.py compares its images (RMSE against the noise-only value, image-mean z scores).
The reference's own noise adds the same variance to every curve point's squared RMSE; it is
estimated from the four images and subtracted (the `rmse` columns; `rmse_raw` keeps it).

Called by run.sh (`bash bench/peers/mitsuba/run.sh path`); see bench/peers/README.md. Not
part of the test suite; nothing asserts a time. Writes <results>/path.{csv,md}.
"""

import argparse
import csv
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cornell  # noqa: E402  (conetrace path render, two-renderer statistics)
import direct  # noqa: E402  (the displaced sphere mesh)
import run as peers  # noqa: E402  (EXR reading, time to error, machine facts)
import toml_scene  # noqa: E402

SCENE_TOML = os.path.join(peers.SCENE_DIR, "path_peer.toml")
SAMPLER = "multijitter"
# One bilinear lookup of the full-resolution texture per sample, what Mitsuba's `bitmap`
# does: a footprint-filtered lookup would converge to a smoother image than the reference.
TEXTURE_ARGUMENTS = ("--lod", "mip0", "--filter", "bilinear")


def log(message):
    print(message, flush=True)


def interpolate_loglog(xs, ys, x):
    """y at x on the polyline through (xs, ys) in log-log coordinates, xs increasing; None
    outside [xs[0], xs[-1]]."""
    for (x0, y0), (x1, y1) in zip(zip(xs, ys), zip(xs[1:], ys[1:])):
        if x0 <= x <= x1:
            if x1 == x0:
                return y0
            f = (math.log(x) - math.log(x0)) / (math.log(x1) - math.log(x0))
            return math.exp(math.log(y0) + f * (math.log(y1) - math.log(y0)))
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--conetrace", required=True, help="release conetrace binary")
    parser.add_argument("--work", required=True, help="directory for intermediate EXRs")
    parser.add_argument("--results", default=os.path.join(peers.PEERS, "results"))
    parser.add_argument("--max-spp", type=int, default=64, help="largest N of both curves")
    parser.add_argument("--mitsuba-max-spp", type=int, default=0,
                        help="largest N of Mitsuba's curve (default 4 x --max-spp)")
    parser.add_argument("--ref-spp", type=int, default=512,
                        help="reference: total samples, split over four images")
    parser.add_argument("--repeats", type=int, default=2, help="timing rounds")
    parser.add_argument("--variant", default="llvm_ad_rgb")
    args = parser.parse_args()
    if args.ref_spp < 8 or args.ref_spp % 4:
        parser.error("--ref-spp must be a multiple of 4, at least 8")
    work = os.path.join(args.work, "path")
    os.makedirs(work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)
    threads = os.cpu_count() or 1
    info = {"load_before": cornell.load_average(),
            "machine": f"{threads} logical CPUs ({peers.cpu_model()}), {peers.os_name()}"}
    log(f"load average before: {info['load_before']}")
    if not os.path.exists(direct.MESH_OBJ):
        count = direct.make_mesh(direct.MESH_OBJ)
        log(f"wrote {direct.MESH_OBJ}: {count} triangles")
    with open(direct.MESH_OBJ) as f:
        info["triangles"] = sum(1 for line in f if line.startswith("f "))

    import mitsuba as mi
    import drjit as dr
    mi.set_log_level(mi.LogLevel.Error)
    mi.set_variant(args.variant)
    start = time.perf_counter()
    scene_dict = toml_scene.mitsuba_dict(mi, SCENE_TOML, SAMPLER, 1)
    scene = mi.load_dict(scene_dict)
    info["mitsuba_load"] = time.perf_counter() - start
    film = scene.sensors()[0].film().crop_size()
    info["size"] = (int(film[0]), int(film[1]))
    info["mitsuba"] = (f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}, variant "
                       f"{args.variant}, {dr.thread_count()} threads, sampler {SAMPLER}, "
                       f"max_depth {scene_dict['integrator']['max_depth']} (conetrace's "
                       f"{scene_dict['integrator']['max_depth'] - 2}; toml_scene.py)")
    log(info["mitsuba"])

    def mitsuba_render(spp, seed):
        start = time.perf_counter()
        image = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[:, :, :3]
        return image, time.perf_counter() - start

    # Reference: two half-count images per renderer, seeds unlike the curve's.
    half = args.ref_spp // 4
    ours_ref, theirs_ref, ref_seconds = [], [], {"conetrace": 0.0, "mitsuba": 0.0}
    for seed in (1_000_003, 2_000_003):
        image, seconds = cornell.conetrace_render(
            args.conetrace, SCENE_TOML, os.path.join(work, f"ref_ours_seed{seed}.exr"), half,
            seed, threads, TEXTURE_ARGUMENTS)
        ours_ref.append(image)
        ref_seconds["conetrace"] += seconds
        image, seconds = mitsuba_render(half, seed)
        theirs_ref.append(image)
        ref_seconds["mitsuba"] += seconds
        log(f"reference images, seed {seed}: done")
    agreement = cornell.compare(ours_ref[0], ours_ref[1], theirs_ref[0], theirs_ref[1])
    reference = (ours_ref[0] + ours_ref[1] + theirs_ref[0] + theirs_ref[1]) / 4.0
    # Variance of the mean of four independent images, two of each renderer.
    reference_variance = (2 * agreement["sigma_ours"] ** 2
                          + 2 * agreement["sigma_mitsuba"] ** 2) / 16.0
    info["reference"] = (f"mean of conetrace and Mitsuba, 2 x {half} spp each (seeds "
                         f"1000003, 2000003): {args.ref_spp} samples per pixel; render "
                         f"seconds conetrace {ref_seconds['conetrace']:.0f}, Mitsuba "
                         f"{ref_seconds['mitsuba']:.0f}; its own noise (RMSE) "
                         f"{math.sqrt(reference_variance):.5f}")
    log(info["reference"])
    for key, value in agreement.items():
        log(f"reference agreement {key}: {value}")

    # Mitsuba's curve runs further so that our slower points still have a Mitsuba time to
    # compare with. One untimed render first: Dr.Jit traces and compiles the kernel there
    # and reuses it at every sample count (the first timed render at each count is within
    # the noise of the later ones: `seconds_first` in the CSV).
    mitsuba_max = args.mitsuba_max_spp or 4 * args.max_spp
    _, info["mitsuba_compile"] = mitsuba_render(1, 0)
    configs = [dict(renderer="conetrace", spp=2 ** k, times=[]) for k in range(20)
               if 2 ** k <= args.max_spp]
    configs += [dict(renderer="mitsuba", spp=2 ** k, times=[]) for k in range(20)
                if 2 ** k <= mitsuba_max]
    configs.sort(key=lambda c: c["spp"])
    for round_index in range(args.repeats):
        for config in configs:
            if round_index > 0 and min(config["times"]) > 10.0:
                continue
            if config["renderer"] == "conetrace":
                image, seconds = cornell.conetrace_render(
                    args.conetrace, SCENE_TOML, os.path.join(work, f"ours_{config['spp']}.exr"),
                    config["spp"], 0, threads, TEXTURE_ARGUMENTS)
            else:
                image, seconds = mitsuba_render(config["spp"], 0)
                config["spp_rendered"] = scene.sensors()[0].sampler().sample_count()
            config["times"].append(seconds)
            if round_index == 0:
                raw = cornell.rmse(image, reference)
                config["rmse_raw"] = raw
                config["rmse"] = math.sqrt(max(raw ** 2 - reference_variance, 0.0))
                log(f"{config['renderer']} {config['spp']} spp: {seconds:.3f} s, RMSE "
                    f"{config['rmse']:.5f} (raw {raw:.5f})")
        log(f"timing round {round_index + 1} of {args.repeats} done, load average "
            f"{cornell.load_average()}")
    for config in configs:
        config["seconds"] = min(config["times"])
    # The traversal floor: camera rays alone through Embree at 1 spp (`bench render`'s raw
    # pass), what N samples cost before anything is shaded or bounced.
    info["floor"] = direct.conetrace_floor(args.conetrace, *info["size"], threads, 3,
                                           scene=SCENE_TOML)[0]
    log(f"traversal floor (raw camera rays, 1 spp): {info['floor']:.4f} s")
    info["load_after"] = cornell.load_average()
    log(f"load average after: {info['load_after']}")
    write_results(args, configs, agreement, info)


def comparisons(configs):
    """Per conetrace point: Mitsuba's time to its RMSE and Mitsuba's RMSE at its time."""
    ours = [c for c in configs if c["renderer"] == "conetrace"]
    theirs = [c for c in configs if c["renderer"] == "mitsuba"]
    curve = [(c.get("spp_rendered", c["spp"]), c["seconds"], c["rmse"]) for c in theirs]
    times = [c["seconds"] for c in theirs]
    errors = [c["rmse"] for c in theirs]
    rows = []
    for c in ours:
        hit = peers.time_to_error(curve, c["rmse"])
        at_time = interpolate_loglog(times, errors, c["seconds"])
        rows.append(dict(spp=c["spp"], seconds=c["seconds"], rmse=c["rmse"],
                         mitsuba_time=hit[2] if hit else None,
                         time_ratio=c["seconds"] / hit[2] if hit else None,
                         mitsuba_rmse=at_time,
                         rmse_ratio=c["rmse"] / at_time if at_time else None))
    return rows


def write_results(args, configs, agreement, info):
    csv_path = os.path.join(args.results, "path.csv")
    with open(csv_path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["renderer", "spp", "spp_rendered", "seconds", "seconds_first",
                         "runs", "rmse", "rmse_raw"])
        for c in configs:
            writer.writerow([c["renderer"], c["spp"], c.get("spp_rendered", c["spp"]),
                             f"{c['seconds']:.5g}", f"{c['times'][0]:.5g}",
                             len(c["times"]), f"{c['rmse']:.6g}", f"{c['rmse_raw']:.6g}"])

    def fmt(value, pattern):
        return pattern.format(value) if value is not None else "outside Mitsuba's curve"

    a = agreement
    width, height = info["size"]
    lines = ["# conetrace vs Mitsuba 3: path tracing", "",
             "Generated by `bash bench/peers/mitsuba/run.sh path` (bench/peers/mitsuba/path.py);"
             " set-up in bench/peers/README.md.", "",
             f"- Machine: {info['machine']}; both renderers use all its threads. The machine "
             f"may be shared with other jobs: load average `{info['load_before']}` before "
             f"the run and `{info['load_after']}` after it (1, 5, 15 minutes; about 2 or "
             "more on 2 cores means other work ran).",
             f"- {info['mitsuba']}; `mi.load_dict` {info['mitsuba_load']:.2f} s (not "
             "counted).",
             f"- Scene: bench/peers/scene/path_peer.toml, {width} x {height}, "
             f"{info['triangles']} triangles in the displaced sphere, textured ground, mirror "
             "and glass spheres, one emissive quad, black environment.",
             f"- Reference: {info['reference']}.",
             f"- The two renderers' reference halves: RMSE between them {a['rmse_between']:.5f}"
             f" against {a['rmse_noise_only']:.5f} from noise alone; image-mean difference "
             "conetrace - Mitsuba (R, G, B) "
             + ", ".join(f"{x - y:+.5f}" for x, y in zip(a["mean_ours"], a["mean_mitsuba"]))
             + ", z " + ", ".join(f"{z:+.2f}" for z in a["z"]) + ".",
             "- Seconds: conetrace (`--lod mip0 --filter bilinear`: Mitsuba's texture work) = "
             "`--stats` `seconds` (rendering only); Mitsuba = "
             "`mi.render` plus the copy into numpy; one untimed render at 1 spp first "
             f"(kernel tracing and compilation: {info['mitsuba_compile']:.2f} s), the kernel "
             "then serves every count. Fastest of up to "
             f"{args.repeats} runs (one run for configurations over 10 s).",
             "- RMSE: over all pixels and channels against the reference, its own noise "
             "variance subtracted.", "",
             "## Curves", "",
             "| spp | conetrace s | conetrace RMSE | Mitsuba spp | Mitsuba s | Mitsuba RMSE | "
             "Mitsuba first timed run s |", "|---|---|---|---|---|---|---|"]
    by = {(c["renderer"], c["spp"]): c for c in configs}
    for spp in sorted({c["spp"] for c in configs}):
        o, m = by.get(("conetrace", spp)), by[("mitsuba", spp)]
        ours = f"{o['seconds']:.3f} | {o['rmse']:.5f}" if o else " | "
        lines.append(f"| {spp} | {ours} | {m.get('spp_rendered', spp)} | {m['seconds']:.3f} | "
                     f"{m['rmse']:.5f} | {m['times'][0]:.3f} |")
    lines += ["", "## Ratios, ours / Mitsuba (below 1: conetrace ahead)", "",
              "Equal RMSE: the time Mitsuba needs to reach our RMSE at N spp; equal time: the "
              "RMSE Mitsuba reaches in our time at N spp. Both interpolated log-log along "
              "Mitsuba's curve.", "",
              "Floor: N times conetrace's raw camera-ray traversal at 1 spp (`conetrace bench "
              f"render`'s raw pass, {info['floor']:.4f} s at 1 spp): what the samples cost in "
              "Embree before anything is shaded or bounced; ours / floor is the rest.", "",
              "| spp | conetrace s | conetrace RMSE | Mitsuba s at that RMSE | time ratio | "
              "Mitsuba RMSE at that time | RMSE ratio | floor s | ours / floor |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in comparisons(configs):
        floor = info["floor"] * r["spp"]
        lines.append(f"| {r['spp']} | {r['seconds']:.3f} | {r['rmse']:.5f} | "
                     f"{fmt(r['mitsuba_time'], '{:.3f}')} | {fmt(r['time_ratio'], '{:.2f}')} | "
                     f"{fmt(r['mitsuba_rmse'], '{:.5f}')} | {fmt(r['rmse_ratio'], '{:.2f}')} | "
                     f"{floor:.3f} | {r['seconds'] / floor:.2f} |")
    md_path = os.path.join(args.results, "path.md")
    with open(md_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    log(f"wrote {csv_path} and {md_path}")


if __name__ == "__main__":
    sys.exit(main())
