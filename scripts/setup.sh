#!/usr/bin/env bash
# Installs the Debian packages conetrace needs to build, render and test, if any is missing.
# Debian bookworm, as root (or with sudo available). Safe to run repeatedly.
set -euo pipefail

# Every program the build and the tests run is here: cc (the build script's Embree shim, the
# C example), g++ (the FLIP metric's C++ source, the C++ example), pkg-config (tests/c_api.rs),
# /usr/bin/python3 with OpenImageIO and numpy, and maketx (tests/oiio_*.rs). The tests send
# signals through kill(2) themselves and need no `kill` program.
packages=(
  libembree-dev          # Embree 3.13.5 headers and libembree3 (ray traversal)
  libclang-dev clang     # libclang for bindgen, which generates the Embree bindings at build time
  gcc libc6-dev          # cc: the build script's C shim (wrapper/) and the C API's C example
  pkg-config             # tests/c_api.rs builds the examples with `pkg-config --cflags --libs`
  python3                # /usr/bin/python3 runs tests/oiio/*.py
  python3-openimageio    # OpenImageIO's TextureSystem: the filtering reference in the tests
  openimageio-tools      # maketx, for mip-mapped reference textures
  python3-numpy
  assimp-testmodels      # real OBJ/glTF files, valid and malformed, used by the tests
  libopenimageio-dev g++ # the C API's C++ example (OpenImageIO TextureSystem via the texture callback)
  fonts-dejavu-core      # DejaVuSans.ttf: labels of `conetrace accuracy`'s plot and crops (drawn without text if absent)
  slurm-wlm munge        # scripts/slurm/ and tests/slurm_cluster.rs (a one-node Slurm cluster: slurmctld, slurmd, sbatch, munged)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ "${#missing[@]}" -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "setup: installing ${missing[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

if ! command -v cargo >/dev/null 2>&1; then
  echo "setup: cargo not found; install Rust (rustup or Debian's cargo) and re-run" >&2
  exit 1
fi
