#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# A fleet's calibration drives on a Slurm cluster: one array task per recording (`lidarcal run`),
# then the fleet report over every calibration in OUT/runs, once all tasks have ended (a failed
# recording does not hold the others back: the report says which gave no model).
#   submit-fleet.sh LIST OUT [lidarcal run options]
# LIST: CSV with the header sensor,date,input, one recording a row (dates ISO 8601, e.g.
# 2024-05-13). OUT must be on a file system every node sees; keep it from week to week and each
# sensor is compared with its previous calibration. SBATCH_PARTITION, SBATCH_TIMELIMIT, ... and
# LIDARCAL as for submit-montecarlo.sh. Prints `tasks_job=ID` and `summary_job=ID`.
set -euo pipefail
usage="usage: submit-fleet.sh LIST OUT [lidarcal run options]"
list=${1:?$usage}
out=${2:?$usage}
shift 2
if [ "$(head -n 1 "$list" | tr -d '\r')" != "sensor,date,input" ]; then
  echo "submit-fleet: $list: line 1: the header must be sensor,date,input" >&2
  exit 2
fi
rows=$(tail -n +2 "$list" | grep -c .) || true
if [ "$rows" -lt 1 ]; then
  echo "submit-fleet: $list lists no recording" >&2
  exit 2
fi
if tail -n +2 "$list" | grep -q '^$'; then
  echo "submit-fleet: $list: blank lines between rows (task I runs row I + 1); remove them" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
list=$(cd "$(dirname "$list")" && pwd)/$(basename "$list")
mkdir -p "$out/logs"
out=$(cd "$out" && pwd)
tasks=$(sbatch --parsable --array="0-$((rows - 1))" --output="$out/logs/run-%a.out" \
  "$here/fleet-task.sbatch" "$list" "$out" "$@")
tasks=${tasks%%;*}
summary=$(sbatch --parsable --dependency="afterany:$tasks" --output="$out/logs/summary.out" \
  "$here/fleet-summary.sbatch" "$list" "$out")
echo "tasks_job=$tasks"
echo "summary_job=${summary%%;*}"
echo "submit-fleet: $rows recordings, then the fleet report in $out/report" >&2
