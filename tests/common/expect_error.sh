#!/usr/bin/env bash
# expect_error.sh EXPECTED -- COMMAND...
# Runs COMMAND (an mpiexec line) with a time limit and passes when it exits non-zero (not by the
# time limit), prints EXPECTED (a fixed string) on stderr, and prints the error line exactly once.
set -u
expected=$1
shift
[[ $1 == "--" ]] && shift
out=$(timeout 60 "$@" 2>&1)
rc=$?
echo "$out"
if [[ $rc -eq 124 ]]; then echo "FAIL: timed out (hang)"; exit 1; fi
if [[ $rc -eq 0 ]]; then echo "FAIL: exit status 0, expected an error"; exit 1; fi
if ! grep -qF -- "$expected" <<<"$out"; then echo "FAIL: message does not contain: $expected"; exit 1; fi
n=$(grep -c "^coloc: error:" <<<"$out")
if [[ $n -gt 1 ]]; then echo "FAIL: the error was printed $n times"; exit 1; fi
echo "PASS: exit $rc with: $expected"
