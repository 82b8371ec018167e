#!/usr/bin/env python3
"""Generates the textures and models of the footprint scenes (standard library only).

These scenes (assets/scenes/fp_*.toml) reproduce seed 000's figures 4-7 and seed 002's
magnifier; docs/footprints.md shows them. Writes, relative to the repository root:

  assets/textures/miplevels.exr  1024x1024 mip-mapped OpenEXR (tiled 64x64, ZIP, half):
                                 each mip level is a checker with grid lines tinted in its own
                                 colour (level 0 red, 1 orange, 2 yellow, 3 green, 4 cyan,
                                 5 blue, 6 violet, 7 magenta, 8.. grey), so a render shows
                                 which level every lookup used, as in seed 000's figures.
  assets/textures/fine_text.png  1024x1024 black 5x7 digits on paper (seed 002's magnifier).
  assets/textures/leaf_alpha.png 256x256 RGBA leaves: alpha exactly 0 or 255 (linear), green.
  assets/models/dish.obj         spherical cap of the unit sphere around -z (half-angle 40
                                 degrees), normals towards the centre: a concave mirror.
  assets/models/vase_outer.obj   lathe (surface of revolution) vase, outer wall + bottom.
  assets/models/vase_inner.obj   the vase's inner wall, normals inwards.
  assets/models/vase_floor.obj   the vase's inner bottom (a disc facing up).
  assets/models/lens.obj         biconvex lens (two spherical caps), axis +z, radius 1.

Run from anywhere: python3 scripts/make_footprint_assets.py
"""

import math
import os
import struct
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def png_chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def write_png(path, width, height, pixel, channels):
    """8-bit PNG, RGB (channels=3) or RGBA (4); pixel(x, y) returns a tuple of ints 0..255."""
    rows = bytearray()
    for y in range(height):
        rows.append(0)
        for x in range(width):
            rows += bytes(pixel(x, y))
    color_type = 2 if channels == 3 else 6
    header = struct.pack(">IIBBBBB", width, height, 8, color_type, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header)
    data += png_chunk(b"IDAT", zlib.compress(bytes(rows), 9)) + png_chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(data)


# ---------------------------------------------------------------------------------------
# Mip-level-coloured texture as a tiled, mip-mapped OpenEXR.

LEVEL_TINTS = [
    (1.00, 0.10, 0.08),  # 0 red
    (1.00, 0.45, 0.05),  # 1 orange
    (0.95, 0.90, 0.10),  # 2 yellow
    (0.15, 0.85, 0.15),  # 3 green
    (0.10, 0.85, 0.90),  # 4 cyan
    (0.15, 0.30, 1.00),  # 5 blue
    (0.55, 0.20, 1.00),  # 6 violet
    (1.00, 0.20, 0.85),  # 7 magenta
]
COARSE_TINT = (0.6, 0.6, 0.6)


def exr_zip(raw):
    """OpenEXR ZIP compression of one block: byte split, delta predictor, zlib."""
    half = (len(raw) + 1) // 2
    split = bytearray(len(raw))
    split[:half] = raw[0::2]
    split[half:] = raw[1::2]
    out = bytearray(len(split))
    prev = split[0] if split else 0
    if split:
        out[0] = split[0]
    for i in range(1, len(split)):
        cur = split[i]
        out[i] = (cur - prev + 128 + 256) & 0xFF
        prev = cur
    packed = zlib.compress(bytes(out), 9)
    return packed if len(packed) < len(raw) else raw


