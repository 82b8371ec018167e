#!/usr/bin/python3
"""OpenImageIO TextureSystem lookups for the cross-check test (run with /usr/bin/python3).

usage: oiio_lookup.py TEXTURE QUERIES.csv OUTDIR --filters closest,bilinear --wraps periodic,clamp
                      [--max-aniso 16]
Writes OUTDIR/<filter>_<wrap>.csv with header r,g,b,a, one row per query (repr of each float).
Filter -> OIIO options (interpolation is always InterpMode.Bilinear except 'closest'):
  closest   -> MipMode.NoMIP,     InterpMode.Closest   (nearest texel of level 0)
  bilinear  -> MipMode.NoMIP,     InterpMode.Bilinear  (level 0 only)
  trilinear -> MipMode.Trilinear, InterpMode.Bilinear
  aniso     -> MipMode.Aniso,     InterpMode.Bilinear
conservative_filter = True, anisotropic = max aniso, a new TextureOpt per lookup.
"""
import argparse
import csv
import os
import sys

try:
    import OpenImageIO as oiio
except ImportError:
    sys.exit("OpenImageIO Python module missing: run `bash scripts/setup.sh`")

WRAPS = {
    "periodic": oiio.Wrap.Periodic,
    "clamp": oiio.Wrap.Clamp,
    "black": oiio.Wrap.Black,
    "mirror": oiio.Wrap.Mirror,
}
FILTERS = {
    "closest": (oiio.MipMode.NoMIP, oiio.InterpMode.Closest),
    "bilinear": (oiio.MipMode.NoMIP, oiio.InterpMode.Bilinear),
    "trilinear": (oiio.MipMode.Trilinear, oiio.InterpMode.Bilinear),
    "aniso": (oiio.MipMode.Aniso, oiio.InterpMode.Bilinear),
}


def make_options(filt, wrap, max_aniso):
    opt = oiio.TextureOpt()
    opt.mipmode, opt.interpmode = FILTERS[filt]
    opt.swrap = opt.twrap = WRAPS[wrap]
    opt.anisotropic = int(max_aniso)
    opt.conservative_filter = True
    return opt


def read_queries(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    if rows[0] != ["s", "t", "dsdx", "dtdx", "dsdy", "dtdy"]:
        sys.exit(f"{path}: bad header {rows[0]}")
    return [tuple(float(v) for v in r) for r in rows[1:] if r]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("texture")
    ap.add_argument("queries")
    ap.add_argument("outdir")
    ap.add_argument("--filters", default="closest,bilinear,trilinear,aniso")
    ap.add_argument("--wraps", default="periodic,clamp,black,mirror")
    ap.add_argument("--max-aniso", type=float, default=16)
    ap.add_argument("--channels", type=int, default=4)
    a = ap.parse_args()
    queries = read_queries(a.queries)
    ts = oiio.TextureSystem(shared=False)
    os.makedirs(a.outdir, exist_ok=True)
    for filt in a.filters.split(","):
        for wrap in a.wraps.split(","):
            lines = ["r,g,b,a"]
            for (s, t, dsdx, dtdx, dsdy, dtdy) in queries:
                opt = make_options(filt, wrap, a.max_aniso)
                v = ts.texture(a.texture, opt, s, t, dsdx, dtdx, dsdy, dtdy, a.channels)
                v = list(v) + [1.0] * (4 - len(v))
                lines.append(",".join(repr(float(x)) for x in v))
            err = ts.geterror()
            if err:
                sys.exit(f"{a.texture}: OIIO error: {err}")
            with open(os.path.join(a.outdir, f"{filt}_{wrap}.csv"), "w") as f:
                f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
