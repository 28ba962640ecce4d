#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Real data with tape-measured truth (docs/results/real-sensors.md):
# the 42 bags of ../shared/data/hokuyo_ust30lx_reflector/range_sweep, sorted by distance, split
# alternately into a fit half (1st, 3rd, ...) and a test half (2nd, 4th, ...). Calibrate on the
# fit half against its tape distances, then measure the reflector's centre distance in the test
# half, raw and corrected, and draw both halves against the tape.
#
#   bench/hokuyo_reference.sh [WORK_DIR]      (default /tmp/lidarcal-hokuyo; writes the tables
#                                              on stdout and WORK_DIR/hokuyo_reference.png)
set -euo pipefail
cd "$(dirname "$0")/.."
LIDARCAL=${LIDARCAL:-build/pipeline/lidarcal}
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}/hokuyo_ust30lx_reflector/range_sweep
WORK=${1:-/tmp/lidarcal-hokuyo}
RADIUS=0.045   # the reflector's radius (../shared/data/README.md)
[ -f "$DATA/labels.csv" ] || { echo "hokuyo_reference: $DATA is absent" >&2; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK"

# labels.csv is sorted by distance; odd rows fit, even rows test.
tail -n +2 "$DATA/labels.csv" | awk -F, 'NR % 2 == 1' > "$WORK/fit.csv"
tail -n +2 "$DATA/labels.csv" | awk -F, 'NR % 2 == 0' > "$WORK/test.csv"
for half in fit test; do
  bags=$(awk -F, -v d="$DATA" '{printf "%s/%s ", d, $1}' "$WORK/$half.csv")
  awk -F, 'BEGIN {printf "{\"format\": \"lidarcal-reference/1\", \"distances\": ["}
           {printf "%s{\"stop\": %d, \"target\": \"landmark\", \"distance_m\": %s}", (NR > 1 ? ", " : ""), NR - 1, $2}
           END {print "]}"}' "$WORK/$half.csv" > "$WORK/$half-ref.json"
  # shellcheck disable=SC2086
  "$LIDARCAL" import -q --from rosbag1 $bags --stop-per-input -o "$WORK/$half" > /dev/null
done
"$LIDARCAL" calibrate -q "$WORK/fit" --reference "$WORK/fit-ref.json" --radius $RADIUS -o "$WORK/model.json" \
  > "$WORK/calibrate.txt"
echo "## Calibration on the fit half"
echo
cat "$WORK/calibrate.txt"
for half in fit test; do
  echo
  echo "## $half half: reflector centre distance measured in the scans vs the tape"
  echo
  "$LIDARCAL" evaluate -q "$WORK/$half" --reference "$WORK/$half-ref.json" --radius $RADIUS \
    --model "$WORK/model.json" -o "$WORK/$half-eval.json"
  # tape, raw error, corrected error (mm) for the plot
  python3 - "$WORK/$half-eval.json" > "$WORK/$half.dat" <<'PY' 2>/dev/null || \
    jq -r '[.raw.entries, .corrected.entries] | transpose[] | "\(.[0].reference_m) \(1000*.[0].error_m) \(1000*.[1].error_m)"' "$WORK/$half-eval.json" > "$WORK/$half.dat"
import json, sys
e = json.load(open(sys.argv[1]))
for r, c in zip(e["raw"]["entries"], e["corrected"]["entries"]):
    print(r["reference_m"], 1000 * r["error_m"], 1000 * c["error_m"])
PY
done
cat > "$WORK/plot.gp" <<'GP'
set terminal pngcairo size 900,560 font "DejaVu Sans,11"
set output "hokuyo_reference.png"
set title "Hokuyo UST-30LX: reflector centre distance from the scans minus the tape measure"
set xlabel "tape-measured centre distance [m]"
set ylabel "measured - tape [mm]"
set grid
set key outside bottom center horizontal
plot 0 with lines dt 2 lc rgb "black" notitle, \
     "fit.dat" using 1:2 with linespoints pt 6 lc rgb "#cc3311" title "raw, fit half", \
     "fit.dat" using 1:3 with linespoints pt 7 lc rgb "#009944" title "corrected, fit half", \
     "test.dat" using 1:2 with points pt 4 ps 1.2 lc rgb "#ee7733" title "raw, test half (not fitted)", \
     "test.dat" using 1:3 with points pt 5 ps 1.2 lc rgb "#0077bb" title "corrected, test half (not fitted)"
GP
(cd "$WORK" && gnuplot plot.gp)
echo
echo "plot: $WORK/hokuyo_reference.png"
