#!/usr/bin/env python3
"""The Cornell box (assets/scenes/cornell.toml) path-traced by conetrace (`--integrator path`)
and by Mitsuba 3 (`path` integrator) on the same scene, to check that the two estimate the
same image: each renders it twice at the same sample count with two different seeds, and the
difference between the renderers is compared with the noise of each.

The Mitsuba scene is built from the TOML by toml_scene.py (the TOML is the only place the
scene's numbers are written). Called by run.sh (`bash bench/peers/mitsuba/run.sh cornell`);
see bench/peers/README.md. Not part of the test suite. Writes <results>/cornell.{csv,md}
(<results>/<stem>.{csv,md} for another --scene).

Statistics, for images o1, o2 (ours, two seeds) and m1, m2 (Mitsuba):
- noise of one image: sigma = RMSE(x1, x2) / sqrt(2) (two independent estimates of the same
  expectation differ by sqrt(2) times the error of either);
- difference of the seed-averaged images o = (o1 + o2) / 2, m = (m1 + m2) / 2: RMSE(o, m),
  against the value pure noise gives, sqrt((sigma_o^2 + sigma_m^2) / 2);
- the same two RMSEs on images averaged over 8 x 8-pixel blocks, where the noise is about 8
  times smaller and a local difference (a light leak at an edge, a wrong shadow) stands out;
- image mean per channel: mean(o) - mean(m) against its standard error, the root of the sum
  over pixels of each pixel's estimated variance ((o1 - o2)^2 / 4 + (m1 - m2)^2 / 4) over the
  pixel count: z = difference / standard error, |z| < 3 being within the noise.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run as peers  # noqa: E402  (EXR reading, machine facts)
import toml_scene  # noqa: E402

REPO = os.path.dirname(os.path.dirname(peers.PEERS))
SCENE_TOML = os.path.join(REPO, "assets", "scenes", "cornell.toml")


def log(message):
    print(message, flush=True)


def load_average():
    with open("/proc/loadavg") as f:
        return f.read().strip()


def conetrace_render(binary, scene, out_exr, spp, seed, threads, extra=()):
    """One path-traced render, colour alone (`--aov none`: Mitsuba computes no AOVs either);
    returns (image, render seconds from --stats)."""
    stats_path = out_exr + ".json"
    command = [binary, "render", scene, "-o", out_exr, "--no-png", "--quiet",
               "--integrator", "path", "--spp", str(spp), "--seed", str(seed),
               "--threads", str(threads), "--aov", "none", "--stats", stats_path, *extra]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()}")
    with open(stats_path) as f:
        stats = json.load(f)
    return peers.rgb(peers.read_exr(out_exr)), float(stats["seconds"])


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


BLOCK = 8


def block_means(image, block=BLOCK):
    """The image averaged over block x block tiles (rows and columns past the last whole
    tile dropped)."""
    h, w = image.shape[0] // block * block, image.shape[1] // block * block
    return image[:h, :w].reshape(h // block, block, w // block, block, -1).mean(axis=(1, 3))


def compare(o1, o2, m1, m2, blocks=True):
    """The statistics of the module doc, as a dict."""
    sigma_o, sigma_m = rmse(o1, o2) / math.sqrt(2.0), rmse(m1, m2) / math.sqrt(2.0)
    o, m = (o1 + o2) / 2.0, (m1 + m2) / 2.0
    pixels = o.shape[0] * o.shape[1]
    variance = ((o1 - o2) ** 2 + (m1 - m2) ** 2) / 4.0
    standard_error = np.sqrt(variance.reshape(-1, 3).sum(axis=0)) / pixels
    mean_o, mean_m = o.reshape(-1, 3).mean(axis=0), m.reshape(-1, 3).mean(axis=0)
    return dict(sigma_ours=sigma_o, sigma_mitsuba=sigma_m, rmse_between=rmse(o, m),
                rmse_noise_only=math.sqrt((sigma_o ** 2 + sigma_m ** 2) / 2.0),
                mean_ours=mean_o, mean_mitsuba=mean_m, standard_error=standard_error,
                z=(mean_o - mean_m) / standard_error,
                **({} if not blocks else {
                    f"block{BLOCK}_{key}": value for key, value in compare(
                        *(block_means(x) for x in (o1, o2, m1, m2)), blocks=False).items()
                    if key in ("sigma_ours", "sigma_mitsuba", "rmse_between",
                               "rmse_noise_only")}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--conetrace", required=True, help="release conetrace binary")
    parser.add_argument("--work", required=True, help="directory for intermediate EXRs")
    parser.add_argument("--results", default=os.path.join(peers.PEERS, "results"))
    parser.add_argument("--scene", default=SCENE_TOML)
    parser.add_argument("--spp", type=int, default=256, help="samples per pixel of each image")
    parser.add_argument("--seeds", default="1,2", help="the two seeds, comma separated")
    parser.add_argument("--variant", default="llvm_ad_rgb")
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    if len(seeds) != 2 or seeds[0] == seeds[1]:
        parser.error("--seeds takes two different seeds")
    work = os.path.join(args.work, "cornell")
    os.makedirs(work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)
    threads = os.cpu_count() or 1
    info = {"load_before": load_average(),
            "machine": f"{threads} logical CPUs ({peers.cpu_model()}), {peers.os_name()}"}
    log(f"load average before: {info['load_before']}")

    import mitsuba as mi
    import drjit as dr
    mi.set_log_level(mi.LogLevel.Error)
    mi.set_variant(args.variant)
    scene_dict = toml_scene.mitsuba_dict(mi, args.scene, "independent", args.spp)
    scene = mi.load_dict(scene_dict)
    info["mitsuba"] = (f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}, variant "
                       f"{args.variant}, {dr.thread_count()} threads, sampler independent, "
                       f"max_depth {scene_dict['integrator']['max_depth']}")
    log(info["mitsuba"])

    rows, ours, theirs = [], [], []
    for seed in seeds:
        exr = os.path.join(work, f"ours_{args.spp}spp_seed{seed}.exr")
        image, seconds = conetrace_render(args.conetrace, args.scene, exr, args.spp, seed,
                                          threads)
        ours.append(image)
        rows.append(dict(renderer="conetrace path", seed=seed, spp=args.spp, seconds=seconds,
                         mean=image.reshape(-1, 3).mean(axis=0)))
        log(f"conetrace seed {seed}: {seconds:.1f} s, mean {rows[-1]['mean']}")
        start = time.perf_counter()
        image = np.array(mi.render(scene, spp=args.spp, seed=seed), dtype=np.float64)[:, :, :3]
        seconds = time.perf_counter() - start
        theirs.append(image)
        mi.Bitmap(image.astype(np.float32)).write(
            os.path.join(work, f"mitsuba_{args.spp}spp_seed{seed}.exr"))
        rows.append(dict(renderer="Mitsuba path", seed=seed, spp=args.spp, seconds=seconds,
                         mean=image.reshape(-1, 3).mean(axis=0)))
        log(f"Mitsuba seed {seed}: {seconds:.1f} s (kernel compilation included), "
            f"mean {rows[-1]['mean']}")
    result = compare(ours[0], ours[1], theirs[0], theirs[1])
    for key, value in result.items():
        log(f"{key}: {value}")
    info["load_after"] = load_average()
    log(f"load average after: {info['load_after']}")
    write_results(args, rows, result, info)


def binary_name(binary):
    """The binary's path relative to the repository when it lies inside it."""
    path = os.path.abspath(binary)
    return os.path.relpath(path, REPO) if path.startswith(REPO + os.sep) else path


