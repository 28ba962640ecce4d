#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Surveyed geometry against an odometry scale error (docs/results/survey.md): the paper's field
# with every step 6 % longer than the odometry says, the pole radius unknown (removed from
# sequence.json), SEEDS seeds. Each seed is calibrated four ways: self-calibration, with the true
# pole centres as a survey (REF.json `landmarks`, no radius), with the true stop poses (REF.json
# `stops`), and with tape distances (true centre distance + 2 mm noise) to the poles within 4 m at
# the first and the last stop only, which join the self-calibration (--reference-fit auto: two
# stops are too few to fit alone). Prints the error of f(d) - d against the truth at 1, 2 and 3 m
# (median and largest over the seeds, mm) and the median standard error the model reports, and in
# how many seeds the truth lies inside the model's 95 % interval (f(d) +- 1.96 SE).
#
#   bench/survey.sh [SEEDS]     (default 10; needs build/pipeline/lidarcal)
set -euo pipefail
cd "$(dirname "$0")/.."
L=$(readlink -f build/pipeline/lidarcal)
SEEDS=${1:-10}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
python3 - "$W/scene.json" <<'PY'
import json, sys
s = json.load(open("data/scenes/paper_field.json"))
s["path"]["step_error_fraction"] = 0.06
json.dump(s, open(sys.argv[1], "w"))
PY
for seed in $(seq 1 "$SEEDS"); do
  d=$W/$seed
  "$L" simulate -q --scene "$W/scene.json" --seed "$seed" -o "$d"
  python3 - "$d" <<'PY'
import json, sys
d = sys.argv[1]
meta = json.load(open(d + "/scans/sequence.json")); meta.pop("landmark_radius_m", None)
json.dump(meta, open(d + "/scans/sequence.json", "w"))
t = json.load(open(d + "/truth.json"))
json.dump({"format": "lidarcal-reference/1",
           "landmarks": [{"x_m": l["x_m"], "y_m": l["y_m"]} for l in t["scene"]["landmarks"]]}, open(d + "/lm.json", "w"))
json.dump({"format": "lidarcal-reference/1",
           "stops": [{"stop": k, "x_m": s["actual"]["x_m"], "y_m": s["actual"]["y_m"], "yaw_rad": s["actual"]["yaw_rad"]}
                     for k, s in enumerate(t["stops"])]}, open(d + "/st.json", "w"))
import math, random
rng = random.Random(d)
tape = []
for k in (0, len(t["stops"]) - 1):
    p = t["stops"][k]["actual"]
    for l in t["scene"]["landmarks"]:
        dist = math.hypot(l["x_m"] - p["x_m"], l["y_m"] - p["y_m"])
        if dist > 4.0: continue
        bearing = math.remainder(math.atan2(l["y_m"] - p["y_m"], l["x_m"] - p["x_m"]) - p["yaw_rad"], 2 * math.pi)
        tape.append({"stop": k, "target": "landmark", "distance_m": dist + rng.gauss(0.0, 0.002), "bearing_rad": bearing})
json.dump({"format": "lidarcal-reference/1", "distances": tape}, open(d + "/tape.json", "w"))
PY
  "$L" calibrate -q "$d/scans" -o "$d/self.json" > /dev/null
  "$L" calibrate -q "$d/scans" --reference "$d/lm.json" -o "$d/lm.json.model" > /dev/null
  "$L" calibrate -q "$d/scans" --reference "$d/st.json" -o "$d/st.json.model" > /dev/null
  "$L" calibrate -q "$d/scans" --reference "$d/tape.json" -o "$d/tape.json.model" > /dev/null
done
python3 - "$W" "$SEEDS" <<'PY'
import json, math, sys, statistics as st
w, seeds = sys.argv[1], int(sys.argv[2])
def f(a, d): return sum(c * d ** i for i, c in enumerate(a))
def se(m, d):
    a = m["bias"]["alpha"]; n = len(a); c = m.get("alpha_covariance") or []
    if len(c) != n * n: return float("nan")
    return math.sqrt(max(0.0, sum(d ** i * d ** j * c[i * n + j] for i in range(n) for j in range(n))))
rows = {"self-calibration": "self.json", "surveyed pole centres": "lm.json.model", "measured stop poses": "st.json.model",
        "tape at 2 of 10 stops": "tape.json.model"}
print("| model | d | median abs error [mm] | largest [mm] | median reported SE [mm] | truth inside the 95 % interval |")
print("|---|---|---|---|---|---|")
for name, file in rows.items():
    for d in (1.0, 2.0, 3.0):
        errs, ses = [], []
        for s in range(1, seeds + 1):
            t = json.load(open(f"{w}/{s}/truth.json"))["model"]["bias_alpha"]
            m = json.load(open(f"{w}/{s}/{file}"))
            errs.append(abs(f(m["bias"]["alpha"], d) - f(t, d)) * 1000)
            ses.append(se(m, d) * 1000)
        inside = sum(1 for e, v in zip(errs, ses) if e <= 1.96 * v)
        print(f"| {name} | {d:.0f} m | {st.median(errs):.1f} | {max(errs):.1f} | {st.median(ses):.1f} | {inside} / {seeds} |")
PY
