#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Scaling of a sharded Monte Carlo study (docs/results/cluster.md): the study cut into N = 1, 2
# and 4 shards run side by side on this machine, one thread each, then merged; per N, RUNS times,
# the median wall time (first shard started to merge done), total CPU (every shard and the
# merge), the slowest shard's wall and CPU and the merge's. Checks that every merge is byte
# identical to the single-process study. Then the per-shard overhead and the wall time predicted
# on P cores, T(P) = W / P + s + m: W the CPU of the trials, s a shard's fixed cost (start-up,
# set-up, writing its records: a shard holding one trial), m the merge's wall.
#
#   bench/cluster_scaling.sh [RUNS] [-- lidarcal montecarlo options]
#   default: 3 runs of --study fig9 --trials 50 --joint-trials 10 (the paper's 1000 / 200 over 20)
#
# Needs build/pipeline/lidarcal and GNU time (/usr/bin/time, Debian package `time`).
set -euo pipefail
cd "$(dirname "$0")/.."
L=$(readlink -f build/pipeline/lidarcal)
RUNS=3
if [[ ${1:-} =~ ^[1-9][0-9]*$ ]]; then RUNS=$1; shift; fi
if [ "${1:-}" = "--" ]; then shift; fi
STUDY=("$@")
[ ${#STUDY[@]} -gt 0 ] || STUDY=(--study fig9 --trials 50 --joint-trials 10)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.3f", b - a}'; }
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
# "wall user sys" of one timed command, written by GNU time to FILE.
timed() { local file=$1; shift; /usr/bin/time -f "%e %U %S" -o "$file" "$@" > /dev/null; }

"$L" -q montecarlo "${STUDY[@]}" --threads 1 --out "$W/reference"

# One run of N shards side by side and the merge: prints "wall cpu slowest_wall slowest_cpu merge_wall merge_cpu".
run_once() {
  local n=$1 dir=$W/n$1 start end
  rm -rf "$dir"
  mkdir -p "$dir"
  start=$(now)
  for k in $(seq 1 "$n"); do
    timed "$dir/time-$k" "$L" -q montecarlo "${STUDY[@]}" --threads 1 --shard "$k/$n" --out "$dir/shard-$k" &
  done
  wait
  local dirs=()
  for k in $(seq 1 "$n"); do dirs+=("$dir/shard-$k"); done
  timed "$dir/time-merge" "$L" -q montecarlo-merge "${dirs[@]}" --out "$dir/merged"
  end=$(now)
  diff -r "$W/reference" "$dir/merged" > /dev/null || { echo "cluster_scaling: $n shards: merge differs from the single process" >&2; exit 1; }
  cat "$dir"/time-[0-9]* | awk -v wall="$(elapsed "$start" "$end")" -v merge="$(cat "$dir/time-merge")" '
    {cpu += $2 + $3; if ($1 > sw) {sw = $1; sc = $2 + $3}}
    END {split(merge, m, " "); printf "%.2f %.2f %.2f %.2f %.2f %.2f\n", wall, cpu + m[2] + m[3], sw, sc, m[1], m[2] + m[3]}'
}

echo "| shards | wall [s] | CPU, all processes [s] | slowest shard wall / CPU [s] | merge wall / CPU [s] |"
echo "|---|---|---|---|---|"
for n in 1 2 4; do
  for r in $(seq 1 "$RUNS"); do run_once "$n"; done > "$W/runs-$n"
  col() { awk -v c="$1" '{print $c}' "$W/runs-$n" | median; }
  echo "| $n | $(col 1) | $(col 2) | $(col 3) / $(col 4) | $(col 5) / $(col 6) |"
done

# A shard's fixed cost: slice 1 of 100000, which holds at most one trial; median of RUNS.
for r in $(seq 1 "$RUNS"); do
  timed "$W/fixed" "$L" -q montecarlo "${STUDY[@]}" --threads 1 --shard 1/100000 --out "$W/fixed-$r"
  cat "$W/fixed"
done > "$W/fixed-runs"
s=$(awk '{print $1}' "$W/fixed-runs" | median)
m=$(awk '{print $5}' "$W/runs-1" | median)
work=$(awk '{print $4 - $6}' "$W/runs-1" | median)  # the single shard's CPU less the merge's: the trials (and one s)
echo
echo "trial work W = $work CPU s; fixed cost of a shard s = $s s; merge m = $m s"
echo "| cores P | predicted wall W/P + s + m [s] | overhead (s + m) / (W/P) |"
echo "|---|---|---|"
for p in 16 64 256; do
  awk -v w="$work" -v s="$s" -v m="$m" -v p="$p" 'BEGIN {printf "| %d | %.2f | %.0f %% |\n", p, w / p + s + m, 100 * (s + m) / (w / p)}'
done
