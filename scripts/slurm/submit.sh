#!/usr/bin/env bash
# Submits a conetrace render split into PARTS Slurm array tasks, plus the merge job that
# runs when all of them succeeded, and prints the two job ids.
#
#   scripts/slurm/submit.sh SCENE PARTS [--only LIST] [conetrace render options...]
#
#   --only LIST   submit only these parts (Slurm array syntax: 2 or 1,3 or 0-5), e.g. to
#                 complete a job one of whose tasks failed; the merge then uses the parts
#                 already in the output directory for the others.
#
# Environment: CONETRACE (the binary, default `conetrace`), OUTDIR (the parts' directory,
# default ./conetrace-parts/<scene name>), OUTPUT (the merged EXR, default
# OUTDIR/merged.exr). sbatch's own SBATCH_* variables (SBATCH_PARTITION, SBATCH_ACCOUNT,
# SBATCH_TIMELIMIT ...) apply to both jobs.
#
# Output (stdout), one line: "render job <id> (parts <list>), merge job <id>".
set -euo pipefail

usage="usage: submit.sh SCENE PARTS [--only LIST] [conetrace render options...]"
scene="${1:?$usage}"
parts="${2:?$usage}"
shift 2
if ! [[ "$parts" =~ ^[1-9][0-9]*$ ]]; then
  echo "submit.sh: PARTS must be a positive whole number, got '$parts'" >&2
  exit 2
fi
array="0-$((parts - 1))"
if [ "${1:-}" = "--only" ]; then
  array="${2:?$usage}"
  shift 2
fi
if [ ! -f "$scene" ]; then
  echo "submit.sh: $scene: no such scene file" >&2
  exit 2
fi

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
name="$(basename "${scene%.*}")"
scene="$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")"
outdir="${OUTDIR:-$PWD/conetrace-parts/$name}"
output="${OUTPUT:-$outdir/merged.exr}"
mkdir -p "$outdir"
outdir="$(cd "$outdir" && pwd)"
export CONETRACE="${CONETRACE:-conetrace}"

render_job=$(sbatch --parsable --array="$array" --job-name="conetrace-$name" \
  --output="$outdir/slurm-render-%A_%a.out" --export=ALL \
  "$here/render.sbatch" render "$scene" "$outdir" "$parts" "$@")
render_job="${render_job%%;*}"
merge_job=$(sbatch --parsable --dependency="afterok:$render_job" --kill-on-invalid-dep=yes \
  --job-name="conetrace-$name-merge" --output="$outdir/slurm-merge-%j.out" --export=ALL \
  "$here/render.sbatch" merge "$outdir" "$parts" "$output")
merge_job="${merge_job%%;*}"
echo "render job $render_job (parts $array), merge job $merge_job"
