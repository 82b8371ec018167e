#!/usr/bin/env python3
"""Writes the assets of the peer-comparison scene (Python standard library only).

- tiles.png: 128 x 128 sRGB texture, 4 x 4-texel squares; each square gets its own colour
  from a fixed linear congruential generator, bright and dark squares alternate like a
  checker. Every square differs from its mirror images, so a flipped or shifted texture
  lookup in either renderer shows up as a large error, and the 4-texel period aliases badly
  when the plane recedes.
- plane.obj: one 100 x 100 quad in the xz plane facing +y, texture coordinates spanning
  [-50, 50] (one texture repeat per world unit, OBJ v up). Both renderers read this same
  file, so neither needs a texture transform.

Deterministic: running it again rewrites identical bytes. grazing_plane.toml (conetrace)
and bench/peers/mitsuba/run.py (Mitsuba) describe the same camera over these assets.
"""

import os
import struct
import zlib

SIZE = 128
SQUARE = 4
HALF_EXTENT = 50.0


def tile_colours():
    """sRGB bytes of every square, row-major, from a fixed LCG."""
    state = 12345
    squares = SIZE // SQUARE
    colours = []
    for j in range(squares):
        for i in range(squares):
            rgb = []
            for _ in range(3):
                state = (1103515245 * state + 12345) % (1 << 31)
                rgb.append(state >> 23)  # 0..255
            if (i + j) % 2 == 0:
                rgb = [96 + c * 159 // 255 for c in rgb]  # bright square: 96..255
            else:
                rgb = [c * 64 // 255 for c in rgb]  # dark square: 0..64
            colours.append(rgb)
    return colours


def png_bytes(width, height, rows):
    """An 8-bit RGB PNG (sRGB chunk set) from rows of bytes."""

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    raw = b"".join(b"\x00" + bytes(row) for row in rows)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"sRGB", b"\x00")
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def texture_rows():
    colours = tile_colours()
    squares = SIZE // SQUARE
    rows = []
    for y in range(SIZE):
        row = []
        for x in range(SIZE):
            row.extend(colours[(y // SQUARE) * squares + x // SQUARE])
        rows.append(row)
    return rows


def plane_obj():
    e = HALF_EXTENT
    return "\n".join(
        [
            "# 100 x 100 quad in the xz plane facing +y; uvs span -50..50 (OBJ v up),",
            "# one texture repeat per world unit. Written by make_scene.py.",
            f"v {-e} 0 {e}",
            f"v {e} 0 {e}",
            f"v {e} 0 {-e}",
            f"v {-e} 0 {-e}",
            f"vt {-e} {-e}",
            f"vt {e} {-e}",
            f"vt {e} {e}",
            f"vt {-e} {e}",
            "vn 0 1 0",
            "f 1/1/1 2/2/1 3/3/1",
            "f 1/1/1 3/3/1 4/4/1",
            "",
        ]
    )


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "tiles.png"), "wb") as f:
        f.write(png_bytes(SIZE, SIZE, texture_rows()))
    with open(os.path.join(here, "plane.obj"), "w") as f:
        f.write(plane_obj())
    print(f"wrote {here}/tiles.png and {here}/plane.obj")


if __name__ == "__main__":
    main()
