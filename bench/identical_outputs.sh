#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Byte-identical outputs before and after a change that must not change behaviour
# (docs/results/test-suite.md): runs one fixed set of commands with a given lidarcal binary and
# prints a SHA-256 per output file; run it with the binary before and after and compare.
#
#   bench/identical_outputs.sh [--quick] [--keep DIR] [LIDARCAL] > sums.txt
#   bench/identical_outputs.sh --compare BEFORE_BINARY AFTER_BINARY [--quick]
#
# --compare keeps both output trees and compares them with bench/compare_outputs.py: every file
# byte-identical, except covariance-derived JSON numbers equal to 10 significant digits (the last digits of a
# Ceres covariance follow the memory addresses of the parameter blocks; the tool lists them).
#
# The set: the bundled example through `run`; each scene of data/scenes/ (seed 1) through
# simulate, detect, calibrate (joint and closed form), correct and diagnose; the noise
# experiments through noise-consistency (ml, and kl-hill on the short scenes); every shared
# recording (../shared/data, skipped when absent) through import, calibrate and correct; the
# Hokuyo range sweep through calibrate --reference. --quick keeps the example, three scenes and
# two recordings (a few minutes instead of tens). Paths inside outputs are made relative to the
# work directory, so two runs in different directories compare.
set -uo pipefail
cd "$(dirname "$0")/.."

quick=0
if [ "${1:-}" = "--compare" ]; then
  before=$2 after=$3
  [ "${4:-}" = "--quick" ] && quick=1
  q=(); [ $quick = 1 ] && q=(--quick)
  k=$(mktemp -d)
  trap 'rm -rf "$k"' EXIT
  "$0" "${q[@]}" --keep "$k/before" "$before" > "$k/before.sums"
  "$0" "${q[@]}" --keep "$k/after" "$after" > "$k/after.sums"
  # Exit codes of every step must match exactly.
  if ! diff -u <(grep '^exit ' "$k/before.sums") <(grep '^exit ' "$k/after.sums"); then
    echo "exit codes differ (lines above: - before, + after)" >&2
    exit 1
  fi
  python3 "$(dirname "$0")/compare_outputs.py" "$k/before" "$k/after"
  exit $?
fi
[ "${1:-}" = "--quick" ] && { quick=1; shift; }
keep=
[ "${1:-}" = "--keep" ] && { keep=$2; shift 2; }
L=$(readlink -f "${1:-build/pipeline/lidarcal}")
[ -x "$L" ] || { echo "identical_outputs: $L is not an executable" >&2; exit 2; }
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}
if [ -n "$keep" ]; then
  mkdir -p "$keep" && W=$(readlink -f "$keep")
else
  W=$(mktemp -d)
  trap 'rm -rf "$W"' EXIT
fi

# Runs a command; records its exit code (a changed refusal is a changed behaviour too).
step() {  # name, args...
  local name=$1; shift
  "$L" "$@" > "$W/$name.stdout" 2> /dev/null
  echo "exit $? $name"
}

step run-example run -q -o "$W/example"
scenes=(data/scenes/*.json)
[ $quick = 1 ] && scenes=(data/scenes/paper_field.json data/scenes/field_clutter.json data/scenes/field_small_poles.json)
for s in "${scenes[@]}"; do
  n=$(basename "$s" .json)
  step "simulate-$n" simulate -q --scene "$s" -o "$W/$n" --seed 1
  [ -d "$W/$n/scans" ] || continue
  step "detect-$n" detect -q "$W/$n/scans" -o "$W/$n-detect"
  step "calibrate-$n" calibrate -q "$W/$n/scans" -o "$W/$n-joint.json"
  step "closed-form-$n" calibrate -q "$W/$n/scans" --method closed-form -o "$W/$n-closed.json"
  [ -f "$W/$n-joint.json" ] && step "correct-$n" correct -q "$W/$n/scans" --model "$W/$n-joint.json" -o "$W/$n-corrected"
  [ $quick = 1 ] || step "diagnose-$n" diagnose -q "$W/$n/scans" -o "$W/$n-diagnose" --seed 1
done
for s in data/scenes/noise_*.json; do
  n=$(basename "$s" .json)
  [ -f "$W/$n/observations.csv" ] || continue
  step "noise-ml-$n" noise-consistency -q --observations "$W/$n/observations.csv" --odometry "$W/$n/odometry.csv" \
    --method ml -o "$W/$n-ml.json"
done

if [ -d "$DATA" ]; then
  recs=("rplidar:$DATA/rplidar_a2_room/rplidar_1.bag" "intel:$DATA/carmen/intel-corrected.log.gz")
  [ $quick = 1 ] || recs+=("yd1:$DATA/ydlidar_x4/2019-05-03-19-38-28.dat" "yd2:$DATA/ydlidar_x4/2019-05-03-19-39-14.dat"
                           "yd3:$DATA/ydlidar_x4/2019-05-03-19-42-50.dat" "yd4:$DATA/ydlidar_x4/2019-05-03-19-44-15.dat"
                           "csail:$DATA/carmen/csail-corrected.log.gz" "campus:$DATA/carmen/freiburg-campus-corrected.log.gz")
  for r in "${recs[@]}"; do
    n=${r%%:*} f=${r#*:}
    [ -f "$f" ] || continue
    step "import-$n" import -q "$f" -o "$W/rec-$n"
    step "calibrate-rec-$n" calibrate -q "$W/rec-$n" -o "$W/rec-$n.json"
    [ -f "$W/rec-$n.json" ] && step "correct-rec-$n" correct -q "$W/rec-$n" --model "$W/rec-$n.json" -o "$W/rec-$n-corrected"
  done
  sweep=$DATA/hokuyo_ust30lx_reflector/range_sweep
  if [ -f "$sweep/labels.csv" ] && [ $quick = 0 ]; then
    mapfile -t rows < <(tail -n +2 "$sweep/labels.csv")
    bags=() entries=()
    for k in "${!rows[@]}"; do
      bags+=("$sweep/${rows[$k]%%,*}")
      entries+=("{\"stop\": $k, \"distance_m\": ${rows[$k]#*,}}")
    done
    (IFS=,; echo "{\"format\": \"lidarcal-reference/1\", \"distances\": [${entries[*]}]}") > "$W/sweep-ref.json"
    step import-sweep import -q "${bags[@]}" --stop-per-input --every 4 -o "$W/sweep"
    step calibrate-sweep calibrate -q "$W/sweep" --reference "$W/sweep-ref.json" --radius 0.045 -o "$W/sweep.json"
  fi
fi

# One checksum per output file, with the work directory's path replaced where outputs echo it.
cd "$W"
find . -type f | LC_ALL=C sort | while read -r f; do
  printf '%s  %s\n' "$(sed "s|$W|WORK|g" "$f" | sha256sum | cut -d' ' -f1)" "$f"
done
