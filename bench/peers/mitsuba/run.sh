#!/usr/bin/env bash
# conetrace vs Mitsuba 3 on the same scene (bench/peers/README.md). Idempotent set-up, then
# run.py: writes bench/peers/results/mitsuba.{csv,md} and mitsuba_side_by_side.png.
#
#   bash bench/peers/mitsuba/run.sh [run.py options, e.g. --max-spp 1024]
#   bash bench/peers/mitsuba/run.sh sampler [sampler.py options]   (samplers at equal N)
#   bash bench/peers/mitsuba/run.sh direct [direct.py options]     (direct lighting)
#   bash bench/peers/mitsuba/run.sh cornell [cornell.py options]   (path tracers agree?)
#   bash bench/peers/mitsuba/run.sh path [path.py options]         (path tracing, time to error)
#   bash bench/peers/mitsuba/run.sh traversal [traversal.py options] (Embree alone, same rays)
#
# Installs (only what is missing): Debian's libllvm19 (Mitsuba's llvm_ad_rgb variant JIT-
# compiles with it), python3-venv, python3-openimageio and python3-numpy (reading EXRs),
# then a virtual environment with mitsuba pinned below. Needs root for apt-get.
# Environment: PEERS_CACHE (default ~/.cache/conetrace-peers) holds the virtual
# environment and the intermediate EXRs; CARGO_TARGET_DIR is honoured for the build;
# CONETRACE names an already built binary instead.
set -euo pipefail

MITSUBA_VERSION=3.9.1

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../../.." && pwd)"
cache="${PEERS_CACHE:-$HOME/.cache/conetrace-peers}"

missing=()
for package in libllvm19 python3-venv python3-openimageio python3-numpy; do
    dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
done
if [ "${#missing[@]}" -gt 0 ]; then
    echo "installing ${missing[*]}"
    apt-get update
    DEBIAN_FRONTEND=noninteractive apt-get install -y "${missing[@]}"
fi

# The system interpreter: Debian's OpenImageIO and numpy modules live in its site-packages.
venv="$cache/venv"
if [ ! -x "$venv/bin/python" ]; then
    /usr/bin/python3 -m venv --system-site-packages "$venv"
fi
if ! "$venv/bin/python" -c "import mitsuba, sys; sys.exit(mitsuba.__version__ != '$MITSUBA_VERSION')" 2>/dev/null; then
    "$venv/bin/pip" install --quiet "mitsuba==$MITSUBA_VERSION"
fi

# CONETRACE=/path/to/conetrace skips the build (e.g. while another cargo holds the lock).
if [ -n "${CONETRACE:-}" ]; then
    binary="$CONETRACE"
else
    (cd "$repo" && cargo build --release --quiet)
    binary="$(cd "$repo" && realpath -m "${CARGO_TARGET_DIR:-target}")/release/conetrace"
fi

# Regenerate the scene's texture and plane only if they are missing (deterministic bytes).
if [ ! -f "$repo/bench/peers/scene/tiles.png" ] || [ ! -f "$repo/bench/peers/scene/plane.obj" ]; then
    /usr/bin/python3 "$repo/bench/peers/scene/make_scene.py"
fi

script="$here/run.py"
if [ "${1:-}" = "sampler" ]; then
    script="$here/sampler.py"
    shift
elif [ "${1:-}" = "direct" ]; then
    script="$here/direct.py"
    shift
elif [ "${1:-}" = "cornell" ]; then
    script="$here/cornell.py"
    shift
elif [ "${1:-}" = "path" ]; then
    script="$here/path.py"
    shift
elif [ "${1:-}" = "traversal" ]; then
    script="$here/traversal.py"
    shift
    (cd "$repo" && cargo build --release --quiet --example peer_traversal)
    example="$(cd "$repo" && realpath -m "${CARGO_TARGET_DIR:-target}")/release/examples/peer_traversal"
    set -- --example "$example" "$@"
fi
exec "$venv/bin/python" "$script" --conetrace "$binary" --work "$cache/work" "$@"
