#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Speed of lidarcal's main commands against the I/O floor (docs/results/speed.md),
# in one run: on a simulated sequence of 20 stops x 50 scans (1000 scans, 5 poles) and on the
# CARMEN Intel log (910 scans, a pose per scan; skipped when ../shared/data is absent), the
# median wall time and peak memory of `run`, `detect` and `calibrate` (farm-bench, RUNS runs
# each) and the ratio of each to the floor (pcd_floor: read and write the same PCD files with
# PCL), each pair timed in turn (farm-bench --vs) so that the ratio holds on a busy machine;
# then calibrate against detect on each sequence, as a pair too.
#
#   bench/speed.sh [RUNS] [DIR] (default 3 runs, work files under DIR (default: mktemp's, on disk);
#                               needs build/pipeline/lidarcal and build/bench/pcd_floor)
#
# DIR on tmpfs (/dev/shm) measures the computation alone; on a disk the file system's cost of
# creating a thousand files in a fresh directory (which every command and the floor pay) varies
# from run to run by a factor of 3 on ext4 here, and dominates both.
set -euo pipefail
cd "$(dirname "$0")/.."
L=$(readlink -f build/pipeline/lidarcal)
F=$(readlink -f build/bench/pcd_floor)
RUNS=${1:-3}
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}
if [ -n "${2:-}" ]; then W=$(mktemp -d -p "$2"); else W=$(mktemp -d); fi
trap 'rm -rf "$W"' EXIT

"$L" simulate -q --scene data/scenes/paper_field.json --stops 20 --scans-per-stop 50 --seed 3 -o "$W/s1000"
sets=("1000 scans (20 stops x 50):$W/s1000/scans")
if [ -f "$DATA/carmen/intel-corrected.log.gz" ]; then
  "$L" import -q "$DATA/carmen/intel-corrected.log.gz" -o "$W/intel" > /dev/null
  sets+=("CARMEN Intel (910 poses):$W/intel")
fi

# median of a farm-bench row: "A wall s  min median max"
median() { awk -v row="$1" '$0 ~ "^"row" " {print $(NF-1)}' "$2"; }

echo "| sequence | command | wall [s] | peak [MiB] | floor wall [s] | floor peak [MiB] | wall / floor |"
echo "|---|---|---|---|---|---|---|"
for s in "${sets[@]}"; do
  name=${s%%:*} seq=${s#*:}
  for cmd in run detect calibrate; do
    case $cmd in
      run) a="$L run -q --no-truth $seq -o $W/out --overwrite" ;;
      detect) a="$L detect -q $seq -o $W/out --overwrite" ;;
      calibrate) a="$L calibrate -q $seq -o $W/model.json --overwrite" ;;
    esac
    # shellcheck disable=SC2086
    farm-bench -n "$RUNS" --timeout 3000 --vs "$F $seq $W/floor" -- $a > "$W/fb.txt" 2>&1 || true
    echo "| $name | $cmd | $(median 'A wall s' "$W/fb.txt") | $(median 'A peak MiB' "$W/fb.txt") |" \
         "$(median 'B wall s' "$W/fb.txt") | $(median 'B peak MiB' "$W/fb.txt") | $(median 'A/B wall' "$W/fb.txt") |"
  done
done
# The target on a long log compares calibrate with detect on the same sequence: timed as a pair.
echo
echo "| sequence | calibrate wall [s] | detect wall [s] | calibrate / detect |"
echo "|---|---|---|---|"
for s in "${sets[@]}"; do
  name=${s%%:*} seq=${s#*:}
  # shellcheck disable=SC2086
  farm-bench -n "$RUNS" --timeout 3000 --vs "$L detect -q $seq -o $W/out --overwrite" -- \
    $L calibrate -q $seq -o $W/model.json --overwrite > "$W/fb.txt" 2>&1 || true
  echo "| $name | $(median 'A wall s' "$W/fb.txt") | $(median 'B wall s' "$W/fb.txt") | $(median 'A/B wall' "$W/fb.txt") |"
done
