#!/usr/bin/env python3
"""Where the 16-spp sampler gap of `run.sh sampler` comes from, simulated: the error of
16-point sets on the peer plane's pixel integrand, per band of image rows.

The peer plane (bench/peers/README.md) at 1280 x 720 is re-traced here in numpy: a pixel
position (x + a, y + b) becomes a camera ray, its hit on the plane y = 0 a texture position
(u = x, v = -z, t = 1 - v as conetrace reads OBJ files), and the colour the bilinear lookup
of the full-resolution texture (texel centres at (i + 0.5) / 128, periodic), the albedo both
renderers average with `--lod mip0 --filter bilinear` / the albedo AOV. For pixels drawn at
random from the given rows, each point set's mean squared error against a 4096-sample
stratified reference is averaged over independent randomisations:

- owen-sobol: the first 16 points of Sobol's first two dimensions, Owen-scrambled with
  independent random bits per tree node (the ideal scramble conetrace's hashed one stands
  for, src/sampler/);
- cmj: Kensler's correlated multi-jittered 4 x 4 pattern ("Correlated Multi-Jittered
  Sampling", 2013), random row and column permutations and jitter, the pattern of Mitsuba's
  `multijitter` sampler at 16 samples;
- random: 16 independent uniform points, for scale.

Usage: <venv>/bin/python bench/peers/mitsuba/sampler_band.py --rows 0:80 --pixels 80
(`run.sh` makes the virtual environment; numpy and OpenImageIO are all this needs).
"""

import argparse
import os

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
TEXTURE = os.path.join(os.path.dirname(HERE), "scene", "tiles.png")
WIDTH, HEIGHT = 1280, 720
EYE, TARGET, UP, VFOV = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -2.25]), \
    np.array([0.0, 1.0, 0.0]), 40.0


def load_texture():
    """The texture as linear RGB (sRGB decoded)."""
    pixels = np.asarray(oiio.ImageBuf(TEXTURE).get_pixels(oiio.FLOAT))[:, :, :3]
    return np.where(pixels <= 0.04045, pixels / 12.92, ((pixels + 0.055) / 1.055) ** 2.4)


class Plane:
    def __init__(self):
        self.texture = load_texture()
        forward = (TARGET - EYE) / np.linalg.norm(TARGET - EYE)
        right = np.cross(forward, UP)
        right /= np.linalg.norm(right)
        self.forward, self.right, self.up = forward, right, np.cross(right, forward)
        self.tan_y = np.tan(np.radians(VFOV) / 2.0)
        self.tan_x = self.tan_y * WIDTH / HEIGHT

    def colour(self, x, y):
        """Bilinear texture colour seen through image positions (x right, y down)."""
        sx = (2.0 * x / WIDTH - 1.0) * self.tan_x
        sy = (1.0 - 2.0 * y / HEIGHT) * self.tan_y
        d = self.forward[None] + np.outer(sx, self.right) + np.outer(sy, self.up)
        t = -EYE[1] / d[:, 1]
        s_coord = EYE[0] + t * d[:, 0]
        t_coord = 1.0 + (EYE[2] + t * d[:, 2])  # t = 1 - v, v = -z
        n = self.texture.shape[0]
        fx, fy = s_coord * n - 0.5, t_coord * n - 0.5
        x0, y0 = np.floor(fx), np.floor(fy)
        ax, ay = (fx - x0)[:, None], (fy - y0)[:, None]
        x0, y0 = x0.astype(int) % n, y0.astype(int) % n
        x1, y1 = (x0 + 1) % n, (y0 + 1) % n
        tex = self.texture
        return ((1 - ax) * (1 - ay) * tex[y0, x0] + ax * (1 - ay) * tex[y0, x1]
                + (1 - ax) * ay * tex[y1, x0] + ax * ay * tex[y1, x1])


def sobol_16():
    """The first 16 points of Sobol's dimensions 0 (van der Corput) and 1 (direction
    numbers m = 1, 3, 5, 15), as 4-bit fractions."""
    x, y = [], []
    for k in range(16):
        x.append(int(format(k, "04b")[::-1], 2))
        acc = 0
        for j, m in enumerate((1, 3, 5, 15)):
            if (k >> j) & 1:
                acc ^= m << (3 - j)
        y.append(acc)
    return np.array(x) / 16.0, np.array(y) / 16.0


def owen_scramble(values, rng, bits=24):
    """Owen's nested uniform scramble with independent random flips per tree node."""
    q = (values * (1 << bits)).astype(np.int64)
    out = np.zeros_like(q)
    flips = {}
    for b in range(bits - 1, -1, -1):
        prefix = q >> (b + 1)
        flip = np.array([flips.setdefault((b, int(p)), int(rng.integers(2))) for p in prefix])
        out |= (((q >> b) & 1) ^ flip) << b
    return (out + rng.random(len(values))) / (1 << bits)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", default="0:80", help="first:end image rows to draw from")
    parser.add_argument("--pixels", type=int, default=80)
    parser.add_argument("--replicas", type=int, default=32, help="randomisations per pixel")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    first, end = (int(v) for v in args.rows.split(":"))
    rng = np.random.default_rng(args.seed)
    plane = Plane()
    sx, sy = sobol_16()
    # The net property the comparison rests on: one point in every 4 x 4 cell.
    assert len(set(zip((sx * 4).astype(int), (sy * 4).astype(int)))) == 16

    def cmj():
        s = np.arange(16)
        col, row = rng.permutation(4)[s % 4], rng.permutation(4)[s // 4]
        return ((s % 4 + (row + rng.random(16)) / 4) / 4,
                (s // 4 + (col + rng.random(16)) / 4) / 4)

    point_sets = {
        "owen-sobol": lambda: (owen_scramble(sx, rng), owen_scramble(sy, rng)),
        "cmj": cmj,
        "random": lambda: (rng.random(16), rng.random(16)),
    }
    errors = {name: [] for name in point_sets}
    for _ in range(args.pixels):
        px, py = int(rng.integers(0, WIDTH)), int(rng.integers(first, end))
        a = (np.arange(4096) % 64 + rng.random(4096)) / 64
        b = (np.arange(4096) // 64 + rng.random(4096)) / 64
        reference = plane.colour(px + a, py + b).mean(0)
        for name, draw in point_sets.items():
            total = 0.0
            for _ in range(args.replicas):
                x, y = draw()
                total += float(((plane.colour(px + x, py + y).mean(0) - reference) ** 2).mean())
            errors[name].append(total / args.replicas)
    print(f"rows {first}..{end}, {args.pixels} pixels, {args.replicas} randomisations each")
    for name, values in errors.items():
        print(f"{name}: RMSE {np.sqrt(np.mean(values)):.5f}")
    print(f"owen-sobol / cmj: {np.sqrt(np.mean(errors['owen-sobol']) / np.mean(errors['cmj'])):.3f}")


if __name__ == "__main__":
    main()
