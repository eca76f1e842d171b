#!/usr/bin/env bash
# Replays the planted faults of docs/reliability/planted_faults.md: for each line of
# tests/planted_faults.txt it applies the one-line fault tests/planted_faults/NAME.patch to the
# source tree, rebuilds the targets the line names in BUILD_DIR, runs the tests its ctest regex
# selects and reports "caught" when one of them fails, "NOT caught" when they all pass. The fault
# is reverted before the next one (and on exit, Ctrl-C included); at the end the targets are
# rebuilt from the clean tree, so the build dir never keeps a faulty binary.
#
# First (unless --no-baseline) the same tests run on the clean tree: they must pass, or a fault
# "caught" by them would mean nothing.
#
# Usage: scripts/planted_faults.sh [BUILD_DIR] [--no-baseline] [NAME ...]
#   BUILD_DIR  a configured build (default build/release; relative to the repository root)
#   NAME       replay only these faults (default: every line of tests/planted_faults.txt)
# Exits 0 when every fault replayed is caught, 1 otherwise (or when a patch does not apply, a
# build fails, or the baseline fails). JOBS (default 2) sets the build's parallelism.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root" || exit 1
list=tests/planted_faults.txt
build=build/release
baseline=1
only=()
for a in "$@"; do
  case "$a" in
    --no-baseline) baseline=0 ;;
    -h | --help) sed -n '2,17p' "$0"; exit 0 ;;
    *) if [ -d "$a" ] && [ ${#only[@]} -eq 0 ] && [ "$build" = build/release ]; then build=$a; else only+=("$a"); fi ;;
  esac
done
[ -f "$build/CTestTestfile.cmake" ] || { echo "planted_faults: $build is not a configured build dir"; exit 1; }
jobs=${JOBS:-2}
log_dir=$(mktemp -d "${TMPDIR:-/tmp}/planted_faults.XXXXXX")

# name targets regex, one fault a line (comments and blank lines skipped).
names=() targets=() regexes=()
while read -r name tgts regex rest; do
  [[ -z "$name" || "$name" == \#* ]] && continue
  if [ ${#only[@]} -gt 0 ] && [[ " ${only[*]} " != *" $name "* ]]; then continue; fi
  [ -f "tests/planted_faults/$name.patch" ] || { echo "planted_faults: no tests/planted_faults/$name.patch"; exit 1; }
  [ -n "$regex" ] || { echo "planted_faults: $list: line '$name' lacks its ctest regex"; exit 1; }
  names+=("$name") targets+=("${tgts//,/ }") regexes+=("$regex")
done < "$list"
[ ${#names[@]} -gt 0 ] || { echo "planted_faults: no fault selected"; exit 1; }

applied=""
revert() {
  if [ -n "$applied" ]; then
    git apply -R "tests/planted_faults/$applied.patch" || echo "planted_faults: could not revert $applied: fix the tree by hand"
    applied=""
  fi
}
trap 'revert' EXIT
trap 'revert; exit 130' INT TERM

build_targets() {  # targets... ; output to $log_dir/build.log
  nice -n 10 cmake --build "$build" -j "$jobs" --target "$@" > "$log_dir/build.log" 2>&1
}
run_tests() {  # regex logfile
  (cd "$build" && nice -n 10 ctest -j "$jobs" -R "$1" --no-tests=error --output-on-failure \
    --timeout 900 > "$2" 2>&1)
}
read -r -a all_targets <<< "$(printf '%s\n' "${targets[@]}" | tr ' ' '\n' | sort -u | tr '\n' ' ')"

if [ $baseline -eq 1 ]; then
  echo "== baseline: building ${all_targets[*]}"
  build_targets "${all_targets[@]}" || { echo "planted_faults: the clean tree does not build ($log_dir/build.log)"; exit 1; }
  joined=$(IFS='|'; echo "${regexes[*]}")
  if ! run_tests "$joined" "$log_dir/baseline.log"; then
    echo "planted_faults: the tests fail on the clean tree; see $log_dir/baseline.log"
    sed -n '/The following tests FAILED/,$p' "$log_dir/baseline.log"
    exit 1
  fi
  echo "== baseline: the tests pass without any fault"
fi

missed=0
for k in "${!names[@]}"; do
  name=${names[$k]}
  patch=tests/planted_faults/$name.patch
  printf '%-36s ' "$name"
  if ! git apply --check "$patch" 2> "$log_dir/$name.apply"; then
    echo "PATCH DOES NOT APPLY ($(head -1 "$log_dir/$name.apply"))"
    missed=$((missed + 1))
    continue
  fi
  git apply "$patch" && applied=$name
  read -r -a these <<< "${targets[$k]}"
  if ! build_targets "${these[@]}"; then
    cp "$log_dir/build.log" "$log_dir/$name.build.log"
    echo "BUILD FAILED (see $log_dir/$name.build.log)"
    missed=$((missed + 1))
    revert
    continue
  fi
  if run_tests "${regexes[$k]}" "$log_dir/$name.log"; then
    echo "NOT caught by ${regexes[$k]}"
    missed=$((missed + 1))
  else
    failed=$(sed -n 's/^[[:space:]]*[0-9]* - \([^ ]*\) .*$/\1/p' "$log_dir/$name.log" | tr '\n' ' ')
    echo "caught: ${failed:-see $log_dir/$name.log}"
  fi
  revert
done

echo "== rebuilding ${all_targets[*]} from the clean tree"
build_targets "${all_targets[@]}" || echo "planted_faults: the clean rebuild failed ($log_dir/build.log)"
echo "logs: $log_dir"
if [ $missed -gt 0 ]; then
  echo "planted_faults: $missed of ${#names[@]} faults not caught"
  exit 1
fi
echo "planted_faults: all ${#names[@]} faults caught"
