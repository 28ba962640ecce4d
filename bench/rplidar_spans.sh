#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Wall-to-wall spans on the RPLIDAR A2 room (docs/RESULTS.md, "Wall-to-wall spans (RPLIDAR A2
# room)"): the bag of ../shared/data/rplidar_a2_room (one static pose, 1319 scans) and the six
# laser-meter spans of its distance_comparison.md (lines 1-3 wall to wall, 4-5 wall to cabinet,
# 6 sideboard to wall across the room). The walls are named by the direction of their normals in
# the sensor frame, as `lidarcal run` lists them when it refuses this recording.
#
# Each span is checked on a model that did not see it: fitted on the other five (leave one span
# out), and fitted without every span between the same two walls (leave the pair out: lines 1-3
# share their walls, so leaving one out still leaves its walls measured). The error is what the
# scans say minus the laser meter, the scans corrected in memory with that model as `correct`
# would (`evaluate --reference --model`: the two walls' fitted lines on the corrected scans).
# Prints a Markdown table.
#
#   bench/rplidar_spans.sh      (needs build/pipeline/lidarcal built with the ROS1 bag reader)
set -euo pipefail
cd "$(dirname "$0")/.."
L=$(readlink -f build/pipeline/lidarcal)
BAG=../shared/data/rplidar_a2_room/rplidar_1.bag
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
"$L" import -q "$BAG" -o "$W/room" > /dev/null

# The spans: line of the plan, wall normals (deg), laser meter (m); pair = the two walls.
python3 - "$W" <<'PY'
import json, sys
w = sys.argv[1]
spans = [("1", -50, 130, 6.155, "A"), ("2", -50, 130, 6.150, "A"), ("3", -50, 130, 6.147, "A"),
         ("4", -50, 130, 5.709, "B"), ("5", -50, 130, 5.709, "B"), ("6", -140, 40, 4.777, "C")]
def ref(keep):
    return {"format": "lidarcal-reference/1",
            "spans": [{"stop": 0, "bearing_a_deg": a, "bearing_b_deg": b, "distance_m": d}
                      for k, (_, a, b, d, _) in enumerate(spans) if keep(k)]}
json.dump(ref(lambda k: True), open(w + "/all.json", "w"))
for k in range(len(spans)):
    json.dump(ref(lambda j: j != k), open(f"{w}/without{k}.json", "w"))
    json.dump(ref(lambda j: j == k), open(f"{w}/only{k}.json", "w"))
    json.dump(ref(lambda j: spans[j][4] != spans[k][4]), open(f"{w}/withoutpair{k}.json", "w"))
json.dump(spans, open(w + "/spans.json", "w"))
PY

"$L" calibrate -q "$W/room" --reference "$W/all.json" -o "$W/all.model" > "$W/all.out"
"$L" evaluate -q "$W/room" --reference "$W/all.json" --model "$W/all.model" -o "$W/all.eval" > /dev/null
for k in 0 1 2 3 4 5; do
  "$L" calibrate -q "$W/room" --reference "$W/without$k.json" -o "$W/without$k.model" > /dev/null
  "$L" evaluate -q "$W/room" --reference "$W/only$k.json" --model "$W/without$k.model" -o "$W/without$k.eval" > /dev/null
  "$L" calibrate -q "$W/room" --reference "$W/withoutpair$k.json" -o "$W/withoutpair$k.model" > /dev/null
  "$L" evaluate -q "$W/room" --reference "$W/only$k.json" --model "$W/withoutpair$k.model" -o "$W/withoutpair$k.eval" > /dev/null
done

python3 - "$W" <<'PY'
import json, math, sys
w = sys.argv[1]
spans = json.load(open(w + "/spans.json"))
def load(name): return json.load(open(f"{w}/{name}"))
def model_text(m):
    a, se = m["bias"]["alpha"], m["bias"]["standard_error"]
    if len(a) == 2 and se[1] == 0.0:
        return f"d {a[0] * 1000:+.1f} ± {se[0] * 1000:.1f} mm"
    return " + ".join(f"{c:.4f}{'' if i == 0 else ' d' if i == 1 else f' d^{i}'}" for i, c in enumerate(a))
def err(e, key): return e[key]["spans"]["entries"][0]["error_m"] * 1000
allm, alle = load("all.model"), load("all.eval")
print("| line | walls | laser meter [m] | raw [mm] | fitted on all six [mm] | span left out [mm] | model without it | "
      "its pair of walls left out [mm] | model without the pair |")
print("|---|---|---|---|---|---|---|---|---|")
raw, fit, one, pair = [], [], [], []
for k, (line, a, b, d, p) in enumerate(spans):
    r = alle["raw"]["spans"]["entries"][k]["error_m"] * 1000
    f = alle["corrected"]["spans"]["entries"][k]["error_m"] * 1000
    o = err(load(f"without{k}.eval"), "corrected")
    q = err(load(f"withoutpair{k}.eval"), "corrected")
    raw.append(r); fit.append(f); one.append(o); pair.append(q)
    print(f"| {line} | {a}°, {b}° | {d:.3f} | {r:+.1f} | {f:+.1f} | {o:+.1f} | {model_text(load(f'without{k}.model'))} | "
          f"{q:+.1f} | {model_text(load(f'withoutpair{k}.model'))} |")
rms = lambda v: math.sqrt(sum(x * x for x in v) / len(v))
print(f"| RMS | | | {rms(raw):.1f} | {rms(fit):.1f} | {rms(one):.1f} | | {rms(pair):.1f} | |")
print()
print(f"Model fitted on all six spans: f(d) = {model_text(allm)} "
      f"(order rule: {allm['order_selection']['rule']}; fitted over {allm['fitted_range']['d_min_m']:.2f}-"
      f"{allm['fitted_range']['d_max_m']:.2f} m)")
for warning in allm.get("warnings", []): print(f"warning: {warning}")
PY
