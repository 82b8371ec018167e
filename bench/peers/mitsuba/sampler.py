#!/usr/bin/env python3
"""Sample placement alone: conetrace's sampler against Mitsuba 3's at equal sample counts, on
the peer plane (bench/peers/README.md), in one run.

Both renderers do the same work per sample (a camera ray, one bilinear lookup of the full-
resolution texture, a box pixel filter), so at equal N the error against the ground truth
differs only by where the samples fall in each pixel. conetrace: `--lod mip0 --filter
bilinear --spp N --seed 0` (Owen-scrambled Sobol, src/sampler/). Mitsuba: the `aov`
integrator's albedo with the `multijitter` sampler (and `independent` for scale), seed 0.

Ground truth: conetrace `--lod mip0 --filter bilinear` at --gt-spp samples with --gt-seed.
Its seed differs from the compared renders' (0), so its samples are not the compared
renders' samples: conetrace's sample i of a pixel is the same at every sample count.

Called by run.sh (`bash bench/peers/mitsuba/run.sh sampler [options]`). Not part of the
test suite. Writes <results>/sampler_<W>x<H>.{csv,md}.
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run as peers  # noqa: E402  (the shared scene, EXR reading, metrics and machine facts)


def conetrace_render(binary, out_exr, spp, seed, threads):
    """One mip0+bilinear render at `spp` with `seed`; returns (image, seconds from --stats)."""
    stats = out_exr + ".json"
    command = ([binary, "render", peers.SCENE_TOML, "-o", out_exr]
               + peers.conetrace_arguments(spp, "mip0", "bilinear", threads)
               + ["--seed", str(seed), "--stats", stats])
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {done.stderr.strip()}")
    with open(stats) as f:
        seconds = float(json.load(f)["seconds"])
    return peers.rgb(peers.read_exr(out_exr)), seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--conetrace", required=True, help="conetrace binary")
    parser.add_argument("--work", required=True, help="directory for intermediate EXRs")
    parser.add_argument("--results", default=os.path.join(peers.PEERS, "results"))
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--spp", default="4,16,64", help="comma-separated sample counts")
    parser.add_argument("--gt-spp", type=int, default=1024)
    parser.add_argument("--gt-seed", type=int, default=1_000_003)
    parser.add_argument("--reuse-ground-truth", action="store_true",
                        help="keep the work directory's ground truth if its --stats match")
    parser.add_argument("--variant", default="llvm_ad_rgb")
    args = parser.parse_args()
    peers.WIDTH, peers.HEIGHT = args.width, args.height
    peers.FAR_ROWS = args.height // 3
    counts = [int(n) for n in args.spp.split(",")]
    work = os.path.join(args.work, f"sampler_{args.width}x{args.height}")
    os.makedirs(work, exist_ok=True)
    os.makedirs(args.results, exist_ok=True)
    threads = os.cpu_count() or 1
    with open("/proc/loadavg") as f:
        load_start = " ".join(f.read().split()[:3])

    # Ground truth.
    gt_exr = os.path.join(work, f"ground_truth_{args.gt_spp}spp_seed{args.gt_seed}.exr")
    if args.reuse_ground_truth and os.path.exists(gt_exr):
        truth = peers.rgb(peers.read_exr(gt_exr))
        with open(gt_exr + ".json") as f:
            gt_seconds = float(json.load(f)["seconds"])
        gt_note = f"{gt_seconds:.1f} s render, reused from an earlier run of the same command"
    else:
        start = time.perf_counter()
        truth, gt_seconds = conetrace_render(args.conetrace, gt_exr, args.gt_spp, args.gt_seed,
                                             threads)
        gt_note = f"{gt_seconds:.1f} s render, {time.perf_counter() - start:.1f} s wall"
    mask = np.ones(truth.shape[:2], bool)
    peers.log(f"ground truth: {args.gt_spp} spp, seed {args.gt_seed} ({gt_note})")

    import mitsuba as mi
    import drjit as dr

    mi.set_log_level(mi.LogLevel.Error)
    variant = args.variant
    try:
        mi.set_variant(variant)
        mi.render(mi.load_dict(peers.mitsuba_scene(mi, "independent", 1)), spp=1)
    except Exception as error:  # noqa: BLE001 - any LLVM failure means: fall back
        peers.log(f"variant {variant} failed ({error}); falling back to scalar_rgb")
        variant = "scalar_rgb"
        mi.set_variant(variant)
    mitsuba_info = f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}, variant {variant}"

    rows = []
    for spp in counts:
        image, seconds = conetrace_render(args.conetrace, os.path.join(work, f"ours_{spp}.exr"),
                                          spp, 0, threads)
        rows.append(dict(renderer="conetrace", sampler="owen-sobol", spp=spp, seconds=seconds,
                         row_mse=((image - truth) ** 2).mean(axis=(1, 2)),
                         **peers.errors(image, truth, mask)))
        peers.log(f"conetrace {spp} spp: RMSE {rows[-1]['rmse_all']:.5f}")
        for sampler in ("multijitter", "independent"):
            scene = mi.load_dict(peers.mitsuba_scene(mi, sampler, spp))
            start = time.perf_counter()
            image = np.array(mi.render(scene, spp=spp, seed=0), dtype=np.float64)[:, :, :3]
            seconds = time.perf_counter() - start
            rendered = scene.sensors()[0].sampler().sample_count()
            rows.append(dict(renderer="mitsuba", sampler=sampler, spp=rendered, seconds=seconds,
                             row_mse=((image - truth) ** 2).mean(axis=(1, 2)),
                             **peers.errors(image, truth, mask)))
            peers.log(f"mitsuba {sampler} {rendered} spp: RMSE {rows[-1]['rmse_all']:.5f}")
    with open("/proc/loadavg") as f:
        load_end = " ".join(f.read().split()[:3])

    stem = os.path.join(args.results, f"sampler_{args.width}x{args.height}")
    fields = ["renderer", "sampler", "spp", "seconds", "rmse_all", "psnr_all", "rmse_far",
              "psnr_far"]
    with open(stem + ".csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v)
                             for k, v in row.items()})

    def find(renderer, sampler, spp):
        return next(r for r in rows if r["renderer"] == renderer and r["sampler"] == sampler
                    and r["spp"] == spp)

    lines = [
        f"# Sampler: conetrace against Mitsuba 3 at equal sample counts ({args.width} x "
        f"{args.height})", "",
        "Generated by `bash bench/peers/mitsuba/run.sh sampler` "
        "(bench/peers/mitsuba/sampler.py); the scene is bench/peers/README.md's.", "",
        f"- Machine: {threads} logical CPUs ({peers.cpu_model()}), {peers.os_name()}; load "
        f"average {load_start} at the start, {load_end} at the end (/proc/loadavg).",
        f"- {mitsuba_info}.",
        f"- Ground truth: conetrace `--lod mip0 --filter bilinear --spp {args.gt_spp} --seed "
        f"{args.gt_seed}` ({gt_note}).",
        "- conetrace: `--lod mip0 --filter bilinear --spp N --seed 0`; Mitsuba: `aov` "
        "integrator (albedo), box filter, `mi.render(scene, spp=N, seed=0)`. Same work per "
        "sample in both; seconds are one run each on a shared machine, for scale only.",
        f"- RMSE over RGB of all pixels, linear units; far = the top {peers.FAR_ROWS} rows.", "",
        "| spp | conetrace RMSE | Mitsuba multijitter RMSE | ratio | conetrace far | "
        "Mitsuba multijitter far | Mitsuba independent RMSE |",
        "|---|---|---|---|---|---|---|",
    ]
    for spp in counts:
        ours = find("conetrace", "owen-sobol", spp)
        theirs = next(r for r in rows if r["renderer"] == "mitsuba"
                      and r["sampler"] == "multijitter" and r["spp"] >= spp)
        independent = next(r for r in rows if r["renderer"] == "mitsuba"
                           and r["sampler"] == "independent" and r["spp"] >= spp)
        count = f"{spp}" if theirs["spp"] == spp else f"{spp} (Mitsuba {theirs['spp']})"
        lines.append(
            f"| {count} | {ours['rmse_all']:.5f} | {theirs['rmse_all']:.5f} | "
            f"{ours['rmse_all'] / theirs['rmse_all']:.3f} | {ours['rmse_far']:.5f} | "
            f"{theirs['rmse_far']:.5f} | {independent['rmse_all']:.5f} |")
    lines += ["", "ratio = conetrace RMSE / Mitsuba multijitter RMSE (<= 1: ours is at most "
              "Mitsuba's).", ""]
    # Where the difference lies: the same ratio over bands of image rows (top = grazing,
    # where a pixel covers many texels along the view; bottom = near, a few texels).
    bands = [(0, 20), (20, 40), (40, 80), (80, 160), (160, 320), (320, args.height)]
    bands = [(a, min(b, args.height)) for a, b in bands if a < args.height]
    lines += ["RMSE ratio conetrace / Mitsuba multijitter by band of image rows (and the "
              "band's conetrace RMSE):", "",
              "| spp | " + " | ".join(f"rows {a}-{b - 1}" for a, b in bands) + " |",
              "|---|" + "---|" * len(bands)]
    for spp in counts:
        ours = find("conetrace", "owen-sobol", spp)
        theirs = next(r for r in rows if r["renderer"] == "mitsuba"
                      and r["sampler"] == "multijitter" and r["spp"] >= spp)
        cells = []
        for a, b in bands:
            o, t = ours["row_mse"][a:b].mean(), theirs["row_mse"][a:b].mean()
            cells.append(f"{np.sqrt(o / t):.3f} ({np.sqrt(o):.5f})")
        lines.append(f"| {spp} | " + " | ".join(cells) + " |")
    lines += ["", "## All runs", "",
              "| renderer | sampler | spp | seconds | RMSE | PSNR dB | far RMSE |",
              "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['renderer']} | {r['sampler']} | {r['spp']} | {r['seconds']:.3f} | "
                     f"{r['rmse_all']:.5f} | {r['psnr_all']:.2f} | {r['rmse_far']:.5f} |")
    with open(stem + ".md", "w") as f:
        f.write("\n".join(lines) + "\n")
    peers.log(f"wrote {stem}.csv and {stem}.md")


if __name__ == "__main__":
    sys.exit(main())
