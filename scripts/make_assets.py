#!/usr/bin/env python3
"""Generates the default scene's textures and models (standard library only).

Writes, relative to the repository root:
  assets/textures/checker.png  1024x1024 checkerboard with 1-pixel grid lines and cell
                               numbers: high-frequency detail that shows texture aliasing
                               and over-blurring when the ground plane recedes.
  assets/textures/crate.png    256x256 wooden crate face.
  assets/textures/sky.png      512x256 lat-long sky (t = 0 at the zenith).
  assets/models/ground.obj     a 2x2 quad in the xz plane, uvs 0..1, normal +y.
  assets/models/crate.obj/.mtl a unit cube with per-face uvs, textured with crate.png.

Run from anywhere: python3 scripts/make_assets.py
"""

import math
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def write_png(path, width, height, pixel):
    """Writes an 8-bit RGB PNG; pixel(x, y) returns an (r, g, b) tuple of ints 0..255."""
    rows = bytearray()
    for y in range(height):
        # Filter type 1 (Sub): each byte stores the difference to the pixel on its left.
        rows.append(1)
        prev = (0, 0, 0)
        for x in range(width):
            r, g, b = pixel(x, y)
            rows += bytes(((r - prev[0]) & 255, (g - prev[1]) & 255, (b - prev[2]) & 255))
            prev = (r, g, b)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(bytes(rows), 9))
    data += chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(data)


# 5x7 digit glyphs, one string of five bits per row.
DIGITS = {
    "0": ["01110", "10001", "10011", "10101", "11001", "10001", "01110"],
    "1": ["00100", "01100", "00100", "00100", "00100", "00100", "01110"],
    "2": ["01110", "10001", "00001", "00010", "00100", "01000", "11111"],
    "3": ["11110", "00001", "00001", "01110", "00001", "00001", "11110"],
    "4": ["00010", "00110", "01010", "10010", "11111", "00010", "00010"],
    "5": ["11111", "10000", "11110", "00001", "00001", "10001", "01110"],
    "6": ["00110", "01000", "10000", "11110", "10001", "10001", "01110"],
    "7": ["11111", "00001", "00010", "00100", "01000", "01000", "01000"],
    "8": ["01110", "10001", "10001", "01110", "10001", "10001", "01110"],
    "9": ["01110", "10001", "10001", "01111", "00001", "00010", "01100"],
}


def clamp8(v):
    return max(0, min(255, int(round(v))))


def checker():
    size, cells, glyph_scale = 1024, 8, 4
    cell = size // cells
    light, dark = (228, 222, 205), (52, 62, 84)
    line_light, line_dark = (150, 140, 120), (110, 125, 150)

    def pixel(x, y):
        cx, cy = x // cell, y // cell
        is_light = (cx + cy) % 2 == 0
        color = light if is_light else dark
        lx, ly = x % cell, y % cell
        # Fine grid: a 1-pixel line every 16 pixels.
        if lx % 16 == 0 or ly % 16 == 0:
            color = line_light if is_light else line_dark
        # Two-digit cell number in the cell's upper left.
        label = "%02d" % (cy * cells + cx)
        gx, gy = lx - 24, ly - 24
        if 0 <= gy < 7 * glyph_scale and 0 <= gx < 12 * glyph_scale:
            digit, col = divmod(gx, 6 * glyph_scale)
            col //= glyph_scale
            if col < 5 and DIGITS[label[digit]][gy // glyph_scale][col] == "1":
                color = (200, 40, 30) if is_light else (250, 200, 60)
        return color

    write_png(os.path.join(ROOT, "assets/textures/checker.png"), size, size, pixel)


def crate():
    size, border = 256, 20

    def pixel(x, y):
        plank = y // 54
        grain = 0.5 + 0.5 * math.sin(x * 0.09 + 3.0 * math.sin(y * 0.21 + plank * 1.7) + plank * 2.3)
        base = (150 + 40 * grain, 100 + 28 * grain, 55 + 15 * grain)
        if y % 54 < 2:
            base = (70, 45, 25)
        on_border = x < border or y < border or x >= size - border or y >= size - border
        on_brace = abs(x - y) < border // 2 + 2
        if on_border or on_brace:
            shade = 0.75 + 0.1 * math.sin((x + y) * 0.15)
            base = (120 * shade, 78 * shade, 40 * shade)
        return tuple(clamp8(c) for c in base)

    write_png(os.path.join(ROOT, "assets/textures/crate.png"), size, size, pixel)


def sky():
    width, height = 512, 256
    zenith, horizon, ground = (0.20, 0.38, 0.80), (0.85, 0.88, 0.92), (0.32, 0.29, 0.25)

    def to_srgb(v):
        v = max(0.0, min(1.0, v))
        s = 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055
        return clamp8(255 * s)

    def pixel(x, y):
        theta = (y + 0.5) / height * math.pi
        elevation = math.pi / 2 - theta
        phi = (x + 0.5) / width * 2 * math.pi
        if elevation >= 0:
            w = math.sin(elevation) ** 0.5
            c = [h * (1 - w) + z * w for h, z in zip(horizon, zenith)]
            # Soft cloud bands, periodic in azimuth so the seam at s = 0 is invisible.
            cloud = max(0.0, math.sin(3 * phi + 4 * elevation) * math.sin(7 * phi - 9 * elevation)) ** 2
            cloud *= max(0.0, 1 - 2 * elevation)
            c = [v * (1 - 0.6 * cloud) + 0.95 * 0.6 * cloud for v in c]
        else:
            w = min(1.0, -elevation * 4)
            c = [h * (1 - w) + g * w for h, g in zip(horizon, ground)]
        return tuple(to_srgb(v) for v in c)

    write_png(os.path.join(ROOT, "assets/textures/sky.png"), width, height, pixel)


def models():
    ground = """# A 2x2 quad in the xz plane facing +y; uvs span 0..1 (OBJ v up).
v -1 0 1
v 1 0 1
v 1 0 -1
v -1 0 -1
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 1 0
f 1/1/1 2/2/1 3/3/1 4/4/1
"""
    with open(os.path.join(ROOT, "assets/models/ground.obj"), "w") as f:
        f.write(ground)

    # Unit cube: each face has its own four vertices so uvs can span 0..1 per face.
    faces = [
        ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
        ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
        ((0, 1, 0), (1, 0, 0), (0, 0, -1)),
        ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
        ((0, 0, 1), (1, 0, 0), (0, 1, 0)),
        ((0, 0, -1), (-1, 0, 0), (0, 1, 0)),
    ]
    lines = ["# A unit cube centred at the origin, one texture per face.", "mtllib crate.mtl"]
    for n, u, v in faces:
        for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            p = [0.5 * (n[i] + su * u[i] + sv * v[i]) for i in range(3)]
            lines.append("v %g %g %g" % tuple(p))
    for _ in faces:
        lines += ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1"]
    for n, _, _ in faces:
        lines.append("vn %g %g %g" % n)
    lines.append("usemtl crate")
    for k in range(len(faces)):
        i = 4 * k
        lines.append("f " + " ".join("%d/%d/%d" % (i + j + 1, i + j + 1, k + 1) for j in range(4)))
    with open(os.path.join(ROOT, "assets/models/crate.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(ROOT, "assets/models/crate.mtl"), "w") as f:
        f.write("newmtl crate\nKd 1 1 1\nKs 0.1 0.1 0.1\nNs 20\nmap_Kd ../textures/crate.png\n")


if __name__ == "__main__":
    for d in ("assets/textures", "assets/models"):
        os.makedirs(os.path.join(ROOT, d), exist_ok=True)
    checker()
    crate()
    sky()
    models()
