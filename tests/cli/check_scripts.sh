#!/usr/bin/env bash
# One build layout (README, "One build layout"): build/release is configured in one place,
# scripts/lib/common.sh's build_release, with RIDGELINE_RELEASE_ARGS. Fails when a script runs
# cmake's configure step itself, or hands build/release to configure / configure_and_build
# (which would configure it with other options than every other script).
# Usage: check_scripts.sh REPO_ROOT
set -u
root=${1:?usage: check_scripts.sh REPO_ROOT}
failed=0
# cmake's configure step, and configure / configure_and_build given build/release.
cmake_configure='cmake[[:space:]]+(-S|-B|-G)'
release='(\$RIDGELINE_ROOT/)?(build/release|\$RIDGELINE_RELEASE_DIR|\$\{RIDGELINE_RELEASE_DIR\})'
configure_release="(^|[[:space:];&|(])(configure|configure_and_build)[[:space:]]+[\"']?$release"
for f in "$root"/scripts/*.sh "$root"/scripts/lib/*.sh "$root"/.ci/run; do
  [ -f "$f" ] || continue
  rel=${f#"$root"/}
  [ "$rel" = scripts/lib/common.sh ] && continue
  n=0
  while IFS= read -r line; do
    n=$((n + 1))
    code=${line%%#*}  # comments may name the commands
    if [[ "$code" =~ $cmake_configure ]]; then
      echo "FAIL: $rel:$n configures a build with cmake itself (use common.sh's build_release or configure): $line"
      failed=1
    elif [[ "$code" =~ $configure_release ]]; then
      echo "FAIL: $rel:$n configures build/release outside build_release: $line"
      failed=1
    fi
  done < "$f"
done
# The one configuration: build_release passes RIDGELINE_RELEASE_ARGS, and only it names them.
grep -q 'configure "$dir" "${RIDGELINE_RELEASE_ARGS\[@\]}"' "$root/scripts/lib/common.sh" || {
  echo "FAIL: scripts/lib/common.sh's build_release no longer configures with RIDGELINE_RELEASE_ARGS"
  failed=1
}
if [ $failed -eq 0 ]; then echo "scripts: build/release is configured by build_release only"; fi
exit $failed
