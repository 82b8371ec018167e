#!/usr/bin/env bash
# Renders the scene of make_scene.sh (in DIR) five ways in one run and prints a markdown
# table: time to the first traced ray (--stats phases.first_ray), total time, peak resident
# memory (/usr/bin/time -v), texture tiles loaded, and whether the image equals the
# uncapped render bit for bit.
#   uncapped   the .tx textures, demand-loaded, cache cap 64 GiB (nothing is evicted)
#   default    the .tx textures under the default cap (256 MiB)
#   256M       the same with --texture-cache 256M spelled out
#   small      the same with --texture-cache SMALL (default 1M, 64 8-bit tiles: below the frame's working set)
#   whole      the untiled TIFFs: every texture decoded whole with all its levels before
#              the first ray (the in-memory fallback)
# Usage: measure.sh DIR [SMALL]      CONETRACE names the binary (default: release build)
set -euo pipefail
dir=${1:?usage: measure.sh DIR [SMALL]}
small=${2:-1M}
here=$(cd "$(dirname "$0")/../.." && pwd)
conetrace=${CONETRACE:-$here/target/release/conetrace}
[ -x "$conetrace" ] || { echo "measure.sh: $conetrace: not built (cargo build --release)" >&2; exit 2; }
[ -e "$dir/scene_tx.toml" ] || { echo "measure.sh: $dir/scene_tx.toml: run make_scene.sh first" >&2; exit 2; }
out="$dir/out"
mkdir -p "$out"

run() {  # $1 = label, $2 = scene, rest = options
    local label=$1 scene=$2
    shift 2
    /usr/bin/time -v "$conetrace" render "$scene" -o "$out/$label.exr" --no-png --quiet \
        --stats "$out/$label.json" "$@" > "$out/$label.log" 2> "$out/$label.time"
}

echo "# $(date -u '+%Y-%m-%d %H:%M UTC'); load:$(uptime | sed 's/.*load average://')"
echo "# $("$conetrace" --version); $(nproc) cores; textures: $(du -sh "$dir/tx" | cut -f1) as .tx, $(du -sh "$dir/untiled" | cut -f1) untiled"
run uncapped "$dir/scene_tx.toml" --texture-cache 64G
run default "$dir/scene_tx.toml"
run 256M "$dir/scene_tx.toml" --texture-cache 256M
run small "$dir/scene_tx.toml" --texture-cache "$small"
run whole "$dir/scene_untiled.toml"

/usr/bin/python3 - "$out" "$small" <<'PY'
import json, re, sys
import numpy as np
import OpenImageIO as oiio
out, small = sys.argv[1], sys.argv[2]

def pixels(label):
    image = oiio.ImageInput.open("%s/%s.exr" % (out, label))
    data = image.read_image(0, 0, 0, image.spec().nchannels, "float")
    image.close()
    return data.view(np.uint32)

reference = pixels("uncapped")
print("| run | cache cap | time to first ray (s) | total (s) | peak RSS (MiB) | tiles loaded | tiles evicted | textures decoded whole | image = uncapped |")
print("|---|---|---|---|---|---|---|---|---|")
caps = {"uncapped": "64 GiB", "default": "default (256 MiB)", "256M": "256 MiB", "small": small, "whole": "n/a"}
for label in ["uncapped", "default", "256M", "small", "whole"]:
    stats = json.load(open("%s/%s.json" % (out, label)))
    rss_kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)",
                            open("%s/%s.time" % (out, label)).read()).group(1))
    cache = stats.get("texture_cache") or {}
    whole = sum(1 for t in stats["texture_memory"] if not t["demand_loaded"])
    same = "yes" if np.array_equal(pixels(label), reference) else "NO"
    print("| %s | %s | %.3f | %.3f | %.0f | %s | %s | %d of %d | %s |" % (
        label, caps[label], stats["phases"]["first_ray"], stats["phases"]["total"],
        rss_kib / 1024, cache.get("tiles_loaded", 0), cache.get("tiles_evicted", 0),
        whole, len(stats["texture_memory"]), same))
PY
