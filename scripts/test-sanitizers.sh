#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# CI step (separate from scripts/test.sh, see docs/BUILDING.md): the whole test suite under
# AddressSanitizer + UndefinedBehaviorSanitizer with LeakSanitizer on, in its own build
# directory build-asan/ (a second full build: about 25 minutes on two cores, the tests about
# as long again). The `lidarcal` processes the CLI tests start are instrumented too and inherit
# the options below, so a leak or an error in a child fails its test (the exit code changes).
#
#   scripts/test-sanitizers.sh [extra ctest arguments, e.g. -R test_io]
set -euo pipefail
cd "$(dirname "$0")/.."
JOBS="${JOBS:-2}"
./scripts/install-deps.sh
cmake -S . -B build-asan -DLIDARCAL_SANITIZE=ON -DLIDARCAL_WERROR=ON -DLIDARCAL_WITH_ROSBAG=ON \
  -DLIDARCAL_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build-asan -j"$JOBS"

supp="$PWD/tests/sanitizers"
# detect_odr_violation=0: Debian's PCL and VTK libraries define some globals in more than one
# shared object (not our code; docs/BUILDING.md, "Sanitizers").
export ASAN_OPTIONS="detect_leaks=1:detect_odr_violation=0:abort_on_error=0:exitcode=99:strict_string_checks=1:check_initialization_order=1:detect_stack_use_after_return=1"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0:exitcode=98"
export UBSAN_OPTIONS="suppressions=$supp/ubsan.supp:print_stacktrace=1:halt_on_error=1"
# install_and_consume links the instrumented static libraries into a project built without the
# sanitizers, which cannot link: it runs in the normal build (scripts/test.sh).
ctest --test-dir build-asan --output-on-failure -j"$JOBS" -LE install --timeout 1800 "$@"
