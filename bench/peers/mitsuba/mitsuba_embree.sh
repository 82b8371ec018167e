#!/usr/bin/env bash
# Builds a stand-in for Debian's libembree3.so.3 that forwards every Embree function
# conetrace calls to the Embree that Mitsuba 3's wheel bundles, so that conetrace can be
# timed with Mitsuba's own Embree build (docs/benchmarks.md, "Traversal with Mitsuba's
# Embree and Mitsuba's choices").
#
# Mitsuba's wheel (installed by run.sh) ships Embree 3.13.4 with its API inside the C++
# namespace `mitsuba` (`mitsuba::rtcNewDevice`, ...). The stand-in exports the C names, each
# a jump to the namespaced function; the structures and calling conventions are Embree 3's
# on both sides.
#
# Usage: bash bench/peers/mitsuba/mitsuba_embree.sh CONETRACE_BINARY OUT_DIR
# then:  LD_LIBRARY_PATH=OUT_DIR CONETRACE_BINARY ...
set -euo pipefail

if [ "$#" -ne 2 ]; then
    echo "usage: $0 CONETRACE_BINARY OUT_DIR" >&2
    exit 2
fi
binary="$1"
out="$2"
cache="${PEERS_CACHE:-$HOME/.cache/conetrace-peers}"
library="$(ls "$cache"/venv/lib/python3*/site-packages/mitsuba/libembree3.so 2>/dev/null | head -n1)"
if [ -z "$library" ]; then
    echo "$0: no Mitsuba wheel under $cache/venv (run bench/peers/mitsuba/run.sh first)" >&2
    exit 1
fi
mkdir -p "$out"
ln -sf "$library" "$out/libembree3.so"

# One forwarding jump per Embree function the binary imports.
exported="$(objdump -T "$library" | awk '{print $NF}' | grep '^_ZN7mitsuba' || true)"
{
    echo '.text'
    for name in $(nm -D --undefined-only "$binary" | awk '$2 ~ /^rtc/ {print $2}'); do
        # Itanium mangling of mitsuba::NAME(...): _ZN7mitsuba<length><name>E<parameters>.
        mangled="$(grep -E "^_ZN7mitsuba${#name}${name}E" <<<"$exported" | head -n1)"
        if [ -z "$mangled" ]; then
            echo "$0: $library has no mitsuba::$name" >&2
            exit 1
        fi
        printf '.globl %s\n.type %s,@function\n%s: jmp %s@PLT\n' \
            "$name" "$name" "$name" "$mangled"
    done
    echo '.section .note.GNU-stack,"",@progbits'
} >"$out/forward.s"
gcc -shared -o "$out/libembree3.so.3" -Wl,-soname,libembree3.so.3 "$out/forward.s" \
    -L"$out" -l:libembree3.so
echo "built $out/libembree3.so.3 (forwarding to $library)"
echo "run: LD_LIBRARY_PATH=$out $binary ..."
