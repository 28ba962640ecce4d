#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# What a user gets beyond the fitted range: simulated rooms (seeds the tests do not use) through
# `lidarcal run`, then the same model applied with each --outside policy by `correct`, and every
# written sequence scored against the simulator's truth by `evaluate` (the files read back).
#
#   bench/outside_policies.sh [LIDARCAL] [SCENE] [SEEDS...]
#
# Prints a Markdown table: per seed and policy the MSE ratio on the landmark returns, on all
# returns and on the returns beyond the fitted range, with the oracle's landmark ratio (the
# ground-truth fit of Alhashimi et al. 2016, same policy) and run's own figure from summary.json.
set -euo pipefail
cd "$(dirname "$0")/.."
L=$(readlink -f "${1:-build/pipeline/lidarcal}")
SCENE=${2:-data/scenes/paper_field.json}
shift $(( $# > 2 ? 2 : $# )) || true
SEEDS=("$@")
[ ${#SEEDS[@]} -eq 0 ] && SEEDS=(301 302 303)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
# ratio FILE PATH: the MSE ratio at PATH (a Python subscript of the row), '-' for a row without returns.
ratio() { python3 -c "import json,sys; r=json.load(open(sys.argv[1]))$2; print('-' if not r['n'] else f\"{r['mse_ratio']:.2f}\")" "$1"; }
echo "| seed | policy | landmarks | all returns | beyond the fitted range (returns) | oracle, landmarks | run's summary.json, all returns |"
echo "|---|---|---|---|---|---|---|"
for s in "${SEEDS[@]}"; do
  "$L" simulate -q --scene "$SCENE" -o "$W/sim$s" --seed "$s"
  "$L" run -q "$W/sim$s/scans" -o "$W/run$s" > /dev/null
  oracle=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(f\"{[b for b in j['baselines'] if b['model'].startswith('ground truth (oracle')][0]['evaluation']['landmarks']['mse_ratio']:.2f}\")" "$W/run$s/summary.json")
  summary_all=$(ratio "$W/run$s/summary.json" "['evaluation']['all']")
  for p in linear keep drop extrapolate; do
    "$L" correct -q "$W/sim$s/scans" --model "$W/run$s/model.json" --outside $p -o "$W/c$s-$p"
    "$L" evaluate "$W/c$s-$p" --truth "$W/sim$s/truth.json" > "$W/e$s-$p.json"
    n=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['beyond_fitted_range']['n'])" "$W/e$s-$p.json")
    echo "| $s | $p | $(ratio "$W/e$s-$p.json" "['landmarks']") | $(ratio "$W/e$s-$p.json" "['all']") | $(ratio "$W/e$s-$p.json" "['beyond_fitted_range']") ($n) | $oracle | $([ $p = linear ] && echo "$summary_all" || echo "") |"
  done
done
