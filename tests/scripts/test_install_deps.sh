#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# scripts/install-deps.sh with stubs first on PATH: nothing is installed for real. The stubs
# (dpkg-query, apt-get, sudo, id) log their arguments; each case checks the exact commands the
# script would run, as root, as a sudo user, as a user without sudo, and with nothing missing.
# Usage: test_install_deps.sh SOURCE_DIR
set -uo pipefail

src=${1:?usage: test_install_deps.sh SOURCE_DIR}
script="$src/scripts/install-deps.sh"
bash_bin=$(command -v bash)
grep_bin=$(command -v grep)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0

# The packages the script checks, in its order (read from the script itself).
mapfile -t packages < <(sed -n '/^PACKAGES=(/,/^)/p' "$script" | sed 's/#.*//' | tr ' ' '\n' |
  "$grep_bin" -v -e '^PACKAGES=(' -e '^)' -e '^$')
[ "${#packages[@]}" -gt 10 ] || { echo "FAIL: could not read PACKAGES from $script"; exit 1; }

# make_stubs DIR UID WITH_SUDO: a PATH holding only the stubs and grep.
make_stubs() {
  local dir=$1 uid=$2 with_sudo=$3
  mkdir -p "$dir"
  ln -s "$grep_bin" "$dir/grep"
  cat >"$dir/id" <<STUB
#!$bash_bin
[ "\$1" = "-u" ] && { echo $uid; exit 0; }
echo "id stub: unexpected arguments \$*" >&2; exit 9
STUB
  # Installed: the packages listed (one a line) in \$STUB_INSTALLED_FILE.
  cat >"$dir/dpkg-query" <<STUB
#!$bash_bin
pkg=\${!#}
if "$grep_bin" -qx -- "\$pkg" "\$STUB_INSTALLED_FILE"; then printf 'install ok installed'; exit 0; fi
echo "dpkg-query: no packages found matching \$pkg" >&2; exit 1
STUB
  cat >"$dir/apt-get" <<STUB
#!$bash_bin
echo "apt-get \$* [DEBIAN_FRONTEND=\${DEBIAN_FRONTEND:-unset}]" >>"\$STUB_LOG"
STUB
  if [ "$with_sudo" = yes ]; then
    cat >"$dir/sudo" <<STUB
#!$bash_bin
echo "sudo \$*" >>"\$STUB_LOG"
[ "\$1" = "-E" ] && shift
exec "\$@"
STUB
  fi
  chmod +x "$dir"/*
}

# run_case NAME UID WITH_SUDO INSTALLED... : runs the script; sets $log, $out, $status.
run_case() {
  local name=$1 uid=$2 with_sudo=$3
  shift 3
  local dir="$work/$name"
  make_stubs "$dir/bin" "$uid" "$with_sudo"
  printf '%s\n' "$@" >"$dir/installed"
  : >"$dir/log"
  out=$(env -i PATH="$dir/bin" STUB_LOG="$dir/log" STUB_INSTALLED_FILE="$dir/installed" HOME="$dir" \
        "$bash_bin" "$script" 2>&1)
  status=$?
  log=$(cat "$dir/log")
}

expect() {  # expect NAME WHAT EXPECTED ACTUAL
  if [ "$3" != "$4" ]; then
    echo "FAIL [$1] $2"
    echo "  expected: $3"
    echo "  actual:   $4"
    failures=$((failures + 1))
  else
    echo "ok   [$1] $2"
  fi
}

# Two packages missing: the first and the last of the list.
missing="${packages[0]} ${packages[-1]}"
installed=("${packages[@]:1:${#packages[@]}-2}")

run_case root 0 no "${installed[@]}"
expect root "exit status" 0 "$status"
expect root "apt-get runs directly" \
  "apt-get update -qq [DEBIAN_FRONTEND=noninteractive]
apt-get install -y -qq --no-install-recommends $missing [DEBIAN_FRONTEND=noninteractive]" "$log"

run_case root-with-sudo 0 yes "${installed[@]}"
expect root-with-sudo "exit status" 0 "$status"
expect root-with-sudo "no sudo as root" \
  "apt-get update -qq [DEBIAN_FRONTEND=noninteractive]
apt-get install -y -qq --no-install-recommends $missing [DEBIAN_FRONTEND=noninteractive]" "$log"

run_case user 1000 yes "${installed[@]}"
expect user "exit status" 0 "$status"
expect user "apt-get through sudo -E" \
  "sudo -E apt-get update -qq
apt-get update -qq [DEBIAN_FRONTEND=noninteractive]
sudo -E apt-get install -y -qq --no-install-recommends $missing
apt-get install -y -qq --no-install-recommends $missing [DEBIAN_FRONTEND=noninteractive]" "$log"

run_case user-no-sudo 1000 no "${installed[@]}"
expect user-no-sudo "exit status" 1 "$status"
expect user-no-sudo "nothing run" "" "$log"
case "$out" in
  *"missing packages: $missing"*"run this script as root or install sudo"*) echo "ok   [user-no-sudo] message" ;;
  *) echo "FAIL [user-no-sudo] message: $out"; failures=$((failures + 1)) ;;
esac

run_case nothing-missing 1000 yes "${packages[@]}"
expect nothing-missing "exit status" 0 "$status"
expect nothing-missing "no apt-get call" "" "$log"
expect nothing-missing "message" "install-deps: all ${#packages[@]} packages present" "$out"

# Whether PACKAGES lists $1. A loop, not `printf | grep -q`: under pipefail, grep quitting at its
# first match can kill printf with SIGPIPE and fail the pipeline.
listed() {
  local p
  for p in "${packages[@]}"; do [ "$p" = "$1" ] && return 0; done
  return 1
}

# The docs tell users to open scans with pcl_viewer: the script must install it.
if listed pcl-tools; then echo "ok   pcl-tools listed (pcl_viewer)"
else echo "FAIL pcl-tools (pcl_viewer, mentioned in docs/FORMAT.md) is not in PACKAGES"; failures=$((failures + 1)); fi

# The build needs them for ROS 2 bags (io/CMakeLists.txt stops without them).
for p in libzstd-dev liblz4-dev libsqlite3-dev; do
  if listed "$p"; then echo "ok   $p listed (ROS 2 bag import)"
  else echo "FAIL $p (needed to build io/ for ROS 2 bags) is not in PACKAGES"; failures=$((failures + 1)); fi
done

[ "$failures" -eq 0 ] && echo "all cases passed" || echo "$failures failure(s)"
exit $((failures != 0))
