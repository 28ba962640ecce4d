#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# CI step (separate from scripts/test.sh, see docs/BUILDING.md): builds the libFuzzer targets
# with clang (ASan + UBSan) in build-fuzz/ and runs each for a bounded time with a fixed seed on
# its seed corpus (tests/fuzz/corpus/<target>/). Exits nonzero on any finding; the input that
# caused it is left in build-fuzz/findings/<target>/ (copy it to tests/fuzz/regressions/<target>/
# with the fix: test_fuzz_regressions replays it in every build).
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET (default 60)] [TARGET ...]   # default: every target
#
# Eight targets at 60 s each plus the build take about 12 minutes on two cores.
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET="${1:-60}"
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -gt 0 ] || TARGETS=(pcd json csv carmen ydlidar csv_import mcap cdr)
JOBS="${JOBS:-2}"

./scripts/install-deps.sh
cmake -S . -B build-fuzz -DLIDARCAL_FUZZ=ON -DLIDARCAL_BUILD_TESTS=OFF -DLIDARCAL_BUILD_BENCH=OFF \
  -DLIDARCAL_WITH_ROSBAG=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 >/dev/null
cmake --build build-fuzz -j"$JOBS" --target $(printf 'fuzz_%s ' "${TARGETS[@]}")

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:symbolize=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp:print_suppressions=0"
status=0
for t in "${TARGETS[@]}"; do
  work="build-fuzz/work/$t"          # the corpus grows here; the committed seeds stay as they are
  findings="build-fuzz/findings/$t"
  rm -rf "$work" "$findings"
  mkdir -p "$work" "$findings"
  echo "fuzz: $t for ${SECONDS_PER_TARGET}s"
  if ! "build-fuzz/tests/fuzz/fuzz_$t" "$work" "tests/fuzz/corpus/$t" \
      -seed=1 -max_total_time="$SECONDS_PER_TARGET" -max_len=16384 -timeout=10 -rss_limit_mb=2048 \
      -artifact_prefix="$findings/" -print_final_stats=1 >"build-fuzz/fuzz-$t.log" 2>&1; then
    echo "fuzz: $t FOUND A PROBLEM (log: build-fuzz/fuzz-$t.log, input: $findings/)" >&2
    tail -40 "build-fuzz/fuzz-$t.log" >&2
    status=1
  else
    grep -E "stat::number_of_executed_units|stat::average_exec_per_sec|stat::peak_rss_mb" "build-fuzz/fuzz-$t.log" | tr '\n' ' '
    echo
  fi
done
exit $status
