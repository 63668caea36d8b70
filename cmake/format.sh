#!/usr/bin/env bash
# cmake/format.sh [--fix] — every tracked C++ file against the repository's .clang-format
# (clang-format from Debian; cmake/setup.sh installs it). Without --fix: lists the files that
# differ and the command that fixes them, exit 1. With --fix: rewrites them in place.
# tests/run.sh (and so CI) runs the check.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
if ! command -v clang-format >/dev/null; then
  echo "cmake/format.sh: clang-format not found (Debian: apt-get install clang-format)" >&2
  exit 1
fi
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files -- '*.cpp' '*.hpp' '*.h' '*.cc')
else  # a tarball: every C++ file outside the build folders
  mapfile -t files < <(find . -path './build*' -prune -o \( -name '*.cpp' -o -name '*.hpp' \
                            -o -name '*.h' -o -name '*.cc' \) -type f -print | sed 's|^\./||' | sort)
fi
if [[ ${1:-} == --fix ]]; then
  printf '%s\0' "${files[@]}" | xargs -0 -n 16 -P "$(nproc)" clang-format --style=file -i
  exit 0
fi
mapfile -t bad < <(printf '%s\0' "${files[@]}" | xargs -0 -n 1 -P "$(nproc)" \
  sh -c 'clang-format --style=file --dry-run --Werror "$0" >/dev/null 2>&1 || echo "$0"' | sort)
if ((${#bad[@]})); then
  echo "cmake/format.sh: ${#bad[@]} of ${#files[@]} C++ files differ from .clang-format ($(clang-format --version | grep -o 'version [0-9.]*')):" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix them with:  cmake/format.sh --fix   (or: clang-format -i FILE...)" >&2
  exit 1
fi
echo "cmake/format.sh: ${#files[@]} C++ files follow .clang-format"
