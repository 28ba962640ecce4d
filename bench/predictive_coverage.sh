#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The predictive intervals of `calibrate --reference` on real recordings the fit never saw
# (docs/results/real-sensors.md, "Predictive intervals on recordings the fit never saw"):
#   - the Hokuyo UST-30LX range sweep of ../shared/data (42 bags, sorted by distance) split into
#     interleaved halves, fitted on one and checked on the other, both ways round;
#   - the README's tape-measure walkthrough: rows 2 12 22 of labels.csv against rows 7 17 27,
#     both ways round;
#   - the four reference scenes (a full room, the reflector at 0.505-1.111 m), checked with the
#     model fitted on the whole sweep;
#   - the whole sweep fitted without one recording and checked on it, every recording in turn, and
#     fitted on every third recording (14) and checked on the other 28, each third in turn;
#   - one tape distance of the whole sweep read 5-30 mm long, in turn at six entries: whether the
#     fit's warnings name it;
# each with the tape distances stated exact (REF.json sigma_m 0) and with a 2 mm tape error
# (sigma_m 0.002). `evaluate --reference --model` counts the entries inside each interval.
#
#   bench/predictive_coverage.sh [WORK_DIR]      (default /tmp/lidarcal-predictive; about 6 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
LIDARCAL=${LIDARCAL:-build/pipeline/lidarcal}
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}/hokuyo_ust30lx_reflector
SWEEP=$DATA/range_sweep
WORK=${1:-/tmp/lidarcal-predictive}
RADIUS=0.045   # the reflector's radius (../shared/data/README.md)
[ -f "$SWEEP/labels.csv" ] || { echo "predictive_coverage: $SWEEP is absent" >&2; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK"

# set NAME ROWS...: the bags of those data rows of labels.csv (1 = the first bag) as one stop each,
# and their REF.json with sigma_m 0 and 0.002.
set_of() {
  local name=$1; shift
  for r in "$@"; do sed -n "$((r + 1))p" "$SWEEP/labels.csv"; done > "$WORK/$name.csv"
  # shellcheck disable=SC2046
  "$LIDARCAL" import -q --from rosbag1 $(awk -F, -v d="$SWEEP" '{printf "%s/%s ", d, $1}' "$WORK/$name.csv") \
    --stop-per-input -o "$WORK/$name" > /dev/null
  for s in 0 0.002; do
    awk -F, -v s=$s 'BEGIN {printf "{\"format\": \"lidarcal-reference/1\", \"distances\": ["}
      {printf "%s{\"stop\": %d, \"target\": \"landmark\", \"distance_m\": %s, \"sigma_m\": %s}", (NR > 1 ? ", " : ""), NR - 1, $2, s}
      END {print "]}"}' "$WORK/$name.csv" > "$WORK/$name-ref-$s.json"
  done
}
n=$(($(wc -l < "$SWEEP/labels.csv") - 1))
set_of odd $(seq 1 2 "$n")      # 0.129, 0.228, ... (the 1st, 3rd, ... by distance)
set_of even $(seq 2 2 "$n")     # 0.178, 0.280, ...
set_of all $(seq 1 "$n")
set_of walk_fit 1 11 21         # the README's walkthrough: rows 2 12 22 of labels.csv
set_of walk_check 6 16 26       # rows 7 17 27
# The reference scenes: the same sensor on another topic (/scan, named as the sweep's topic so
# that the model applies) with other range limits (evaluate --force).
SCENES=$DATA/reference_scenes
"$LIDARCAL" import -q --from rosbag1 "$SCENES"/ref_505.bag "$SCENES"/ref_707.bag "$SCENES"/ref_909.bag "$SCENES"/ref_1111.bag \
  --stop-per-input --sensor-name "$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["sensor_name"])' \
  "$WORK/all/sequence.json")" -o "$WORK/scenes" > /dev/null
for s in 0 0.002; do
  echo "{\"format\": \"lidarcal-reference/1\", \"distances\": [$(for k in 0 1 2 3; do
    d=(0.505 0.707 0.909 1.111); printf '%s{"stop": %d, "distance_m": %s, "bearing_rad": 1.5708, "sigma_m": %s}' \
      "$([ $k -gt 0 ] && echo ', ')" $k "${d[$k]}" $s; done)]}" > "$WORK/scenes-ref-$s.json"
