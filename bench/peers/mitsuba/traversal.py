#!/usr/bin/env python3
"""Traversal alone: Mitsuba 3's Embree and conetrace's, on the same scene and the same rays,
one thread each, in one run.

The rays are those of the path-tracing peer scene (bench/peers/scene/path_peer.toml): its
512 x 512 pixel-centre camera rays, and one cosine-distributed bounce ray from every camera
ray's hit (Mitsuba finds the hits and spawns the rays; a fixed seed). Both sets are written
to <work>/traversal/*.bin (little-endian f32 `ox oy oz dx dy dz` per ray) and traced by
Mitsuba (`ray_intersect_preliminary` for closest hits, `ray_test` for occlusion, each the
whole set in one kernel after an untimed compiling call) and by conetrace's
`examples/peer_traversal.rs` (the path tracer's incoherent streams of 256 rays). Fastest of
--passes runs; conetrace runs twice, in its robust (watertight) mode, as it renders, and
with `CONETRACE_NOT_ROBUST=1` (Embree's default triangle test, what Mitsuba builds with).
Called by run.sh (`bash bench/peers/mitsuba/run.sh traversal`); nothing asserts a time.
Writes <results>/traversal.md.
"""

import argparse
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import direct  # noqa: E402  (the displaced sphere mesh)
import run as peers  # noqa: E402  (machine facts)
import toml_scene  # noqa: E402

SCENE_TOML = os.path.join(peers.SCENE_DIR, "path_peer.toml")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--conetrace", required=True, help="release conetrace binary (unused)")
    parser.add_argument("--work", required=True)
    parser.add_argument("--example", required=True,
                        help="release build of examples/peer_traversal.rs")
    parser.add_argument("--passes", type=int, default=5)
    parser.add_argument("--results", default=os.path.join(peers.PEERS, "results"))
    parser.add_argument("--variant", default="llvm_ad_rgb")
    args = parser.parse_args()
    work = os.path.join(args.work, "traversal")
    os.makedirs(work, exist_ok=True)
    if not os.path.exists(direct.MESH_OBJ):
        direct.make_mesh(direct.MESH_OBJ)

    import mitsuba as mi
    import drjit as dr
    mi.set_log_level(mi.LogLevel.Error)
    mi.set_variant(args.variant)
    dr.set_thread_count(1)
    scene = mi.load_dict(toml_scene.mitsuba_dict(mi, SCENE_TOML))
    sensor = scene.sensors()[0]
    width, height = (int(v) for v in sensor.film().crop_size())
    x, y = np.meshgrid(np.arange(width), np.arange(height))
    position = mi.Point2f(((x.ravel() + 0.5) / width).astype(np.float32),
                          ((y.ravel() + 0.5) / height).astype(np.float32))
    camera, _ = sensor.sample_ray(0.0, 0.5, position, mi.Point2f(0.5, 0.5))
    si = scene.ray_intersect(camera)
    valid = np.array(si.is_valid())
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(7, width * height)
    local = mi.warp.square_to_cosine_hemisphere(sampler.next_2d())
    bounce = si.spawn_ray(si.to_world(local))

    def to_array(ray, keep):
        o, d = np.array(ray.o), np.array(ray.d)
        if o.shape[0] == 3:
            o, d = o.T, d.T
        return np.concatenate([o, d], axis=1)[keep].astype("<f4")

    sets = {"camera": to_array(camera, np.ones(width * height, bool)),
            "bounce": to_array(bounce, valid)}
    lines = []

    def log(line):
        print(line, flush=True)
        lines.append(line)

    log(f"Mitsuba {mi.__version__}, variant {args.variant}, {dr.thread_count()} thread; "
        f"{peers.cpu_model()}; load average before {open('/proc/loadavg').read().strip()}")
    for name, rays in sets.items():
        path = os.path.join(work, f"{name}.bin")
        rays.tofile(path)
        ray = mi.Ray3f(mi.Point3f(rays[:, 0], rays[:, 1], rays[:, 2]),
                       mi.Vector3f(rays[:, 3], rays[:, 4], rays[:, 5]))
        coherent = name == "camera"

        def closest():
            pi = scene.ray_intersect_preliminary(ray, coherent=coherent)
            dr.eval(pi.t)
            return pi

        def occluded():
            hit = scene.ray_test(ray, coherent=coherent)
            dr.eval(hit)

        closest()
        occluded()
        best_closest = best_occluded = float("inf")
        for _ in range(args.passes):
            start = time.perf_counter()
            pi = closest()
            best_closest = min(best_closest, time.perf_counter() - start)
            start = time.perf_counter()
            occluded()
            best_occluded = min(best_occluded, time.perf_counter() - start)
        hits = int(np.count_nonzero(np.isfinite(np.array(pi.t))))
        n = len(rays)
        log(f"{name}: {n} rays, {hits} hits")
        log(f"  Mitsuba:   closest hit {best_closest:.4f} s ({n / best_closest / 1e6:.2f} "
              f"Mrays/s), occlusion {best_occluded:.4f} s ({n / best_occluded / 1e6:.2f} "
              f"Mrays/s)")
        for robust in (True, False):
            env = dict(os.environ)
            env.pop("CONETRACE_NOT_ROBUST", None)
            if not robust:
                env["CONETRACE_NOT_ROBUST"] = "1"
            out = subprocess.run([args.example, SCENE_TOML, path, str(args.passes)],
                                 capture_output=True, text=True, check=True, env=env)
            log(f"  conetrace: {out.stdout.strip()}")
    log(f"load average after {open('/proc/loadavg').read().strip()}")
    os.makedirs(args.results, exist_ok=True)
    with open(os.path.join(args.results, "traversal.md"), "w") as f:
        f.write("# Traversal alone: conetrace's Embree against Mitsuba 3's, same rays\n\n"
                "Generated by `bash bench/peers/mitsuba/run.sh traversal` "
                "(bench/peers/mitsuba/traversal.py, examples/peer_traversal.rs).\n\n```\n")
        f.write("\n".join(lines) + "\n```\n")


if __name__ == "__main__":
    main()
