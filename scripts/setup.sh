#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# First README command: install what is missing, build, and run the main job on the bundled example.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake -S . -B build -DLIDARCAL_WERROR=ON -DLIDARCAL_WITH_ROSBAG=ON
cmake --build build -j"$(nproc)"
./build/pipeline/lidarcal run --out build/example-run --overwrite
echo "setup: the report is build/example-run/report/report.md"
