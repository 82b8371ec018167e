#!/usr/bin/env bash
# Generates the production-sized texture case of docs/texture-filtering.md in DIR:
#   untiled/tex_NN.tif  16 (or COUNT) 8192x8192 8-bit RGB scanline TIFFs (noise over a
#                       colour ramp of its own per texture), the untiled sources;
#   tx/tex_NN.tx        the same textures made tiled and mip-mapped by `conetrace maketx`;
#   scene_tx.toml       16 textured spheres seen from afar, 256x256, Whitted, on the .tx;
#   scene_untiled.toml  the same scene on the untiled TIFFs (decoded whole in memory).
# Usage: make_scene.sh DIR [COUNT] [SIZE]     (defaults 16 and 8192; needs about
#        COUNT x 0.47 GB of disk at 8192, and /usr/bin/python3 with numpy and OpenImageIO)
# CONETRACE names the binary (default: target/release/conetrace of this repository).
set -euo pipefail
dir=${1:?usage: make_scene.sh DIR [COUNT] [SIZE]}
count=${2:-16}
size=${3:-8192}
here=$(cd "$(dirname "$0")/../.." && pwd)
conetrace=${CONETRACE:-$here/target/release/conetrace}
[ -x "$conetrace" ] || { echo "make_scene.sh: $conetrace: not built (cargo build --release)" >&2; exit 2; }
mkdir -p "$dir/untiled" "$dir/tx"

/usr/bin/python3 - "$dir/untiled" "$count" "$size" <<'PY'
import os, sys
import numpy as np
import OpenImageIO as oiio
out, count, size = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
for i in range(count):
    path = os.path.join(out, "tex_%02d.tif" % i)
    if os.path.exists(path):
        continue
    rng = np.random.default_rng(1000 + i)
    # A ramp of the texture's own hue, with noise on top: every level differs.
    hue = np.array([(i * 37) % 256, (i * 91 + 80) % 256, (i * 53 + 160) % 256], np.float32)
    ramp = np.linspace(0.35, 1.0, size, dtype=np.float32)[:, None, None]
    base = (hue[None, None, :] * ramp).astype(np.uint8)
    image = np.empty((size, size, 3), np.uint8)
    for y0 in range(0, size, 1024):  # in bands: a few hundred MB at a time
        band = base[y0:y0 + 1024]
        noise = rng.integers(0, 64, (band.shape[0], size, 3), dtype=np.uint8)
        image[y0:y0 + 1024] = np.minimum(band.astype(np.uint16) + noise, 255).astype(np.uint8)
    spec = oiio.ImageSpec(size, size, 3, "uint8")
    spec.attribute("compression", "none")
    o = oiio.ImageOutput.create(path + ".part.tif")
    if not o.open(path + ".part.tif", spec):
        sys.exit("make_scene.sh: " + oiio.geterror())
    o.write_image(image)
    o.close()
    os.rename(path + ".part.tif", path)
    print("wrote", path, flush=True)
PY

for src in "$dir"/untiled/tex_*.tif; do
    tx="$dir/tx/$(basename "${src%.tif}").tx"
    [ -e "$tx" ] || "$conetrace" maketx "$src" "$tx"
done

# 16 spheres in a 4x4 grid, seen from afar: each covers a few dozen pixels, so a render
# needs coarse levels only.
write_scene() {  # $1 = scene file, $2 = texture directory, $3 = extension
    {
        printf '[render]\nwidth = 256\nheight = 256\nintegrator = "whitted"\n\n'
        printf '[camera]\neye = [0, 0, 60]\ntarget = [0, 0, 0]\nfov = 12\n\n'
        printf '[[light]]\ntype = "directional"\ndirection = [-0.3, -0.4, -1]\n\n'
        printf '[environment]\ncolor = [0.1, 0.1, 0.12]\n\n'
        i=0
        for src in "$dir"/untiled/tex_*.tif; do
            name=$(basename "${src%.tif}")
            x=$(awk "BEGIN{print ($i % 4) * 3 - 4.5}"); y=$(awk "BEGIN{print int($i / 4) * 3 - 4.5}")
            printf '[[texture]]\nname = "%s"\nfile = "%s/%s.%s"\n\n' "$name" "$2" "$name" "$3"
            printf '[[material]]\nname = "m%s"\nbase_color = [1, 1, 1]\nbase_color_texture = "%s"\n\n' "$name" "$name"
            printf '[[sphere]]\ncenter = [%s, %s, 0]\nradius = 1.2\nmaterial = "m%s"\n\n' "$x" "$y" "$name"
            i=$((i + 1))
        done
    } > "$1"
}
write_scene "$dir/scene_tx.toml" tx tx
write_scene "$dir/scene_untiled.toml" untiled tif
du -sh "$dir/untiled" "$dir/tx"
echo "wrote $dir/scene_tx.toml and $dir/scene_untiled.toml"
