#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Every shared real recording through `lidarcal calibrate` (docs/results/real-sensors.md):
# the outcome (exit 0 with the model, or exit 3 with the reason), wall time and peak memory of
# calibrate, the selected order and the bias at 1 m and 3 m with their standard errors.
#
#   bench/real_recordings.sh [WORK_DIR]     (default /tmp/lidarcal-real; needs a build in build/
#                                            and ../shared/data; prints one Markdown row per recording)
set -euo pipefail
cd "$(dirname "$0")/.."
L=${LIDARCAL:-build/pipeline/lidarcal}
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}
WORK=${1:-/tmp/lidarcal-real}
[ -d "$DATA" ] || { echo "real_recordings: $DATA is absent" >&2; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK"

echo "| recording | scans | calibrate | wall [s] | peak [MB] | order | f(1 m) - 1 m [mm] | f(3 m) - 3 m [mm] | warnings / reason |"
echo "|---|---|---|---|---|---|---|---|---|"
row() {  # name, import arguments...
  local name=$1; shift
  local seq="$WORK/$name"
  if ! "$L" import -q "$@" -o "$seq" > /dev/null 2> "$WORK/$name.import.err"; then
    echo "| $name | - | import failed: $(head -c 200 "$WORK/$name.import.err") | | | | | | |"
    return
  fi
  local scans
  scans=$(find "$seq" -name '*.pcd' | wc -l)
  set +e
  /usr/bin/time -f "%e %M" -o "$WORK/$name.time" "$L" calibrate -q "$seq" -o "$WORK/$name.json" \
    > "$WORK/$name.out" 2> "$WORK/$name.err"
  local rc=$?
  set -e
  read -r wall kb < <(tail -n 1 "$WORK/$name.time")
  python3 - "$name" "$scans" "$rc" "$wall" "$kb" "$WORK/$name.json" "$WORK/$name.err" <<'EOF'
import json, math, sys
name, scans, rc, wall, kb, model, err = sys.argv[1:]
mb = int(kb) / 1024
if rc != "0":
    reason = open(err).read().strip().replace("|", "/").replace("\n", " ")
    reason = reason.split("calibration: ", 1)[-1][:260]
    print(f"| {name} | {scans} | exit {rc} | {float(wall):.1f} | {mb:.0f} | | | | {reason} |")
    sys.exit()
m = json.load(open(model))
a = m["bias"]["alpha"]
cov = m.get("alpha_covariance") or []
n = len(a)
def err(d):
    x = [d ** i for i in range(n)]
    f = sum(ai * xi for ai, xi in zip(a, x)) - d
    if len(cov) != n * n:
        return f"{1000 * f:+.0f}"
    v = sum(x[i] * cov[i * n + j] * x[j] for i in range(n) for j in range(n))
    return f"{1000 * f:+.0f} ± {1000 * math.sqrt(max(v, 0.0)):.0f}"
warn = "; ".join(m.get("warnings", [])).replace("|", "/")[:260] or "none"
print(f"| {name} | {scans} | exit 0 | {float(wall):.1f} | {mb:.0f} | {n - 1} | {err(1.0)} | {err(3.0)} | {warn} |")
EOF
}
row rplidar_a2_room "$DATA/rplidar_a2_room/rplidar_1.bag"
for f in 2019-05-03-19-38-28 2019-05-03-19-39-14 2019-05-03-19-42-50 2019-05-03-19-44-15; do
  row "ydlidar_$f" "$DATA/ydlidar_x4/$f.dat"
done
for f in intel csail freiburg-079 freiburg-campus; do
  row "carmen_$f" "$DATA/carmen/$f-corrected.log.gz"
done
row hokuyo_range_sweep_all "$DATA"/hokuyo_ust30lx_reflector/range_sweep/*.bag --stop-per-input --every 4