def write_results(args, rows, result, info):
    # results/cornell.* for the default scene, results/<scene file stem>.* for another one.
    name = ("cornell" if os.path.abspath(args.scene) == SCENE_TOML
            else os.path.splitext(os.path.basename(args.scene))[0])
    csv_path = os.path.join(args.results, f"{name}.csv")
    with open(csv_path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["renderer", "seed", "spp", "seconds", "mean_r", "mean_g", "mean_b"])
        for r in rows:
            writer.writerow([r["renderer"], r["seed"], r["spp"], f"{r['seconds']:.4g}",
                             *(f"{v:.6g}" for v in r["mean"])])
    r = result
    within = (r["rmse_between"] <= 1.1 * r["rmse_noise_only"]
              and r[f"block{BLOCK}_rmse_between"] <= 1.1 * r[f"block{BLOCK}_rmse_noise_only"]
              and np.all(np.abs(r["z"]) < 3.0))
    scene = os.path.relpath(args.scene, REPO)
    lines = ["# conetrace vs Mitsuba 3: the Cornell box, path traced", "",
             "Generated by `bash bench/peers/mitsuba/run.sh cornell` "
             "(bench/peers/mitsuba/cornell.py); set-up in bench/peers/README.md.", "",
             f"- Scene: `{scene}`, converted for Mitsuba by `toml_scene.py`.",
             f"- conetrace (`{binary_name(args.conetrace)}`): `render --integrator path --spp {args.spp} "
             "--seed S`, seconds = `--stats` render time; Mitsuba seconds = `mi.render` "
             "including its kernel compilation; "
             f"{info['mitsuba']}.",
             f"- Machine: {info['machine']}; load average `{info['load_before']}` before, "
             f"`{info['load_after']}` after.", "",
             "| renderer | seed | spp | seconds | mean R | mean G | mean B |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['renderer']} | {row['seed']} | {row['spp']} | "
                     f"{row['seconds']:.1f} | " + " | ".join(f"{v:.5f}" for v in row["mean"])
                     + " |")
    lines += ["", "| statistic | value |", "|---|---|",
              f"| noise of one conetrace image (RMSE between its seeds / sqrt 2) | "
              f"{r['sigma_ours']:.5f} |",
              f"| noise of one Mitsuba image | {r['sigma_mitsuba']:.5f} |",
              f"| RMSE between the seed-averaged images | {r['rmse_between']:.5f} |",
              f"| the same if only noise separated them | {r['rmse_noise_only']:.5f} |",
              f"| {BLOCK} x {BLOCK}-pixel block means: RMSE between the seed-averaged images | "
              f"{r[f'block{BLOCK}_rmse_between']:.5f} |",
              f"| {BLOCK} x {BLOCK}-pixel block means: the same if only noise separated them | "
              f"{r[f'block{BLOCK}_rmse_noise_only']:.5f} |",
              "| image mean, conetrace - Mitsuba (R, G, B) | "
              + ", ".join(f"{a - b:+.5f}" for a, b in zip(r["mean_ours"], r["mean_mitsuba"]))
              + " |",
              "| its standard error (R, G, B) | "
              + ", ".join(f"{v:.5f}" for v in r["standard_error"]) + " |",
              "| z = difference / standard error (R, G, B) | "
              + ", ".join(f"{v:+.2f}" for v in r["z"]) + " |",
              "", "Within the noise (both RMSEs at most 1.1 times their noise-only values and every "
              f"|z| < 3): **{'yes' if within else 'no'}**."]
    md_path = os.path.join(args.results, f"{name}.md")
    with open(md_path, "w") as f:
        f.write("\n".join(lines) + "\n")
    log(f"wrote {csv_path} and {md_path}")


if __name__ == "__main__":
    sys.exit(main())
