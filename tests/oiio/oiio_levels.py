#!/usr/bin/python3
"""Dump every MIP level of a texture file as little-endian float32 RGBA.

usage: oiio_levels.py TEXTURE.tx OUT.bin
Format: u32 level count, then per level u32 width, u32 height, width*height*4 f32
(missing channels: colour copies channel 0, alpha = 1). Run with /usr/bin/python3.
"""
import struct
import sys

try:
    import OpenImageIO as oiio
    import numpy as np
except ImportError:
    sys.exit("OpenImageIO Python module missing: run `bash scripts/setup.sh`")


def main():
    path, out = sys.argv[1], sys.argv[2]
    first = oiio.ImageBuf(path)
    if first.has_error:
        sys.exit(f"{path}: {first.geterror()}")
    levels = []
    for m in range(first.nmiplevels):
        buf = oiio.ImageBuf(path, 0, m)
        spec = buf.spec()
        px = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)
        px = px.reshape(spec.height, spec.width, spec.nchannels)
        rgba = np.ones((spec.height, spec.width, 4), dtype=np.float32)
        for c in range(3):
            rgba[:, :, c] = px[:, :, min(c, spec.nchannels - 1)]
        if spec.nchannels >= 4:
            rgba[:, :, 3] = px[:, :, 3]
        levels.append((spec.width, spec.height, rgba))
    with open(out, "wb") as f:
        f.write(struct.pack("<I", len(levels)))
        for w, h, rgba in levels:
            f.write(struct.pack("<II", w, h))
            f.write(rgba.astype("<f4").tobytes())


if __name__ == "__main__":
    main()
