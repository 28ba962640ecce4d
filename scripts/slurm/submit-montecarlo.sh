#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# A Monte Carlo study on a Slurm cluster: N array tasks, one shard each, then the merge, which
# runs when every shard has succeeded. The study lands in OUT/study, the job logs in OUT/logs.
#   submit-montecarlo.sh N OUT [lidarcal montecarlo options]
#   e.g. submit-montecarlo.sh 64 /shared/mc --study all --trials 10000
# OUT must be on a file system every node sees. sbatch's own variables choose the partition,
# time limit or account (SBATCH_PARTITION, SBATCH_TIMELIMIT, SBATCH_ACCOUNT); LIDARCAL names the
# lidarcal binary the nodes run (default: lidarcal on PATH). Prints the job ids as
# `shards_job=ID` and `merge_job=ID`.
set -euo pipefail
usage="usage: submit-montecarlo.sh N OUT [lidarcal montecarlo options]"
n=${1:?$usage}
out=${2:?$usage}
shift 2
if ! [[ $n =~ ^[1-9][0-9]*$ ]]; then
  echo "submit-montecarlo: N must be a positive whole number, not '$n' ($usage)" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out/logs"
out=$(cd "$out" && pwd)
shards=$(sbatch --parsable --array="0-$((n - 1))" --output="$out/logs/shard-%a.out" \
  "$here/montecarlo-shard.sbatch" "$out" "$@")
shards=${shards%%;*}  # --parsable prints JOBID[;CLUSTER]
merge=$(sbatch --parsable --dependency="afterok:$shards" --kill-on-invalid-dep=yes --output="$out/logs/merge.out" \
  "$here/montecarlo-merge.sbatch" "$out" "$n")
echo "shards_job=$shards"
echo "merge_job=${merge%%;*}"
echo "submit-montecarlo: $n shards, then the merge into $out/study" >&2
