#!/usr/bin/python3
"""Time OpenImageIO TextureSystem.texture() per filter, single thread (for bench-textures).

usage: oiio_texture_bench.py TEXTURE.tx QUERIES.csv --filters trilinear,aniso [--max-aniso 16]
                             [--cache-mb 256]
Sets the ImageCache's max_memory_MB to --cache-mb (the cap of the cached side) and prints
"cache_mb <MB>" (the value OIIO reports back), "empty <ns>" (the same loop calling an empty Python function with the same
arguments), "binding <ns>" (texture() on a 1x1 texture with NoMIP/Closest: the
pybind11 call and argument conversion plus a trivial lookup, an upper bound of the
binding overhead) and "<filter> <ns>" (nanoseconds per lookup, overhead included).
Options as in tests/oiio/oiio_lookup.py: InterpMode.Bilinear (Closest for 'closest'),
MipMode NoMIP / NoMIP / Trilinear / Aniso, conservative_filter, periodic wrap.
"""
import argparse
import csv
import sys
import tempfile
import time

try:
    import OpenImageIO as oiio
except ImportError:
    sys.exit("OpenImageIO Python module missing: run `bash scripts/setup.sh`")

MODES = {
    "closest": (oiio.MipMode.NoMIP, oiio.InterpMode.Closest),
    "bilinear": (oiio.MipMode.NoMIP, oiio.InterpMode.Bilinear),
    "trilinear": (oiio.MipMode.Trilinear, oiio.InterpMode.Bilinear),
    "aniso": (oiio.MipMode.Aniso, oiio.InterpMode.Bilinear),
}


def empty(name, opt, s, t, a, b, c, d, n):
    pass


def timed(fn, name, opt, queries, reps):
    best = float("inf")
    for _ in range(reps):
        start = time.perf_counter()
        for (s, t, a, b, c, d) in queries:
            fn(name, opt, s, t, a, b, c, d, 4)
        best = min(best, time.perf_counter() - start)
    return best / len(queries) * 1e9


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("texture")
    ap.add_argument("queries")
    ap.add_argument("--filters", default="trilinear,aniso")
    ap.add_argument("--max-aniso", type=float, default=16)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--cache-mb", type=float, default=256.0)
    a = ap.parse_args()
    with open(a.queries) as f:
        rows = list(csv.reader(f))[1:]
    queries = [tuple(float(v) for v in r) for r in rows if r]
    ts = oiio.TextureSystem(shared=False)
    ts.attribute("max_memory_MB", a.cache_mb)
    print(f"cache_mb {ts.getattribute('max_memory_MB', oiio.FLOAT)}")
    opt = oiio.TextureOpt()
    print(f"empty {timed(empty, a.texture, opt, queries, a.reps):.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        src, tiny = f"{tmp}/one.exr", f"{tmp}/one.tx"
        buf = oiio.ImageBuf(oiio.ImageSpec(1, 1, 4, oiio.FLOAT))
        buf.write(src)
        cfg = oiio.ImageSpec()
        cfg.attribute("maketx:filtername", "box")
        oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, src, tiny, cfg)
        opt = oiio.TextureOpt()
        opt.mipmode, opt.interpmode = MODES["closest"]
        ts.texture(tiny, opt, 0.5, 0.5, 0, 0, 0, 0, 4)
        print(f"binding {timed(ts.texture, tiny, opt, queries, a.reps):.1f}")
    for filt in a.filters.split(","):
        opt = oiio.TextureOpt()
        opt.mipmode, opt.interpmode = MODES[filt]
        opt.swrap = opt.twrap = oiio.Wrap.Periodic
        opt.anisotropic = int(a.max_aniso)
        opt.conservative_filter = True
        ts.texture(a.texture, opt, 0.5, 0.5, 0, 0, 0, 0, 4)  # open the file outside the timing
        print(f"{filt} {timed(ts.texture, a.texture, opt, queries, a.reps):.1f}")


if __name__ == "__main__":
    main()
