#!/usr/bin/env bash
# clang-format on every C++ file of include, src, tests and platform. A
# failure is reported at the end of .ci/run, after the other steps have run.
source .ci/lib.sh

dirs=()
for d in include src tests platform; do [[ -d $d ]] && dirs+=("$d"); done
mapfile -t files < <(find "${dirs[@]}" -type f \( -name '*.h' -o -name '*.cpp' \) | sort)
# One clang-format per file, KG_CI_JOBS at a time; each prints the name of
# a file it would change.
mapfile -t unformatted < <(printf '%s\0' "${files[@]}" |
  xargs -0 -n 1 -P "$KG_CI_JOBS" sh -c 'clang-format --dry-run --Werror "$1" >/dev/null 2>&1 || echo "$1"' sh |
  sort)
if ((${#unformatted[@]})); then
  {
    echo "clang-format: ${#unformatted[@]} of ${#files[@]} files are not formatted:"
    printf '  %s\n' "${unformatted[@]}"
    echo "fix with: clang-format -i <file>...  (see the diff with: clang-format --dry-run <file>)"
  } | tee "$KG_CI_REPORT"
  exit "$KG_CI_SOFT_FAILURE"
fi
echo "clang-format: all ${#files[@]} files formatted"
