#!/usr/bin/env bash
# Regenerates docs/footprints.md's tile-count table and docs/images/fp_*.png: renders every
# footprint scene (assets/scenes/fp_*.toml, 320x180, 1 spp, trilinear filtering) under each
# level-of-detail strategy with --stats, prints the texture tiles touched as a Markdown table
# and puts pairs of renders side by side.
#
# Usage: bash scripts/footprint_figures.sh [OUTDIR]   (default OUTDIR: out/footprints)
# Needs the release binary (built once here) and python3 (standard library only).
set -euo pipefail

ROOT="$(cd "$(dirname "$0")/.." && pwd)"
OUT="${1:-$ROOT/out/footprints}"
mkdir -p "$OUT" "$ROOT/docs/images"
cd "$ROOT"
cargo build --release --quiet
BIN="${CARGO_TARGET_DIR:-$ROOT/target}/release/conetrace"

SCENES="convex concave two_cones vase vase_lined magnifier"
STRATEGIES="mip0 distance cone1 cone differential"
for scene in $SCENES; do
  for lod in $STRATEGIES; do
    "$BIN" render "assets/scenes/fp_$scene.toml" --lod "$lod" --filter trilinear \
      -o "$OUT/${scene}_$lod.exr" --png "$OUT/${scene}_$lod.png" \
      --stats "$OUT/${scene}_$lod.json" --quiet > /dev/null
  done
done

python3 - "$OUT" "$ROOT/docs/images" <<'EOF'
import json
import struct
import sys
import zlib

out, images = sys.argv[1], sys.argv[2]
scenes = ["convex", "concave", "two_cones", "vase", "vase_lined", "magnifier"]
strategies = ["mip0", "distance", "cone1", "cone", "differential"]

print("| scene | " + " | ".join(strategies) + " |")
print("|---" * (len(strategies) + 1) + "|")
for scene in scenes:
    cells = []
    for lod in strategies:
        with open("%s/%s_%s.json" % (out, scene, lod)) as f:
            cells.append(str(json.load(f)["texture_tiles"]["total"]))
    print("| fp_%s | %s |" % (scene, " | ".join(cells)))
print()
print("Tiles per mip level (level 0 first), cone vs distance:")
for scene in scenes:
    for lod in ("distance", "cone1", "cone"):
        with open("%s/%s_%s.json" % (out, scene, lod)) as f:
            tiles = json.load(f)["texture_tiles"]["per_texture"]
        print("- fp_%s, %s: %s" % (scene, lod, "; ".join("%s %s" % (n, t) for n, t in tiles)))


def read_png(path):
    """Decodes the 8-bit RGB/RGBA PNGs conetrace writes; returns width, height, RGB rows."""
    data = open(path, "rb").read()
    pos, idat = 8, b""
    while pos < len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            width, height, _, color_type = struct.unpack(">IIBB", body[:10])
        elif kind == b"IDAT":
            idat += body
    raw = zlib.decompress(idat)
    bpp = 4 if color_type == 6 else 3
    stride = width * bpp
    rows, prev, at = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[at], bytearray(raw[at + 1:at + 1 + stride])
        at += 1 + stride
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if kind == 1:
                line[x] = (line[x] + a) & 255
            elif kind == 2:
                line[x] = (line[x] + b) & 255
            elif kind == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(v for i, v in enumerate(line) if bpp == 3 or i % 4 != 3))
        prev = line
    return width, height, rows


def side_by_side(name, left, right):
    """Writes docs/images/<name>.png: two renders with a 4-pixel white gap."""
    a, b = read_png("%s/%s.png" % (out, left)), read_png("%s/%s.png" % (out, right))
    gap = b"\xff" * 12
    body = b"".join(b"\0" + ra + gap + rb for ra, rb in zip(a[2], b[2]))
    width = a[0] + 4 + b[0]

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, a[1], 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(body, 9)) + chunk(b"IEND", b"")
    with open("%s/%s.png" % (images, name), "wb") as f:
        f.write(png)


side_by_side("fp_convex_cone_vs_distance", "convex_cone", "convex_distance")
side_by_side("fp_concave_cone_vs_distance", "concave_cone", "concave_distance")
side_by_side("fp_two_cones_cone_vs_cone1", "two_cones_cone", "two_cones_cone1")
side_by_side("fp_vase_trap_vs_lined", "vase_cone", "vase_lined_cone")
side_by_side("fp_magnifier_cone_vs_distance", "magnifier_cone", "magnifier_distance")
EOF
