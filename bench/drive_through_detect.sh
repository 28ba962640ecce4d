#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# odometry-drive end to end through simulated scans and `detect` (docs/results/odometry.md):
# the bundled driving scene with a laser that reads 30 mm long and exact odometry, simulated,
# its poles detected with their known radius, the wheels' angles derived from the true poses of
# truth.json for wheels of radius 50 mm on a 300 mm axle, then fitted twice: on the circles of
# landmarks.csv and (--beams) on the labelled returns. One run per beam noise: none, constant
# 5 mm, and the scene's own (growing with the square of the range).
# Usage: bench/drive_through_detect.sh [BUILD_DIR] [WORK_DIR]
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
work=${2:-$(mktemp -d)}
lidarcal=$build/pipeline/lidarcal
mkdir -p "$work"

python3 - "$here/data/scenes/driving_large_poles.json" "$work" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["sensor"]["bias_alpha"] = [0.03, 1.0]  # 30 mm long, no scale error
scene["path"]["odometry"] = {"translation_fraction": 0.0, "heading_deg_per_m": 0.0,
                             "heading_fraction": 0.0}
scene["clutter"] = []
for name, noise in [("none", {"kind": "none"}), ("constant", {"kind": "constant", "sigma_e": 0.005}),
                    ("squared", scene["sensor"]["noise"])]:
    scene["sensor"]["noise"] = noise
    json.dump(scene, open(f"{sys.argv[2]}/scene_{name}.json", "w"), indent=1)
PY

wheels() {  # truth.json -> wheel_angles.csv: each true step as the arc two wheels drive
  python3 - "$1" "$2" <<'PY'
import json, math, sys
radius, axle = 0.05, 0.30
rows, left, right, prev = ["file,left_wheel_rad,right_wheel_rad"], 0.0, 0.0, None
for stop in json.load(open(sys.argv[1]))["stops"]:
    a = stop["actual"]
    if prev:
        c, s = math.cos(prev["yaw_rad"]), math.sin(prev["yaw_rad"])
        dx, dy = a["x_m"] - prev["x_m"], a["y_m"] - prev["y_m"]
        forward = c * dx + s * dy
        turn = math.remainder(a["yaw_rad"] - prev["yaw_rad"], 2 * math.pi)
        chord = math.hypot(dx, dy)
        distance = chord if abs(turn) < 1e-12 else chord * (turn / 2) / math.sin(turn / 2)
        distance = math.copysign(distance, forward)
        left += (distance - turn * axle / 2) / radius
        right += (distance + turn * axle / 2) / radius
    rows.append("scan_%06d.pcd,%.12g,%.12g" % (stop["first_scan"], left, right))
    prev = a
open(sys.argv[2], "w").write("\n".join(rows) + "\n")
PY
}

for noise in none constant squared; do
  "$lidarcal" --quiet simulate --scene "$work/scene_$noise.json" -o "$work/sim_$noise" --seed 1 --overwrite > /dev/null
  "$lidarcal" --quiet detect "$work/sim_$noise/scans" --out "$work/det_$noise" --radius 0.1 --overwrite > /dev/null
  wheels "$work/sim_$noise/truth.json" "$work/wheels_$noise.csv"
  echo "== beam noise: $noise (truth: radii 50 mm, axle 300 mm, mounting 0, range offset 30 mm)"
  for level in circles beams; do
    echo "-- fitted by ${level}"
    "$lidarcal" --quiet odometry-drive --wheels "$work/wheels_$noise.csv" \
      --landmarks "$work/det_$noise/landmarks.csv" --nominal 0.05,0.05,0.30,0,0,0 \
      -o "$work/drive_${noise}_$level.json" --overwrite $([ $level = beams ] && echo --beams)
  done
done
