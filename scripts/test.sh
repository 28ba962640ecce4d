#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Second README command (and CI's first step): install what is missing, build with warnings as
# errors, run the default test suite: every test but the long statistical cases (label slow) and
# the Slurm recipes (label slurm), which CI runs as its next steps (.ci/run); docs/BUILDING.md
# gives the times.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake -S . -B build -DLIDARCAL_WERROR=ON -DLIDARCAL_WITH_ROSBAG=ON
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" -LE "slow|slurm"
