#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Where Sharma 2020's hill climbing ends, beside the thesis' end points
# (docs/results/noise-consistency.md, "The hill climbing's end points beside the thesis'").
#   bench/noise_endpoints.sh [SEEDS]     (default SEEDS: 1 2 3 4 5; needs a build in build/)
# Experiments 1-3 (simulator seed 1, as in docs/noise/exp*.md), variances only (the thesis prints
# only those), both variants of the objective, the hill climbing's own seed (particle filter and
# random jumps) over SEEDS; experiment 2 also with steps of 0.1, the steps its printed trace takes.
# Prints one Markdown row per run: the end point, evaluations, and how many of the four variances
# end within 10 % of the truth.
set -euo pipefail
cd "$(dirname "$0")/.."
L=build/pipeline/lidarcal
SEEDS=${1:-1 2 3 4 5}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
"$L" simulate -q --scene data/scenes/noise_exp12.json --out "$TMP/e12" --seed 1
"$L" simulate -q --scene data/scenes/noise_exp3.json --out "$TMP/e3" --seed 1
echo "| experiment | variant | step | seed | sensor 1 [range, bearing] | sensor 2 [range, bearing] | evaluations | within 10 % of the truth |"
echo "|---|---|---|---|---|---|---|---|"
run() {  # experiment data init variant step seed
  local out="$TMP/r.json"
  rm -f "$out"
  "$L" noise-consistency -q --observations "$TMP/$2/observations.csv" --odometry "$TMP/$2/odometry.csv" \
    --method kl-hill --variant "$4" --fixed-means --init "data/noise/$3.json" --step "$5" --seed "$6" --out "$out"
  python3 - "$out" "$TMP/$2/noise_truth.json" "$1" "$4" "$5" "$6" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1])); t = json.load(open(sys.argv[2]))
def pairs(j):
    return [(s["range_var_m2"], s["bearing_var_rad2"]) for s in j["sensors"]]
est, truth = pairs(r), pairs(t)
within = sum(abs(e / v - 1) <= 0.10 for ep, tp in zip(est, truth) for e, v in zip(ep, tp))
fmt = lambda p: "[%.3f, %.3f]" % p
print("| %s | %s | %s | %s | %s | %s | %s | %d / 4 |" % (sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6], fmt(est[0]), fmt(est[1]),
      r.get("evaluations", "?"), within))
EOF
}
for seed in $SEEDS; do
  for variant in faithful sound; do
    run 1 e12 exp1_init "$variant" 0.01 "$seed"
    run 2 e12 exp2_init "$variant" 0.01 "$seed"
    run 2 e12 exp2_init "$variant" 0.1 "$seed"
    run 3 e3 exp3_init "$variant" 0.01 "$seed"
  done
done