done

# check FIT CHECK SIGMA [--force]: calibrate on FIT, evaluate on CHECK; one JSON line of counts.
check() {
  local fit=$1 check=$2 s=$3; shift 3
  [ -f "$WORK/model-$fit-$s.json" ] || "$LIDARCAL" calibrate -q "$WORK/$fit" --reference "$WORK/$fit-ref-$s.json" \
    --radius $RADIUS -o "$WORK/model-$fit-$s.json" > /dev/null
  "$LIDARCAL" evaluate -q "$WORK/$check" --reference "$WORK/$check-ref-$s.json" --radius $RADIUS \
    --model "$WORK/model-$fit-$s.json" -o "$WORK/eval-$fit-$check-$s.json" "$@" > "$WORK/eval-$fit-$check-$s.txt" 2>&1
  python3 - "$WORK/eval-$fit-$check-$s.json" "$fit" "$check" "$s" <<'PY'
import json, math, sys
whole = json.load(open(sys.argv[1]))
e, q = whole["predictive"], whole["corrected"]["mse_ratio"]
rows = [x for x in e["entries"] if x["checked"]]
n = len(rows)
rms = 1000 * math.sqrt(sum(x["error_m"] ** 2 for x in rows) / n) if n else float("nan")
tau = e["discrepancy"]["sigma_m"]
pct = lambda k: f"{k}/{n} = {100 * k / n:.0f} %" if n else "-"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {1000 * float(sys.argv[4]):.0f} mm | {n} | "
      f"{'-' if tau is None else f'{1000 * tau:.1f}'} ({e['discrepancy']['dof']}) | {rms:.1f} mm | "
      f"{pct(e['inside_68'])} | {pct(e['inside_95'])} | {pct(e['inside_curve_95'])} | "
      + (f"{q['ratio']:.2f} ({q['low_95']:.2f}-{q['high_95']:.2f}) |" if q["low_95"] is not None else "- |"))
PY
}

echo "| fitted on | checked on | stated tape error | entries checked | discrepancy [mm] (dof) | RMS corrected - tape |" \
     "inside the 68 % predictive interval | inside the 95 % predictive interval | inside the curve's 95 % interval |" \
     "MSE ratio raw / corrected (95 % interval) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for s in 0.002 0; do
  check odd even $s
  check even odd $s
  check walk_fit walk_check $s
  check walk_check walk_fit $s
  check all scenes $s --force
done

