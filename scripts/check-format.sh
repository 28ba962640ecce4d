#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# The style check the test suite runs (ctest: style.format, style.spdx): every C++ source is as
# clang-format leaves it (.clang-format), and every source file carries an SPDX licence line.
#
#   scripts/check-format.sh          check; lists each file that fails, exit 1 when any does
#   scripts/check-format.sh --fix    format the C++ sources in place (then review and commit)
#   scripts/check-format.sh --spdx   check only the SPDX lines
set -euo pipefail
cd "$(dirname "$0")/.."

# The files checked: git's list in a checkout, otherwise the source folders (an unpacked archive).
sources() {
  if git rev-parse --is-inside-work-tree > /dev/null 2>&1; then
    git ls-files --cached --others --exclude-standard
  else
    find . -path ./build -prune -o -path './build-*' -prune -o -type f -print | sed 's|^\./||'
  fi
}
cxx=$(sources | grep -E '\.(cpp|hpp)$' | grep -v '^tests/fuzz/corpus' || true)
licensed=$(sources | grep -E '(\.(cpp|hpp|idl|sh|py|cmake|sbatch|supp|xml)|CMakeLists\.txt|\.cmake\.in|^\.ci/run)$' || true)

mode=${1:-check}
fail=0
checked=
if [ "$mode" != --spdx ]; then
  cf=$(command -v clang-format-14 || command -v clang-format || true)
  if [ -z "$cf" ]; then
    echo "check-format: clang-format is not installed (scripts/install-deps.sh installs it)" >&2
    exit 2
  fi
  if [ "$mode" = --fix ]; then
    echo "$cxx" | xargs "$cf" -i
    exit 0
  fi
  # --dry-run -Werror: exit nonzero and name the file and line where the formatter would change it.
  log=$(mktemp)
  trap 'rm -f "$log"' EXIT
  if ! echo "$cxx" | xargs "$cf" --dry-run -Werror 2> "$log"; then
    grep -E '^[^ ].*: error:' "$log" | cut -d: -f1 | sort -u | sed 's/^/unformatted: /'
    echo "check-format: run scripts/check-format.sh --fix, review the change and commit it" >&2
    fail=1
  fi
  checked="$(echo "$cxx" | wc -l) C++ files formatted, "
fi
missing=$(echo "$licensed" | while read -r f; do
  [ -n "$f" ] && ! head -3 "$f" | grep -q 'SPDX-License-Identifier: BSD-3-Clause' && echo "$f"
done || true)
if [ -n "$missing" ]; then
  echo "$missing" | sed 's/^/no SPDX line: /'
  echo "check-format: add '// SPDX-License-Identifier: BSD-3-Clause' (or '#' for scripts) near the top" >&2
  fail=1
fi
[ $fail = 0 ] && echo "check-format: ${checked:-}$(echo "$licensed" | wc -l) files with an SPDX line"
exit $fail
