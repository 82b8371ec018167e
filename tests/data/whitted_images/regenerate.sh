#!/bin/sh
# Renders the reference images that tests/whitted_images.rs compares against: every shipped
# scene (assets/scenes/**/*.toml and the built-in default scene) with the Whitted integrator
# (also for scenes that select another one),
# 64x36, one sample per pixel, every AOV, once with the scene's own effects and once with
# every effect forced on (the general path); and again with 4 samples per pixel and the
# default AOVs, the scene's own effects (`NAME.spp4.exr`, where hits are shaded in lanes).
# The options must match tests/whitted_images.rs.
#
# Usage: tests/data/whitted_images/regenerate.sh [path/to/conetrace [OUT]]
# Run it from the repository root with the binary of the code whose images are the
# reference (e.g. a build of the commit before a refactoring), then commit the EXRs.
# Embree's kernels for 16-lane packets (AVX-512) and 8-lane ones (AVX2) can differ in a
# hit's last bits, so each width has its own set: run it on a machine of each width, with
# OUT tests/data/whitted_images (the default) where Embree traces 16 lanes natively and
# tests/data/whitted_images/width8 where it traces 8 (a CPU with AVX2 but not AVX-512).
set -eu
bin=${1:-target/debug/conetrace}
out=${2:-tests/data/whitted_images}
mkdir -p "$out"
render() {
    name=$1
    shift
    "$bin" render "$@" --width 64 --height 36 --spp 1 --aov all --no-png --quiet \
        --threads 2 --integrator whitted --output "$out/$name.exr"
    "$bin" render "$@" --width 64 --height 36 --spp 1 --aov all --no-png --quiet \
        --threads 2 --integrator whitted --all-effects --output "$out/$name.all_effects.exr"
}
render_sample_waves() {
    name=$1
    shift
    "$bin" render "$@" --width 64 --height 36 --spp 4 --no-png --quiet \
        --threads 2 --integrator whitted --output "$out/$name.spp4.exr"
}
render builtin_default
for scene in $(find assets/scenes -name '*.toml' | sort); do
    name=$(echo "${scene#assets/scenes/}" | sed 's/\.toml$//; s#/#_#g')
    render "$name" "$scene"
    render_sample_waves "$name" "$scene"
done