# folds S K ON NAME: the whole sweep split by recording index modulo K; for each residue r the
# model is fitted on the recordings with index % K == r (ON=1) or != r (ON=0) and checked on the
# others. One row of counts pooled over the folds, with the held-out errors over their interval's
# standard error (z).
folds() {
  local s=$1 k=$2 on=$3 name=$4 r
  for ((r = 0; r < k; r++)); do
    python3 - "$WORK/all-ref-$s.json" "$k" "$r" "$on" "$WORK/fold-fit.json" "$WORK/fold-check.json" <<'PY'
import json, sys
ref = json.load(open(sys.argv[1])); k, r, on = (int(v) for v in sys.argv[2:5])
fit = lambda d: (d["stop"] % k == r) == bool(on)
for path, keep in ((sys.argv[5], fit), (sys.argv[6], lambda d: not fit(d))):
    json.dump(dict(ref, distances=[d for d in ref["distances"] if keep(d)]), open(path, "w"))
PY
    "$LIDARCAL" calibrate -q "$WORK/all" --reference "$WORK/fold-fit.json" --radius $RADIUS --overwrite \
      -o "$WORK/fold-model.json" > /dev/null 2>&1
    "$LIDARCAL" evaluate -q "$WORK/all" --reference "$WORK/fold-check.json" --radius $RADIUS \
      --model "$WORK/fold-model.json" -o "$WORK/fold-$name-$s-$r.json" > /dev/null 2>&1
    printf '\r%s (tape %s): %d of %d' "$name" "$s" $((r + 1)) "$k" >&2
  done
  echo >&2
  python3 - "$WORK" "$s" "$k" "$name" "$(pwd)/bench" <<'PY'
import json, math, sys
sys.path.insert(0, sys.argv[5])
from mse_ratio import text
work, s, k, name = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
rows, raw, cor = [], [], []
for r in range(k):
    e = json.load(open(f"{work}/fold-{name}-{s}-{r}.json"))
    rows += [x for x in e["predictive"]["entries"] if x["checked"]]
    for a, b in zip(e["raw"]["entries"], e["corrected"]["entries"]):
        if a["status"] == "ok" and b["status"] == "ok" and a["in_fitted_range"]:
            raw.append(a["error_m"]), cor.append(b["error_m"])
m = len(rows)
z = [x["error_m"] / x["interval_se_m"] for x in rows]
pct = lambda key: f"{sum(x[key] for x in rows)}/{m} = {100 * sum(x[key] for x in rows) / m:.0f} %"
print(f"| {name} | {1000 * float(s):.0f} mm | {m} | {math.sqrt(sum(v * v for v in z) / m):.2f} | "
      f"{max(abs(v) for v in z):.2f} | {1000 * math.sqrt(sum(x['error_m'] ** 2 for x in rows) / m):.1f} mm | "
      f"{pct('inside_68')} | {pct('inside_95')} | {pct('inside_curve_95')} | {text(raw, cor)} |")
PY
}
echo
echo "Folds of the whole sweep: fitted on all but one recording, or on every third, and checked on the rest"
echo
echo "| folds | stated tape error | entries checked | RMS z | largest abs z | RMS corrected - tape |" \
     "inside the 68 % predictive interval | inside the 95 % predictive interval | inside the curve's 95 % interval |" \
     "MSE ratio raw / corrected, pooled (95 % interval) |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for s in 0.002 0; do
  folds $s "$n" 0 "leave one out"
  folds $s 3 1 "fitted on a third"
done

# A misread tape: one entry of the whole sweep (2 mm stated tape error) read long by E mm, at
# six entries spread over the range in turn; which entries the fit's warnings name
# (calibration/discrepancy.hpp, deletedResiduals) and the model discrepancy, read back from model.json.
echo
echo "One tape distance read long: the entries calibrate --reference names as disagreeing with the others"
echo
echo "| tape read long by | fits | the misread entry named, alone | another entry named | model discrepancy [mm], median |"
echo "|---|---|---|---|---|"
for e in 0 5 10 15 20 30; do
  for k in 3 10 17 24 31 38; do
    python3 - "$WORK/all-ref-0.002.json" "$k" "$e" "$WORK/misread.json" <<'PY'
import json, sys
ref = json.load(open(sys.argv[1])); k, e = int(sys.argv[2]), float(sys.argv[3])
ref["distances"][k]["distance_m"] += e / 1000
json.dump(ref, open(sys.argv[4], "w"))
PY
    "$LIDARCAL" calibrate -q "$WORK/all" --reference "$WORK/misread.json" --radius $RADIUS --overwrite \
      -o "$WORK/misread-$e-$k.json" > /dev/null 2>&1
    [ "$e" = 0 ] && break  # the sweep as taped: one fit
  done
  python3 - "$WORK" "$e" <<'PY'
import glob, json, re, statistics, sys
work, e = sys.argv[1], sys.argv[2]
fits = alone = other = 0
tau = []
for path in sorted(glob.glob(f"{work}/misread-{e}-*.json")):
    k = int(re.search(r"-(\d+)\.json$", path).group(1))
    m = json.load(open(path))
    named = {int(re.match(r"distances\[(\d+)\]", w).group(1)) for w in m.get("warnings", []) if "disagrees" in w}
    fits += 1
    alone += named == {k} and e != "0"
    other += bool(named - {k}) if e != "0" else bool(named)
    tau.append(1000 * m["discrepancy"]["sigma_m"])
print(f"| {e} mm | {fits} | {alone if e != '0' else '-'} | {other} | {statistics.median(tau):.1f} |")
PY
done
echo
echo "per-entry tables: $WORK/eval-*.txt"
