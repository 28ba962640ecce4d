#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs the Debian 12 packages lidarcal needs. Idempotent: checks what is installed first
# and returns at once when nothing is missing. Uses sudo when not run as root.
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config
  libpcl-dev libeigen3-dev libflann-dev libceres-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev gnuplot-nox
  pcl-tools                        # pcl_viewer, to look at scans (docs/FORMAT.md)
  zlib1g-dev                       # gzip-compressed CARMEN logs (importer)
  libzstd-dev liblz4-dev libsqlite3-dev  # ROS 2 bags: MCAP chunk compression, .db3 files (importer)
  # ROS1 bag reading (importer; see docs/BUILDING.md for why each is listed)
  librosbag-storage-dev libsensor-msgs-dev libclass-loader-dev
  librcpputils-dev librcutils-dev libament-index-cpp-dev
  libnav-msgs-dev libtf2-msgs-dev  # odometry and tf in bags (import --pose odom:|tf:)
  libroscpp-dev python3-rosmaster  # lidarcal_node (roscpp) and the rosmaster its test starts
  libdiagnostic-msgs-dev libstd-msgs-dev  # lidarcal_node's /diagnostics status and learn mode's candidate topic
  cyclonedds-dev cyclonedds-tools  # lidarcal_ros2_node: Eclipse Cyclone DDS and its IDL compiler idlc
  libfastrtps-dev fastddsgen       # eProsima Fast DDS and fastddsgen: the other vendor, for the cross-vendor test
  clang-format-14                  # the style check (scripts/check-format.sh, .clang-format)
  clang-14 libclang-rt-14-dev      # libFuzzer targets (scripts/fuzz.sh): clang's -fsanitize=fuzzer and its runtime
  slurmctld slurmd slurm-client munge  # the Slurm recipes' test (scripts/slurm/): a single-node cluster it starts and stops
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

# As root, apt-get runs directly; otherwise through sudo (with -E so DEBIAN_FRONTEND reaches it).
# An array, not a string: an empty prefix must vanish, not become an empty command word.
as_root=()
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null; then
    echo "install-deps: missing packages: ${missing[*]}" >&2
    echo "install-deps: run this script as root or install sudo" >&2
    exit 1
  fi
  as_root=(sudo -E)
fi

echo "install-deps: installing ${#missing[@]} missing packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${as_root[@]}" apt-get update -qq
"${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
