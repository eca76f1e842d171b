#!/usr/bin/env bash
# `ridge mesh` writes a .glb that Khronos' glTF-Validator (npm package gltf-validator) accepts.
# The validator comes from the ctest fixture install_gltf_validator (tests/cli/
# install_gltf_validator.sh); without node or the validator this test fails, naming what is
# missing (it never skips).
set -uo pipefail
validator_dir=${GLTF_VALIDATOR_DIR:-}
if ! command -v node >/dev/null; then
  echo "FAIL: node not found (apt-get install nodejs npm)"; exit 1
fi
if [ -z "$validator_dir" ] || [ ! -d "$validator_dir/node_modules/gltf-validator" ]; then
  echo "FAIL: no gltf-validator in '$validator_dir' (tests/cli/install_gltf_validator.sh installs it)"
  exit 1
fi
out=$TMPDIR/validate_glb
mkdir -p "$out"
fail=0
check() {
  local name=$1; shift
  "$RIDGE" mesh "$@" --out "$out/$name.glb" --json "$out/$name.json" || { echo "FAIL $name: ridge mesh"; fail=1; return; }
  if NODE_PATH="$validator_dir/node_modules" node -e '
    const v = require("gltf-validator"); const fs = require("fs");
    v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[1]))).then(r => {
      console.log(process.argv[1] + ": " + r.issues.numErrors + " errors, " + r.issues.numWarnings + " warnings");
      process.exit(r.issues.numErrors || r.issues.numWarnings ? 1 : 0); });' "$out/$name.glb"; then
    echo "ok $name"
  else
    echo "FAIL $name: validator"; fail=1
  fi
}
check view --default-terrain --eye 100,300,100 --target 1000,50,1000 --threshold 2
check tolerance --default-terrain --tolerance 4
check far --default-terrain --origin 10000000,-10000000 --eye 10000100,300,-9999900 --target 10001000,50,-9999000 --triangles 20000
exit $fail
