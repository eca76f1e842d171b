#!/usr/bin/env bash
# Every planted fault of tests/planted_faults.txt still applies to the tree (git apply --check):
# a patch whose line moved would otherwise be found only by the next full replay
# (scripts/planted_faults.sh, docs/reliability/planted_faults.md). Fails naming the patch and
# how to make it again.
# Usage: check_planted_faults.sh REPO_ROOT
set -u
root=${1:?usage: check_planted_faults.sh REPO_ROOT}
cd "$root" || exit 1
failed=0 checked=0
while read -r name _; do
  case $name in '' | '#'*) continue ;; esac
  patch=tests/planted_faults/$name.patch
  if [ ! -f "$patch" ]; then
    echo "FAIL: tests/planted_faults.txt lists $name, but $patch does not exist"
    failed=1
  elif ! out=$(git apply --check "$patch" 2>&1); then
    echo "FAIL: $patch no longer applies (its line moved or changed): make it again as the same one-line fault with git diff; $out"
    failed=1
  fi
  checked=$((checked + 1))
done < tests/planted_faults.txt
[ "$checked" -gt 0 ] || { echo "FAIL: tests/planted_faults.txt lists no fault"; exit 1; }
[ "$failed" -eq 0 ] && echo "planted faults: $checked patches apply"
exit "$failed"
