#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What is the Hokuyo range sweep's structured error against the tape
# (docs/FINDINGS.md "Hokuyo UST-30LX range sweep")? Imports the 42 bags of
# ../shared/data/hokuyo_ust30lx_reflector/range_sweep as one stop each, detects the 45 mm
# reflector, measures its centre distance against the tape (`evaluate --reference`, raw), and
# tests sensor-side explanations of what a polynomial in the distance leaves: the reflector's
# received intensity (mean and peak over its points: range walk), the points on it, a cyclic
# error of period 2-60 cm, and an offset per setup (the reflector stood at three bearings).
# Each is scored by leave-one-recording-out prediction (RMS, mm) on the recordings from 0.4 m.
#
#   bench/hokuyo_residuals.sh [WORK_DIR]     (default /tmp/lidarcal-hokuyo-residuals; ~40 s)
set -euo pipefail
cd "$(dirname "$0")/.."
L=$(readlink -f "${LIDARCAL:-build/pipeline/lidarcal}")
DATA=${LIDARCAL_SHARED_DATA:-../shared/data}/hokuyo_ust30lx_reflector/range_sweep
W=${1:-/tmp/lidarcal-hokuyo-residuals}
[ -f "$DATA/labels.csv" ] || { echo "hokuyo_residuals: $DATA is absent" >&2; exit 1; }
rm -rf "$W" && mkdir -p "$W"
tail -n +2 "$DATA/labels.csv" > "$W/all.csv"
awk -F, 'BEGIN {printf "{\"format\": \"lidarcal-reference/1\", \"distances\": ["}
         {printf "%s{\"stop\": %d, \"target\": \"landmark\", \"distance_m\": %s}", (NR > 1 ? ", " : ""), NR - 1, $2}
         END {print "]}"}' "$W/all.csv" > "$W/ref.json"
# shellcheck disable=SC2046
"$L" import -q --from rosbag1 $(awk -F, -v d="$DATA" '{printf "%s/%s ", d, $1}' "$W/all.csv") --stop-per-input \
  -o "$W/seq" > /dev/null
"$L" detect -q "$W/seq" -o "$W/det" --ascii --radius 0.045 --min-stops 1 --inlier-threshold 0.01,0.0005 > /dev/null
"$L" evaluate -q "$W/seq" --reference "$W/ref.json" --radius 0.045 -o "$W/eval.json" > /dev/null
python3 - "$W" <<'PY'
import collections, csv, glob, json, math, sys
w = sys.argv[1]
ev = json.load(open(w + "/eval.json"))["raw"]["entries"]
files = sorted(glob.glob(w + "/det/scan_*.pcd"))
bearing = collections.defaultdict(list)
for row in csv.DictReader(open(w + "/det/landmarks.csv")):
    bearing[int(row["stop"])].append(float(row["bearing_rad"]))
per = len(files) // len(ev)
rows = []
for k, e in enumerate(ev):
    isum = n = 0.0; peaks = []; scans = 0
    for f in files[k * per:(k + 1) * per]:
        lines = open(f).read().split("\n")
        top = 0.0; got = 0
        for line in lines[lines.index("DATA ascii") + 1:]:
            p = line.split()
            if p and p[-1] != "0":
                isum += float(p[3]); n += 1; got += 1; top = max(top, float(p[3]))
        if got: scans += 1; peaks.append(top)
    b = math.degrees(sum(bearing[k]) / len(bearing[k]))
    setup = 0 if b > -2 else (1 if b < -30 else 2)
    if e["status"] == "ok":
        rows.append(dict(d=e["reference_m"], err=1000 * e["error_m"], se=1000 * e["measured_se_m"], mean_i=isum / max(n, 1),
                         peak_i=sum(peaks) / max(len(peaks), 1), points=n / max(scans, 1), bearing=b, setup=setup))
print("| tape [m] | raw - tape [mm] | its SE [mm] | bearing [deg] | mean intensity | peak intensity | points on the reflector |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    print("| %.3f | %+.1f | %.1f | %+.1f | %.0f | %.0f | %.1f |" % (r["d"], r["err"], r["se"], r["bearing"], r["mean_i"], r["peak_i"], r["points"]))
rows = [r for r in rows if r["d"] >= 0.4]
def solve(X, y):
    n = len(X[0]); A = [[sum(x[i] * x[j] for x in X) for j in range(n)] for i in range(n)]
    b = [sum(x[i] * v for x, v in zip(X, y)) for i in range(n)]
    for i in range(n):
        p = max(range(i, n), key=lambda r: abs(A[r][i])); A[i], A[p] = A[p], A[i]; b[i], b[p] = b[p], b[i]
        for r in range(i + 1, n):
            f = A[r][i] / A[i][i]
            for c in range(i, n): A[r][c] -= f * A[i][c]
            b[r] -= f * b[i]
    x = [0.0] * n
    for i in reversed(range(n)): x[i] = (b[i] - sum(A[i][c] * x[c] for c in range(i + 1, n))) / A[i][i]
    return x
def loo(features):
    e = []
    for k in range(len(rows)):
        train = [r for j, r in enumerate(rows) if j != k]
        c = solve([features(r) for r in train], [r["err"] for r in train])
        e.append(rows[k]["err"] - sum(a * b for a, b in zip(c, features(rows[k]))))
    return math.sqrt(sum(v * v for v in e) / len(e))
poly = lambda r: [r["d"] ** i for i in range(4)]
cands = {"cubic in d": poly,
         "+ mean intensity": lambda r: poly(r) + [r["mean_i"] / 1e4],
         "+ peak intensity": lambda r: poly(r) + [r["peak_i"] / 1e4],
         "+ points on the reflector": lambda r: poly(r) + [r["points"] / 10],
         "+ offset per setup (bearing)": lambda r: poly(r) + [float(r["setup"] == 1), float(r["setup"] == 2)]}
best = min((loo(lambda r, P=P: poly(r) + [math.sin(2 * math.pi * r["d"] / P), math.cos(2 * math.pi * r["d"] / P)]), P)
           for P in [x / 1000 for x in range(20, 605, 5)])
print("\n%d recordings from 0.4 m; leave-one-recording-out prediction of raw - tape:\n" % len(rows))
print("| model | LOO RMS [mm] |\n|---|---|")
for name, f in cands.items(): print("| %s | %.2f |" % (name, loo(f)))
print("| + best cyclic term (period %.0f cm of 2-60 cm) | %.2f |" % (100 * best[1], best[0]))
PY
