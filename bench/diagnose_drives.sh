#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Diagnoses simulated drives (a robot that never stops: data/scenes/driving_*_poles.json), clean
# or with one effect hidden in the scene's sensor, and prints the cause named for each.
#   bench/diagnose_drives.sh SCENE EFFECT FIRST LAST [LIDARCAL]
# SCENE: driving_small_poles | driving_large_poles; EFFECT: none | incidence_bias |
# incidence_noise | range_drift | mixed_pixels | range_noise_law | landmark_bias | angle_offset.
# For `none`, FIRST..LAST are simulator seeds; otherwise case numbers: the effect's size and
# sign are drawn from the case number (sizes as in bench/diagnose_accuracy's cases) and the
# simulator seed is 500 + case. Needs python3. docs/results/hidden-effects.md.
# With KEEP=DIR set, each case's diagnosis.json is kept as DIR/SCENE-EFFECT-K.json.
# REPLICAS (default 19, diagnose's own default) sets --replicas; with 5 the
# Student-t predictive p of the statistics (4 degrees of freedom) cannot fall far.
set -euo pipefail
scene=$1 effect=$2 first=$3 last=$4
bin=${5:-build/pipeline/lidarcal}
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for k in $(seq "$first" "$last"); do
  python3 - "$root/data/scenes/$scene.json" "$effect" "$k" > "$work/scene.json" <<'PY'
import json, random, sys
path, effect, case = sys.argv[1], sys.argv[2], int(sys.argv[3])
d = json.load(open(path))
effects = ["none", "incidence_bias", "incidence_noise", "range_drift", "mixed_pixels",
           "range_noise_law", "landmark_bias", "angle_offset"]
r = random.Random(case * 1000 + effects.index(effect))
sign = -1 if r.random() < 0.5 else 1
e = {}
if effect == "incidence_bias": e["incidence_bias_m"] = sign * (0.02 + 0.02 * r.random())
elif effect == "incidence_noise": e["incidence_noise_exponent"] = 1 + 0.5 * r.random()
elif effect == "range_drift": e["range_drift_m_per_scan"] = sign * (0.03 + 0.01 * r.random()) / d["path"]["scans"]
elif effect == "mixed_pixels": e["mixed_pixel_fraction"] = 0.05 + 0.05 * r.random()
elif effect == "range_noise_law":  # sigma proportional to f(d)^k, about the squared law's size at 1.8 m
    k = 0.5 + 0.5 * r.random()
    d["sensor"]["noise"] = {"kind": "power", "sigma_e": d["sensor"]["noise"]["sigma_e"] * 1.8 ** (2 - k), "exponent": k}
elif effect == "landmark_bias":  # per-pole offsets, RMS 2-2.5 cm about their mean
    offs = [r.gauss(0, 1) for _ in d["landmarks"]]
    m = sum(offs) / len(offs)
    rms = (sum((o - m) ** 2 for o in offs) / len(offs)) ** 0.5
    s = 0.02 + 0.005 * r.random()
    for l, o in zip(d["landmarks"], offs): l["range_offset_m"] = (o - m) / rms * s
elif effect == "angle_offset": d["sensor"]["mount_yaw_deg"] = sign * (2 + r.random())
if e: d["sensor"]["effects"] = e
json.dump(d, sys.stdout, indent=1)
PY
  seed=$k
  [ "$effect" = none ] || seed=$((500 + k))
  "$bin" simulate -q --scene "$work/scene.json" --seed "$seed" -o "$work/sim" --overwrite
  echo "$scene $effect $k $("$bin" diagnose "$work/sim/scans" -o "$work/d" --overwrite --replicas "${REPLICAS:-19}" -q)"
  if [ -n "${KEEP:-}" ]; then cp "$work/d/diagnosis.json" "$KEEP/$scene-$effect-$k.json"; fi
done
