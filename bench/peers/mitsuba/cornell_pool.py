#!/usr/bin/env python3
"""Pools the Cornell-box images of several `run.sh cornell` runs (cornell.py keeps every
image in <work>/cornell/: ours_<spp>spp_seed<S>.exr, mitsuba_<spp>spp_seed<S>.exr) and
compares the two renderers' image means per channel across seeds: each image's mean is one
independent estimate, so the spread of those means over the seeds gives the standard error
directly (Welch's t), whatever the tails of the per-pixel noise (a caustic's rare bright
paths make per-pixel variance estimates from two images unreliable; the mean of a whole
image is an average over many pixels and much closer to normal).

    venv/bin/python bench/peers/mitsuba/cornell_pool.py --work ~/.cache/conetrace-peers/work \\
        --spp 256 --seeds 5,6,7,8

Prints one line per channel; writes nothing. Not part of the test suite.
"""

import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run as peers  # noqa: E402  (EXR reading)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--work", required=True, help="cornell.py's --work directory")
    parser.add_argument("--spp", type=int, required=True)
    parser.add_argument("--seeds", required=True, help="comma-separated seeds, at least 2")
    args = parser.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    if len(seeds) < 2:
        parser.error("at least two seeds")
    means = {}
    for renderer in ("ours", "mitsuba"):
        rows = []
        for seed in seeds:
            path = os.path.join(args.work, "cornell", f"{renderer}_{args.spp}spp_seed{seed}.exr")
            if not os.path.exists(path):
                sys.exit(f"{path}: missing (run `run.sh cornell --spp {args.spp} --seeds ...` "
                         "for this seed first)")
            rows.append(peers.rgb(peers.read_exr(path)).reshape(-1, 3).mean(axis=0))
        means[renderer] = np.array(rows)
    n = len(seeds)
    for channel, name in enumerate("RGB"):
        o, m = means["ours"][:, channel], means["mitsuba"][:, channel]
        difference = o.mean() - m.mean()
        standard_error = math.sqrt(o.var(ddof=1) / n + m.var(ddof=1) / n)
        print(f"{name}: conetrace {o.mean():.6f} (seed spread {o.std(ddof=1):.6f}), Mitsuba "
              f"{m.mean():.6f} (seed spread {m.std(ddof=1):.6f}), difference "
              f"{difference:+.6f} = {100 * difference / m.mean():+.3f} %, standard error "
              f"{standard_error:.6f}, t = {difference / standard_error:+.2f} ({n} seeds each)")


if __name__ == "__main__":
    sys.exit(main())
