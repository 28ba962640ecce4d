#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The numbers of docs/results/watch.md: the field watcher on simulated drives (build/bench/
# watch_drives) and on the shared recordings (lidarcal watch). About four hours on 2 cores; each
# part writes OUT/NAME.txt.
#
#   bench/watch_results.sh [OUT]        (default /tmp/lidarcal-watch-results)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-/tmp/lidarcal-watch-results}
mkdir -p "$OUT"
W=build/bench/watch_drives
L=build/pipeline/lidarcal
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}
scene() { echo "data/scenes/driving_$1.json"; }

# 1. False alarms on clean drives: 200 drives of 30 m per scene at 20 per km, where the rate is
#    measurable (each check's test spends 20 x its exposure), and 20 drives at the default rate.
for s in large_poles small_poles; do
  $W --scene "$(scene $s)" --seeds 200 --first-seed 1000 --scans 1000 --rate 20 > "$OUT/clean_$s.txt"
  $W --scene "$(scene $s)" --seeds 20 --first-seed 3000 --scans 1500 > "$OUT/clean_default_$s.txt"
done
# 2. Changes injected at scan 900 of 1500 (27 m into the drive), 20 drives each.
for s in small_poles large_poles; do
  for c in 10 20 30 0.3% 1%; do
    $W --scene "$(scene $s)" --seeds 20 --first-seed 2000 --scans 1500 --change "$c@900" \
      > "$OUT/change_${s}_${c%\%}.txt"
  done
done
# 3. Learn mode after a 20 mm change, against `calibrate` on the scans after the change.
$W --scene "$(scene large_poles)" --seeds 10 --first-seed 2000 --scans 2000 --change 20@900 \
  --learn --work "$OUT/learn_work" > "$OUT/learn_large_poles.txt"
# Clean drives in learn mode at 1000 false alarms per km, so that nearly every drive raises one
# and refits: how many of those false alarms lead to a switch (at most 1 % should). Thin poles:
# 400 drives (about 2 hours on one core).
$W --scene "$(scene small_poles)" --seeds 400 --first-seed 3000 --scans 1500 --learn --rate 1000 \
  > "$OUT/learn_clean_small_poles.txt"
$W --scene "$(scene large_poles)" --seeds 20 --first-seed 3000 --scans 1500 --learn --rate 1000 \
  > "$OUT/learn_clean_large_poles.txt"
# The baseline's absolute test without the check fit's own bias taken out, for comparison
# (drives that end after it).
for s in small_poles large_poles; do
  $W --scene "$(scene $s)" --seeds 200 --first-seed 1000 --scans 560 --rate 20 \
    --bias-replicas 0 > "$OUT/clean_no_replicas_$s.txt"
done
# The change test and the baseline's absolute test on draws of their own model: rejections per
# level by record length, spread and scale (about a minute each).
build/bench/change_test_level > "$OUT/change_test_level.txt"
build/bench/change_test_level --absolute > "$OUT/absolute_test_level.txt"
# 4. Memory over a 100,000-scan drive.
$W --scene "$(scene large_poles)" --seeds 1 --first-seed 4000 --scans 100000 --rss-every 10000 \
  > "$OUT/memory.txt"
# 5. The shared recordings with motion (YDLIDAR X4 logs, CARMEN logs), learn mode without a
#    model: what a replay can check there.
if [ -d "$DATA" ]; then
  for f in "$DATA"/ydlidar_x4/*.dat "$DATA"/carmen/*.log.gz; do
    n=$(basename "$f"); n=${n%%.*}
    echo "== $n" >> "$OUT/recordings.txt"
    $L watch "$f" --mode learn -o "$OUT/rec_$n" --overwrite -q >> "$OUT/recordings.txt" 2>&1 \
      || echo "exit $?" >> "$OUT/recordings.txt"
  done
fi
echo "written to $OUT"
