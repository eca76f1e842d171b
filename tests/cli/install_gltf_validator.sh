#!/usr/bin/env bash
# Installs Khronos' glTF-Validator (npm package gltf-validator, pinned) into DIR/node_modules
# unless it is there: the ctest fixture of cli_glb_validator, and scripts/test.sh before its
# stages. Needs node and npm (Debian: apt-get install nodejs npm; scripts/test.sh installs them).
# Usage: install_gltf_validator.sh DIR
set -uo pipefail
dir=${1:?usage: install_gltf_validator.sh DIR}
version=2.0.0-dev.3.10
if [ -f "$dir/node_modules/gltf-validator/package.json" ] &&
   grep -q "\"version\": \"$version\"" "$dir/node_modules/gltf-validator/package.json"; then
  echo "gltf-validator $version: already in $dir"; exit 0
fi
for tool in node npm; do
  command -v $tool > /dev/null ||
    { echo "error: $tool not found: install nodejs and npm (apt-get install nodejs npm)"; exit 1; }
done
mkdir -p "$dir" || exit 1
if ! npm install --prefix "$dir" --no-audit --no-fund --no-save "gltf-validator@$version" > "$dir.log" 2>&1; then
  echo "error: npm install gltf-validator@$version into $dir failed:"; tail -20 "$dir.log"; exit 1
fi
echo "gltf-validator $version: installed in $dir"