def exr_attribute(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def write_mip_exr(path, levels, tile=64):
    """levels: list of (width, height, rows) with rows[y][x] = (r, g, b), finest first."""
    width, height = levels[0][0], levels[0][1]
    chlist = b""
    for name in ("B", "G", "R"):  # alphabetical, as OpenEXR stores them
        chlist += name.encode() + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1)  # HALF
    chlist += b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = b"\x76\x2f\x31\x01" + struct.pack("<I", 2 | 0x200)
    header += exr_attribute("channels", "chlist", chlist)
    header += exr_attribute("compression", "compression", bytes([3]))  # ZIP
    header += exr_attribute("dataWindow", "box2i", box)
    header += exr_attribute("displayWindow", "box2i", box)
    header += exr_attribute("lineOrder", "lineOrder", bytes([0]))
    header += exr_attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
    header += exr_attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
    header += exr_attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
    # Mip-map levels (mode 1), rounding down (0 << 4).
    header += exr_attribute("tiles", "tiledesc", struct.pack("<IIB", tile, tile, 1))
    header += b"\0"
    chunks = []
    for level, (w, h, rows) in enumerate(levels):
        for ty in range((h + tile - 1) // tile):
            for tx in range((w + tile - 1) // tile):
                x0, y0 = tx * tile, ty * tile
                x1, y1 = min(w, x0 + tile), min(h, y0 + tile)
                raw = bytearray()
                for y in range(y0, y1):
                    row = rows[y][x0:x1]
                    for c in (2, 1, 0):
                        raw += struct.pack("<%de" % len(row), *(p[c] for p in row))
                data = exr_zip(bytes(raw))
                chunks.append(struct.pack("<iiiii", tx, ty, level, level, len(data)) + data)
    offset = len(header) + 8 * len(chunks)
    table = b""
    for chunk in chunks:
        table += struct.pack("<Q", offset)
        offset += len(chunk)
    with open(path, "wb") as f:
        f.write(header + table + b"".join(chunks))


def miplevels():
    size, cell, grid = 1024, 64, 8
    # Level 0 brightness: a checker of 64-texel cells with 1-texel grid lines every 8.
    lum = []
    for y in range(size):
        row = []
        for x in range(size):
            v = 0.9 if ((x // cell) + (y // cell)) % 2 == 0 else 0.3
            if x % grid == 0 or y % grid == 0:
                v *= 0.55
            row.append(v)
        lum.append(row)
    levels = []
    level = 0
    while True:
        n = len(lum)
        tint = LEVEL_TINTS[level] if level < len(LEVEL_TINTS) else COARSE_TINT
        rows = [[(tint[0] * v, tint[1] * v, tint[2] * v) for v in row] for row in lum]
        levels.append((n, n, rows))
        if n == 1:
            break
        # Box filter for the next level's brightness (maketx's rule for even sizes).
        lum = [
            [
                0.25 * (lum[2 * y][2 * x] + lum[2 * y][2 * x + 1] + lum[2 * y + 1][2 * x] + lum[2 * y + 1][2 * x + 1])
                for x in range(n // 2)
            ]
            for y in range(n // 2)
        ]
        level += 1
    write_mip_exr(os.path.join(ROOT, "assets/textures/miplevels.exr"), levels)


# ---------------------------------------------------------------------------------------
# Fine text and leaves.

# The 5x7 digit glyphs of the default scene's checker texture.
from make_assets import DIGITS  # noqa: E402


def fine_text():
    size, scale = 1024, 2
    char_w, line_h = 6 * scale, 10 * scale
    paper, ink = (235, 230, 215), (20, 20, 30)

    def pixel(x, y):
        line, gy = divmod(y, line_h)
        column, gx = divmod(x, char_w)
        gx //= scale
        gy = gy // scale - 1
        if 0 <= gy < 7 and gx < 5 and column < size // char_w:
            digit = str((line * 7 + column * 3 + (line * column) // 5) % 10)
            if DIGITS[digit][gy][gx] == "1":
                return ink
        return paper

    write_png(os.path.join(ROOT, "assets/textures/fine_text.png"), size, size, pixel, 3)


# Leaves: (centre s, centre t, half length, half width, angle in radians), texture units.
LEAVES = [
    (0.28, 0.30, 0.24, 0.09, 0.6),
    (0.70, 0.25, 0.22, 0.08, -0.5),
    (0.50, 0.62, 0.26, 0.10, 1.4),
    (0.20, 0.78, 0.18, 0.07, -0.9),
    (0.80, 0.72, 0.20, 0.08, 0.3),
]


def leaf_alpha():
    size = 256

    def inside(s, t):
        for cs, ct, a, b, angle in LEAVES:
            ds, dt = s - cs, t - ct
            u = ds * math.cos(angle) + dt * math.sin(angle)
            v = -ds * math.sin(angle) + dt * math.cos(angle)
            # A pointed leaf: an ellipse narrowed towards both tips.
            if abs(u) < a and abs(v) < b * (1 - (u / a) ** 2) ** 0.5 * (1 - 0.3 * abs(u) / a):
                return True
        return False

    covered = 0

    def pixel(x, y):
        nonlocal covered
        s, t = (x + 0.5) / size, (y + 0.5) / size
        if inside(s, t):
            covered += 1
            shade = 0.75 + 0.25 * math.sin(40 * s + 25 * t)
            return (int(60 * shade), int(150 * shade), int(50 * shade), 255)
        return (40, 90, 30, 0)

    write_png(os.path.join(ROOT, "assets/textures/leaf_alpha.png"), size, size, pixel, 4)
    print("leaf_alpha.png: mean alpha %.4f" % (covered / (size * size)))


# ---------------------------------------------------------------------------------------
# Models.


def write_obj(path, comment, vertices, normals, uvs, faces):
    """faces: triangles of vertex indices (0-based); each vertex has its normal and uv."""
    lines = ["# " + comment]
    lines += ["v %.5g %.5g %.5g" % p for p in vertices]
    lines += ["vt %.4g %.4g" % uv for uv in uvs]
    lines += ["vn %.4g %.4g %.4g" % n for n in normals]
    for f in faces:
        lines.append("f " + " ".join("%d/%d/%d" % (i + 1, i + 1, i + 1) for i in f))
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def normalize(v):
    length = math.sqrt(sum(c * c for c in v)) or 1.0
    return tuple(c / length for c in v)


def lathe(profile, segments, inward):
    """Surface of revolution about +y. profile: list of (radius, y, profile normal (nr, ny)).
    Returns vertices, normals, uvs (s = angle / 2pi, v = y parameter), triangles."""
    vertices, normals, uvs, faces = [], [], [], []
    ring = segments + 1
    for k, (r, y, (nr, ny)) in enumerate(profile):
        for j in range(ring):
            phi = 2 * math.pi * j / segments
            c, s = math.cos(phi), math.sin(phi)
            vertices.append((r * c, y, r * s))
            n = normalize((nr * c, ny, nr * s))
            normals.append(tuple(-x for x in n) if inward else n)
            uvs.append((j / segments, k / (len(profile) - 1)))
    for k in range(len(profile) - 1):
        for j in range(segments):
            a, b = k * ring + j, k * ring + j + 1
            c, d = a + ring, b + ring
            # Counter-clockwise seen from the side the normals face.
            faces += [(a, b, c), (b, d, c)] if inward else [(a, c, b), (b, c, d)]
    return vertices, normals, uvs, faces


def profile_normals(points):
    """Outward (away from the axis) normals of a profile polyline of (r, y)."""
    out = []
    for i, (r, y) in enumerate(points):
        r0, y0 = points[max(0, i - 1)]
        r1, y1 = points[min(len(points) - 1, i + 1)]
        dr, dy = r1 - r0, y1 - y0
        out.append((r, y, (dy, -dr)))
    return out


def vase_radius(y):
    """Vase profile: a round belly, a narrow neck and a flared lip; height 2."""
    belly = 0.55 * math.sin(math.pi * min(1.0, y / 1.5)) ** 0.8
    neck = 0.36 + 0.16 * max(0.0, (y - 1.5) / 0.5) ** 2
    w = min(1.0, max(0.0, (y - 1.1) / 0.5))
    return max(0.12, (1 - w) * (0.18 + belly) + w * neck)


def models():
    models_dir = os.path.join(ROOT, "assets/models")
    # Concave mirror: cap of the unit sphere around -z, normals towards the centre.
    rings, segments, half_angle = 16, 48, math.radians(40)
    vertices, normals, uvs, faces = [], [], [], []
    vertices.append((0.0, 0.0, -1.0))
    normals.append((0.0, 0.0, 1.0))
    uvs.append((0.5, 0.5))
    for k in range(1, rings + 1):
        theta = half_angle * k / rings
        for j in range(segments):
            phi = 2 * math.pi * j / segments
            p = (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), -math.cos(theta))
            vertices.append(p)
            normals.append(tuple(-c for c in p))
            uvs.append((0.5 + 0.5 * p[0] / math.sin(half_angle), 0.5 + 0.5 * p[1] / math.sin(half_angle)))
    for j in range(segments):
        faces.append((0, 1 + j, 1 + (j + 1) % segments))
    for k in range(1, rings):
        base, nxt = 1 + (k - 1) * segments, 1 + k * segments
        for j in range(segments):
            j1 = (j + 1) % segments
            faces += [(base + j, nxt + j, nxt + j1), (base + j, nxt + j1, base + j1)]
    write_obj(
        os.path.join(models_dir, "dish.obj"),
        "Concave mirror: the unit sphere's cap around -z (40 degree half-angle), normals inwards.",
        vertices,
        normals,
        uvs,
        faces,
    )

    # Vase: outer wall (normals outwards) and inner wall (offset 0.04, normals towards the
    # axis), both closed at the bottom by a disc; open at the top.
    steps = 32
    outer = [(vase_radius(2.0 * i / steps), 2.0 * i / steps) for i in range(steps + 1)]
    inner = [(max(0.05, r - 0.04), max(0.04, y)) for r, y in outer]
    bottom_y = outer[0][1]
    v, n, uv, f = lathe(profile_normals([(0.0, bottom_y)] + outer), 64, False)
    write_obj(
        os.path.join(models_dir, "vase_outer.obj"),
        "Vase outer wall (lathe of a belly-neck-lip profile) and bottom, normals outwards.",
        v, n, uv, f,
    )
    v, n, uv, f = lathe(profile_normals(inner), 64, True)
    write_obj(
        os.path.join(models_dir, "vase_inner.obj"),
        "Vase inner wall (open at both ends), normals towards the inside.",
        v, n, uv, f,
    )
    r0, y0 = inner[0]
    disc = [(0.0, y0), (r0 * 0.5, y0), (r0, y0)]
    v, n, uv, f = lathe(profile_normals(disc), 64, True)
    write_obj(
        os.path.join(models_dir, "vase_floor.obj"),
        "The vase's inner bottom, a disc facing up.",
        v, n, uv, f,
    )

    # Biconvex lens: spherical caps of radius 2.5 meeting at radius 1, axis +z.
    radius, aperture = 2.5, 1.0
    offset = math.sqrt(radius * radius - aperture * aperture)
    steps = 16
    vertices, normals, uvs, faces = [], [], [], []
    for side in (1, -1):
        points = []
        for i in range(steps + 1):
            r = aperture * i / steps
            z = side * (math.sqrt(radius * radius - r * r) - offset)
            points.append((r, z))
        start = len(vertices)
        ring = 49
        for k, (r, z) in enumerate(points):
            for j in range(ring):
                phi = 2 * math.pi * j / (ring - 1)
                p = (r * math.cos(phi), r * math.sin(phi), z)
                vertices.append(p)
                normals.append(normalize((p[0], p[1], p[2] + side * offset)))
                uvs.append((j / (ring - 1), k / steps))
        for k in range(steps):
            for j in range(ring - 1):
                a, b = start + k * ring + j, start + k * ring + j + 1
                c, d = a + ring, b + ring
                # Counter-clockwise seen from outside: the geometric normal faces out.
                faces += [(a, c, b), (b, c, d)] if side > 0 else [(a, b, c), (b, d, c)]
    write_obj(
        os.path.join(models_dir, "lens.obj"),
        "Biconvex lens: two caps of radius 2.5 meeting at radius 1, axis +z.",
        vertices,
        normals,
        uvs,
        faces,
    )


if __name__ == "__main__":
    for d in ("assets/textures", "assets/models"):
        os.makedirs(os.path.join(ROOT, d), exist_ok=True)
    miplevels()
    fine_text()
    leaf_alpha()
    models()
