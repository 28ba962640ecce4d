#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Reproduces the tables and plots of docs/results/noise-consistency.md.
#   bench/noise_experiments.sh [OUT]        (default OUT: docs/noise; needs a build in build/)
# Writes OUT/<experiment>.md (side-by-side table), OUT/<experiment>/<method>/{result.json,
# objective.png, params.png, trace.dat, params.dat, plot.gp} and OUT/ml_study_<experiment>.md.
# Slow: the hill climbing of experiment 3 and the harder case runs the 80-particle filter
# thousands of times (about half an hour on two loaded cores).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=build/bench/noise_experiments
OUT=${1:-docs/noise}
mkdir -p "$OUT"
run() {  # name scene init
  echo "side-by-side $1" >&2
  "$BIN" side-by-side --scene "data/scenes/$2.json" --init "data/noise/$3.json" --seed 1 --out "$OUT/$1" >"$OUT/$1.md"
}
run exp1 noise_exp12 exp1_init
run exp2 noise_exp12 exp2_init
run exp3 noise_exp3 exp3_init
run hard noise_hard hard_init
echo "objective-noise exp3" >&2
"$BIN" objective-noise --scene data/scenes/noise_exp3.json --init data/noise/exp3_init.json >"$OUT/objective_noise_exp3.md"
for s in noise_exp12:exp2 noise_exp3:exp3 noise_exp3_long:exp3_long noise_hard:hard; do
  echo "ml-study ${s#*:}" >&2
  "$BIN" ml-study --scene "data/scenes/${s%%:*}.json" --seeds 20 >"$OUT/ml_study_${s#*:}.md"
done
# Sharma 2020's experiments tell the estimator the true process noise: the sensors' noise alone.
for s in noise_exp12:exp2 noise_exp3:exp3; do
  echo "ml-study ${s#*:}, process given" >&2
  "$BIN" ml-study --scene "data/scenes/${s%%:*}.json" --seeds 20 --process-given >"$OUT/ml_study_${s#*:}_process_given.md"
done
"$BIN" ml-study --scene data/scenes/noise_exp3.json --seeds 200 --process-given >"$OUT/ml_study_exp3_process_given_200.md"
echo "ml-study exp3, 200 seeds" >&2
"$BIN" ml-study --scene data/scenes/noise_exp3.json --seeds 200 >"$OUT/ml_study_exp3_200.md"
"$BIN" ml-study --scene data/scenes/noise_exp3_long.json --seeds 60 >"$OUT/ml_study_exp3_long_60.md"
