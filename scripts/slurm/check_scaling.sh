#!/usr/bin/env bash
# Measures the wall time of submit.sh renders with 1..4 tasks on a running cluster
# (SLURM_CONF), from submission to the end of the merge job, to check
# `conetrace bench scale-out` (docs/scale-out.md).
#
#   scripts/slurm/check_scaling.sh SCENE [conetrace render options...]
#
# Prints one line per task count: "tasks N: wall S s". CONETRACE names the binary.
set -euo pipefail
scene="${1:?usage: check_scaling.sh SCENE [options...]}"
shift
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for tasks in 1 2 3 4; do
  start=$(date +%s.%N)
  line=$(OUTDIR="$work/$tasks" "$here/submit.sh" "$scene" "$tasks" "$@")
  merge_job="${line##* }"
  while true; do
    state=$(scontrol show job "$merge_job" | grep -o 'JobState=[A-Z_]*' | cut -d= -f2)
    case "$state" in
      PENDING|RUNNING|CONFIGURING|COMPLETING) sleep 0.1 ;;
      *) break ;;
    esac
  done
  end=$(date +%s.%N)
  [ "$state" = COMPLETED ] || { echo "tasks $tasks: merge job $merge_job ended $state" >&2; exit 1; }
  echo "tasks $tasks: wall $(awk "BEGIN { printf \"%.2f\", $end - $start }") s"
done
