#!/usr/bin/python3
"""PSNR between a render's texture lookups and OpenImageIO's, pixel by pixel.

usage: fullframe.py FRAME.exr TEXTURE [--filter aniso] [--wrap periodic] [--max-aniso 16]
                    [--maketx] [--lookups LOOKUPS.csv]

FRAME.exr holds per pixel the lookup the renderer made (channels tex.s, tex.t,
tex.dsdx, tex.dtdx, tex.dsdy, tex.dtdy) and its result (texcolor.R, texcolor.G,
texcolor.B); texcolor.A is 1 where a lookup happened and 0 elsewhere (frames without
texcolor.A mark missing lookups with NaN). Every pixel with a lookup
is looked up with TextureSystem.texture() using the options of oiio_lookup.py, and
the PSNR (peak 1) between OIIO's RGB and texcolor is printed, with the pixel count
and the max abs difference. TEXTURE should be a maketx output; with --maketx the
script runs `maketx --filter box` on it first (into a temporary file).

With --lookups, the lookups come from LOOKUPS.csv instead of the frame's tex.* channels:
header x,y,s,t,dsdx,dtdx,dsdy,dtdy, one row per pixel to compare (the caller computes them
independently of the renderer). Each such pixel must have a lookup in the frame
(texcolor.A > 0), else the script exits 2 naming the first one.
Run with /usr/bin/python3 (Debian's python3-openimageio); exit 2 on bad input.
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

try:
    import OpenImageIO as oiio
    import numpy as np
except ImportError:
    sys.stderr.write("OpenImageIO Python module missing: run `bash scripts/setup.sh`\n")
    sys.exit(2)

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from oiio_lookup import FILTERS, WRAPS, make_options  # noqa: E402

LOOKUP = ["tex.s", "tex.t", "tex.dsdx", "tex.dtdx", "tex.dsdy", "tex.dtdy"]
COLOR = ["texcolor.R", "texcolor.G", "texcolor.B"]


def read_channels(path, names):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        sys.stderr.write(f"{path}: {buf.geterror()}\n")
        sys.exit(2)
    spec = buf.spec()
    px = np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(spec.height, spec.width, spec.nchannels)
    out = []
    for n in names:
        if n not in spec.channelnames:
            sys.stderr.write(f"{path}: missing channel {n} (has {', '.join(spec.channelnames)})\n")
            sys.exit(2)
        out.append(px[:, :, spec.channelnames.index(n)])
    return np.stack(out, axis=-1)


def lookups_from_csv(path, frame, shape):
    """(mask of listed pixels, per-pixel s t dsdx dtdx dsdy dtdy) from the caller's CSV."""
    height, width = shape
    lookup = np.zeros((height, width, 6), dtype=np.float64)
    valid = np.zeros((height, width), dtype=bool)
    has_lookup = read_channels(frame, ["texcolor.A"])[:, :, 0] > 0
    with open(path) as f:
        header = f.readline().strip()
        if header != "x,y,s,t,dsdx,dtdx,dsdy,dtdy":
            sys.stderr.write(f"{path}: bad header {header!r}\n")
            sys.exit(2)
        for n, line in enumerate(f, start=2):
            if not line.strip():
                continue
            fields = line.split(",")
            x, y = int(fields[0]), int(fields[1])
            if not (0 <= x < width and 0 <= y < height):
                sys.stderr.write(f"{path}:{n}: pixel ({x}, {y}) outside the frame\n")
                sys.exit(2)
            if not has_lookup[y, x]:
                sys.stderr.write(f"{path}:{n}: the frame has no texture lookup at ({x}, {y})\n")
                sys.exit(2)
            lookup[y, x] = [float(v) for v in fields[2:8]]
            valid[y, x] = True
    return valid, lookup


def psnr(mse):
    return float("inf") if mse == 0 else 10.0 * math.log10(1.0 / mse)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("frame")
    ap.add_argument("texture")
    ap.add_argument("--filter", default="aniso", choices=sorted(FILTERS))
    ap.add_argument("--wrap", default="periodic", choices=sorted(WRAPS))
    ap.add_argument("--max-aniso", type=float, default=16)
    ap.add_argument("--maketx", action="store_true")
    ap.add_argument("--lookups")
    a = ap.parse_args()

    texture = a.texture
    tmp = None
    if a.maketx:
        tmp = tempfile.TemporaryDirectory()
        texture = os.path.join(tmp.name, "tex.tx")
        r = subprocess.run(["maketx", a.texture, "-o", texture, "--filter", "box"],
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.stderr.write(f"{a.texture}: maketx failed: {r.stderr.strip()}\n")
            sys.exit(2)

    ours = read_channels(a.frame, COLOR)
    if a.lookups:
        valid, lookup = lookups_from_csv(a.lookups, a.frame, ours.shape[:2])
    else:
        lookup = read_channels(a.frame, LOOKUP)
        valid = np.all(np.isfinite(lookup), axis=-1)
        if "texcolor.A" in oiio.ImageBuf(a.frame).spec().channelnames:
            valid &= read_channels(a.frame, ["texcolor.A"])[:, :, 0] > 0
    ts = oiio.TextureSystem(shared=False)
    theirs = np.zeros_like(ours)
    ys, xs = np.nonzero(valid)
    for y, x in zip(ys, xs):
        s, t, dsdx, dtdx, dsdy, dtdy = (float(v) for v in lookup[y, x])
        opt = make_options(a.filter, a.wrap, a.max_aniso)
        theirs[y, x] = ts.texture(texture, opt, s, t, dsdx, dtdx, dsdy, dtdy, 3)
    err = ts.geterror()
    if err:
        sys.stderr.write(f"{texture}: OIIO error: {err}\n")
        sys.exit(2)
    n = int(valid.sum())
    if n == 0:
        print("pixels 0 psnr inf max_abs_diff 0")
        return
    diff = (ours[valid] - theirs[valid]).astype(np.float64)
    mse = float(np.mean(diff * diff))
    print(f"pixels {n} psnr {psnr(mse):.2f} max_abs_diff {float(np.max(np.abs(diff))):.3e}")


if __name__ == "__main__":
    main()
