#!/usr/bin/env bash
# Second README command (and CI): install what is missing, build with warnings as errors, run all
# tests but the Slurm recipes (label slurm: `ctest --test-dir build -L slurm`, CI's second step).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
cmake -S . -B build -DLIDARCAL_WERROR=ON -DLIDARCAL_WITH_ROSBAG=ON
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" -LE slurm
