#!/usr/bin/env bash
# End-to-end checks of the `ridge` tool: every subcommand, its output format, bad flags, bad
# files, bad CSV lines and exit codes (0 ok, 1 runtime error, 2 usage error).
# Environment: RIDGE (the binary), TEST_DATA (tests/data), TMPDIR (a scratch directory).
set -u
: "${RIDGE:?set RIDGE to the ridge binary}" "${TEST_DATA:?set TEST_DATA}" "${TMPDIR:=/tmp}"
T=$(mktemp -d "$TMPDIR/cli_ridge.XXXXXX")
trap 'rm -rf "$T"' EXIT
passed=0
failed=0

ok() { passed=$((passed + 1)); }
bad() { failed=$((failed + 1)); echo "FAIL: $1"; [ -n "${2:-}" ] && printf '  %s\n' "$2"; }

# run ARGS...: runs ridge, keeping stdout in $out, stderr in $err and the exit code in $rc.
run() {
  "$RIDGE" "$@" > "$T/stdout" 2> "$T/stderr"
  rc=$?
  out=$(cat "$T/stdout")
  err=$(cat "$T/stderr")
}

# expect NAME RC [STDERR_SUBSTRING]: checks the last run's exit code (and stderr text).
expect() {
  local name=$1 want=$2 text=${3:-}
  if [ "$rc" != "$want" ]; then
    bad "$name: exit $rc, want $want" "stderr: $err"
  elif [ -n "$text" ] && [[ "$err" != *"$text"* ]]; then
    bad "$name: stderr lacks '$text'" "stderr: $err"
  elif [ "$want" != 0 ] && [ -n "$out" ] && [ -z "${ALLOW_OUT:-}" ]; then
    bad "$name: failed but wrote to stdout" "stdout: $out"
  else
    ok
  fi
}

# contains NAME TEXT: the last run's stdout contains TEXT.
contains() {
  if [[ "$out" == *"$2"* ]]; then ok; else bad "$1: stdout lacks '$2'" "stdout: ${out:0:400}"; fi
}

# near NAME A B TOL: |A - B| <= TOL (floating point, through awk).
near() {
  if awk -v a="$2" -v b="$3" -v t="$4" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t) }'
  then ok; else bad "$1: $2 vs $3 (tolerance $4)"; fi
}

# json_num KEY: the number after "KEY": in $out (first occurrence).
json_num() { sed -n "s/.*\"$1\": *\([-0-9.eE+]*\).*/\1/p" <<< "$out" | head -1; }

# A 3 x 2 raw u16 heightmap: 10 20 30 / 40 0 60 (the 0 is used as no-data below).
printf '\x0a\x00\x14\x00\x1e\x00\x28\x00\x00\x00\x3c\x00' > "$T/h.r16"
PNG=$TEST_DATA/ramp16.png   # 5 x 4, 16-bit, value(i, j) = 1000 + 100 i + 10 j
RGB=$TEST_DATA/rgb8.png     # 4 x 3, 8-bit RGB: R = i, G = 10 + j, B = 200

# ---- help and usage ------------------------------------------------------------------------------
run --help; expect "ridge --help" 0
for s in info query profile bench; do contains "ridge --help lists $s" "$s"; done
for s in info query profile bench "bench queries"; do
  # shellcheck disable=SC2086
  run $s --help; expect "ridge $s --help" 0
done
run info --help; contains "info --help shows the terrain flags" "--raw-size"
run; expect "no subcommand" 2 "A subcommand is required"
run --version; expect "ridge --version" 0
[[ "$out" =~ ^ridge\ [0-9]+\.[0-9]+\.[0-9]+$ ]] && ok || bad "--version prints 'ridge X.Y.Z'" "$out"
run frobnicate; expect "unknown subcommand" 2 "unknown subcommand 'frobnicate' of ridge"
[[ "$err" == *"info, bake, query, profile"* ]] && ok || bad "unknown subcommand lists the subcommands" "$err"
run bench frobnicate --default-terrain; expect "unknown benchmark" 2 "unknown subcommand 'frobnicate' of ridge bench"
run info --default-terrain --no-such-flag; expect "unknown flag" 2 "--no-such-flag (see ridge info --help)"
run bench --default-terrain; expect "bench without a benchmark" 2
run info --default-terrain --heightmap "$PNG"; expect "--heightmap with --default-terrain" 2
# Missing required flags are usage errors (exit 2), as docs/cli.md says.
run info; expect "no terrain" 2 "no terrain given: pass --heightmap FILE, --world WORLD or --default-terrain"
run info --help; expect "--help without a terrain" 0
run mesh --default-terrain --threshold 2; expect "mesh without --out" 2 "--out is required"
run mesh --default-terrain --out "$T/m.glb"; expect "mesh without a LOD setting" 2 "give --threshold PX, --triangles N or --tolerance METRES"
run mesh --default-terrain --threshold 2 --out "$T/m.glb"; expect "mesh without a camera" 2 "give --eye X,Y,Z and --target X,Y,Z"
run bench lod --default-terrain --threshold 2; expect "bench lod without --path" 2 "--path is required"
run bench lod --default-terrain --path "$TEST_DATA/paths/flyover.json"; expect "bench lod without a LOD setting" 2 "--tolerance METRES"

# ---- output files ----------------------------------------------------------------------------------
run info --default-terrain --json "$T/no/such/dir/info.json"
expect "--json into a missing folder" 1 "the folder '$T/no/such/dir' does not exist"
run mesh --default-terrain --tolerance 20 --out "$T/no/such/dir/x.glb"
expect "--out into a missing folder" 1 "the folder '$T/no/such/dir' does not exist"
[ ! -e "$T/no" ] && ok || bad "nothing created for a missing folder"

# ---- mesh and bench lod: --tolerance, the stop reason --------------------------------------------
run bench lod --default-terrain --path "$TEST_DATA/paths/flyover.json" --tolerance 4 --error-every 0
expect "bench lod --tolerance" 0
contains "bench lod --tolerance converges" '"stopped_by": "converged"'
tris_tol=$(json_num triangles_median)
run mesh --default-terrain --tolerance 4 --out "$T/tol.glb"; expect "mesh --tolerance" 0
near "bench lod --tolerance gives the view-independent mesh of ridge mesh" "$(json_num triangles)" "$tris_tol" 0
run bench lod --default-terrain --path "$TEST_DATA/paths/flyover.json" --triangles 2000 --error-every 0
expect "bench lod --triangles" 0
contains "triangle cap stop reason" '"stopped_by": "triangle_budget"'
[[ "$out" != *'"stopped_by": "triangles"'* ]] && ok || bad "old stop reason spelling" "$out"
run mesh --default-terrain --eye 100,290,100 --target 600,170,500 --triangles 2000 --out "$T/capped.glb"
expect "mesh --triangles" 0
contains "mesh stop reason" '"stopped_by": "triangle_budget"'

# ---- info ----------------------------------------------------------------------------------------
run info --default-terrain; expect "info default" 0
contains "info default width" '"width": 1025'
contains "info default height" '"height": 1025'
contains "info default spacing" '"spacing": ['
contains "info default materials" '"has_materials": true'
hash1=$(sed -n 's/.*"content_hash": "\([0-9a-f]*\)".*/\1/p' <<< "$out")
bps=$(json_num bytes_per_sample)
near "info default bytes per sample in (4, 16)" "$bps" 10 6
[ "${#hash1}" = 16 ] && ok || bad "content hash is 16 hex digits: '$hash1'"
run info --default-terrain --json "$T/info.json"; expect "info --json" 0
[ -z "$out" ] && ok || bad "info --json FILE writes nothing to stdout" "$out"
grep -q "\"content_hash\": \"$hash1\"" "$T/info.json" && ok || bad "info --json file has the same hash"

run info --heightmap "$PNG" --spacing 10,2 --height-scale 0.5 --height-offset -100 --origin 1e6,-5
expect "info png" 0
contains "png width" '"width": 5'
contains "png height" '"height": 4'
near "png height_min = -100 + 0.5 * 1000" "$(json_num height_min)" 400 0
near "png height_max = -100 + 0.5 * 1430" "$(json_num height_max)" 615 0
contains "png extent" "\"extent\": ["
out_compact=$(tr -d ' \n' <<< "$out")
[[ "$out_compact" == *'"extent":[40.0,6.0]'* ]] && ok || bad "png extent is 40 x 6" "$out_compact"
[[ "$out_compact" == *'"origin":[1000000.0,-5.0]'* ]] && ok || bad "png origin" "$out_compact"

run info --heightmap "$T/h.r16" --raw-size 3,2 --raw-type u16
expect "info raw" 0
near "raw height_max" "$(json_num height_max)" 60 0
near "raw height_min" "$(json_num height_min)" 0 0
run info --heightmap "$T/h.r16" --raw-size 3,2; expect "raw type from .r16" 0
cp "$T/h.r16" "$T/h.raw"
run info --heightmap "$T/h.raw" --raw-size 3,2; expect "raw without type" 1 "--raw-type"
run info --heightmap "$T/h.raw"; expect "raw without size" 1 "--raw-size"
run info --heightmap "$T/h.r16" --raw-size 4,2 --raw-type u16
expect "raw size mismatch" 1 "file is 12 bytes but 4 x 2 u16 samples need 16 bytes"
run info --heightmap "$T/h.r16" --raw-size 3,2 --raw-type f32
expect "raw type mismatch" 1 "need 24 bytes"
run info --heightmap "$T/h.r16" --raw-size 3,2 --raw-type u8; expect "bad raw type" 1 "'u8'"
run info --heightmap "$T/h.r16" --raw-size 3.5,2; expect "fractional raw size" 1 "--raw-size"
run info --heightmap "$T/h.r16" --raw-size 1,12; expect "1 sample wide" 1 "1 x 12 samples; need at least 2 x 2"

# no-data and fill
run info --heightmap "$T/h.r16" --raw-size 3,2 --nodata 0
expect "no-data refused" 1 "sample (1, 1) is 0 (the no-data value)"
run info --heightmap "$T/h.r16" --raw-size 3,2 --nodata 0 --fill constant:5
expect "no-data constant fill" 0
near "filled_samples" "$(json_num filled_samples)" 1 0
near "fill constant is the new minimum" "$(json_num height_min)" 5 0
run info --heightmap "$T/h.r16" --raw-size 3,2 --nodata 0 --fill nearest; expect "nearest fill" 0
near "nearest fill minimum" "$(json_num height_min)" 10 0

# bad files
run info --heightmap "$T/missing.png"; expect "missing file" 1 "heightmap '$T/missing.png': no such file"
run info --heightmap "$T"; expect "directory" 1 "is a directory"
head -c 60 "$PNG" > "$T/truncated.png"
run info --heightmap "$T/truncated.png"; expect "truncated png" 1 "heightmap '$T/truncated.png'"
# One message, one line: nothing printed before it (libpng's own line) and no repeated reason.
if [ "$err" = "ridge: error: heightmap '$T/truncated.png': truncated PNG file: it ends inside the header of chunk 3 at byte 54 (60 bytes in all)" ]; then ok; else bad "truncated png: not one clear line" "stderr: $err"; fi
for n in 8 20 40 70 100 105; do
  head -c $n "$PNG" > "$T/cut.png"
  run info --heightmap "$T/cut.png"
  expect "png cut at $n bytes" 1 "ridge: error: heightmap '$T/cut.png': truncated PNG file: "
  [ "$(printf '%s\n' "$err" | wc -l)" = 1 ] && [ "$(grep -o truncated <<< "$err" | wc -l)" = 1 ] &&
    ok || bad "png cut at $n bytes: not one message on one line" "stderr: $err"
done
printf 'this is not a png at all, not even close.........' > "$T/garbage.png"
run info --heightmap "$T/garbage.png"; expect "garbage png" 1 "not a readable image"
run info --heightmap "$RGB"; expect "rgb refused" 1 "3 channels (R, G, B)"
run info --heightmap "$RGB" --channel 1; expect "rgb channel 1" 0
near "rgb green max = 12" "$(json_num height_max)" 12 0
run info --heightmap "$RGB" --channel 3; expect "rgb channel 3" 1 "channel 3 requested"
run info --heightmap "$PNG" --max-samples 19; expect "size cap" 1 "exceeds the limit of 19 samples (HeightfieldDesc::max_samples); raise it with --max-samples N"
run info --heightmap "$PNG" --max-samples 20; expect "size cap exact" 0
run info --default-terrain --max-samples 1000; expect "default terrain cap" 1 "exceeds the limit"
run info --heightmap "$PNG" --materials "$RGB"; expect "material size" 1 "material image"

# non-finite and malformed numbers in flags
for args in "--spacing nan" "--spacing inf" "--spacing -1" "--spacing 0" "--spacing 1,2,3" \
            "--spacing 1,nan" "--spacing abc" "--height-scale 0" "--height-scale -inf" \
            "--height-offset nan" "--origin 1" "--origin 1,2,3" "--origin nan,0" "--nodata nan" \
            "--fill sideways" "--fill constant:" "--fill constant:nan" "--max-samples 1.5" \
            "--max-samples -3" "--height-offset 1e999" "--spacing 1e-300" "--spacing 1e-7" \
            "--spacing 1,1e-300" "--spacing 2e6"; do
  # shellcheck disable=SC2086
  run info --default-terrain $args
  flag=${args%% *}
  expect "info $args" 1 "${flag%%=*}"
done
run info --default-terrain --spacing 1e-300
expect "absurd spacing names the range" 1 "--spacing '1e-300': spacing must be within 1e-6 .. 1e6 metres"
run info --heightmap "$PNG" --spacing 1e-6; expect "spacing of a micrometre" 0
run info --heightmap "$PNG" --spacing 1e6,1; expect "spacing of 1,000 km" 0
run info --default-terrain --spacing=; expect "empty --spacing=" 2
run info --default-terrain --spacing ""; expect "empty --spacing" 1 "--spacing"
run info --default-terrain --spacing 4 --origin 100,200 --height-offset 1000
expect "default terrain placed" 0
[[ "$(tr -d ' \n' <<< "$out")" == *'"extent":[4096.0,4096.0]'* ]] && ok || bad "placed extent"

# ---- GeoTIFF placement (real DEMs from Debian's r-cran-terra, fetched by the ctest fixture) ------
EX=${EXTERNAL_DATA:-}/terra/usr/lib/R/site-library/terra/ex
if [ -f "$EX/elev.tif" ] && [ -f "$EX/meuse.tif" ]; then
  # elev.tif: 1/120-degree cells at 49.8 N, about 598.8 x 926.7 m; 46 % no-data outside Luxembourg.
  run info --heightmap "$EX/elev.tif"; expect "elev.tif without a fill policy" 1 "(the no-data value)"
  run info --heightmap "$EX/elev.tif" --fill nearest; expect "info elev.tif" 0
  sx=$(tr -d ' \n' <<< "$out" | sed -n 's/.*"spacing":\[\([-0-9.e+]*\),\([-0-9.e+]*\)\].*/\1/p')
  sz=$(tr -d ' \n' <<< "$out" | sed -n 's/.*"spacing":\[\([-0-9.e+]*\),\([-0-9.e+]*\)\].*/\2/p')
  near "elev.tif spacing x within 1 % of 598.8 m" "$sx" 598.8 5.988
  near "elev.tif spacing z within 1 % of 926.7 m" "$sz" 926.7 9.267
  contains "elev.tif spacing source" '"spacing_source": "geotiff"'
  contains "elev.tif origin source" '"origin_source": "default"'
  contains "elev.tif pixel type" '"pixel_type": "int16"'
  contains "elev.tif placement described" 'GeoTIFF geographic (EPSG 4326)'
  contains "elev.tif filled warning in the output" '3942 of 8550 samples (46.1 %) are filled'
  [[ "$err" == *"warning:"*"46.1 %"* ]] && ok || bad "elev.tif filled warning logged" "$err"
  [[ "$err" == *"degrees give no origin in metres"* ]] && ok || bad "loader says the conversion" "$err"
  run info --heightmap "$EX/elev.tif" --fill nearest --spacing 30
  expect "info elev.tif --spacing" 0
  contains "--spacing overrides the file" '"spacing_source": "flag"'
  [[ "$(tr -d ' \n' <<< "$out")" == *'"spacing":[30.0,30.0]'* ]] && ok || bad "--spacing 30 used"
  # meuse.tif: projected (RD New), 40 m cells, tie point (178400, 334000) at the corner.
  run info --heightmap "$EX/meuse.tif" --fill nearest; expect "info meuse.tif" 0
  [[ "$(tr -d ' \n' <<< "$out")" == *'"spacing":[40.0,40.0]'* ]] && ok || bad "meuse spacing" "$out"
  [[ "$(tr -d ' \n' <<< "$out")" == *'"origin":[178420.0,-333980.0]'* ]] && ok || bad "meuse origin" "$out"
  contains "meuse origin source" '"origin_source": "geotiff"'
  run info --heightmap "$EX/meuse.tif" --fill nearest --origin 0,0; expect "meuse --origin" 0
  contains "--origin overrides the file" '"origin_source": "flag"'
  contains "--origin keeps the file's spacing" '"spacing_source": "geotiff"'
else
  bad "$EX/elev.tif or meuse.tif missing: the ctest fixture fetch_terra_data fetches r-cran-terra"
fi
run info --default-terrain; contains "default terrain pixel type" '"pixel_type": "float (generated)"'
contains "default terrain spacing source" '"spacing_source": "default"'
run info --heightmap "$T/h.r16" --raw-size 3,2; contains "raw pixel type" '"pixel_type": "u16"'
run info --heightmap "$T/h.r16" --raw-size 3,2 --nodata 0 --fill nearest
contains "1 of 6 filled is warned about in the output" '1 of 6 samples (16.7 %) are filled'
[[ "$err" == *"1 of 6 samples (16.7 %) are filled"* ]] && ok || bad "raw filled warning" "$err"

# ---- query ---------------------------------------------------------------------------------------
# On the ramp with spacing 10, scale 0.1, offset -50: height = -50 + 100 + x + z / 10 where the
# terrain is; a plane, so every face normal is (-1, 1, -0.1) / sqrt(2.01).
printf '15,5\n0.1,0\n\n40,30\n-1,0\n41,0\n 20 , 10 \r\n' > "$T/points.csv"
run query --heightmap "$PNG" --spacing 10 --height-scale 0.1 --height-offset -50 --points "$T/points.csv"
expect "query" 0
lines=$(wc -l < "$T/stdout")
[ "$lines" = 6 ] && ok || bad "query writes one line per point (6), got $lines" "$out"
IFS=, read -r x z h nx ny nz <<< "$(sed -n 1p "$T/stdout")"
near "query x" "$x" 15 0
near "query height" "$h" 65.5 1e-9
s=$(awk 'BEGIN { printf "%.17g", 1 / sqrt(2.01) }')
near "query nx" "$nx" "-$s" 1e-6
near "query ny" "$ny" "$s" 1e-6
near "query nz" "$nz" "$(awk -v s="$s" 'BEGIN { printf "%.17g", -0.1 * s }')" 1e-6
[ "$(sed -n 2p "$T/stdout" | cut -d, -f1)" = "0.10000000000000001" ] && ok ||
  bad "query writes 17 significant digits" "$(sed -n 2p "$T/stdout")"
near "query far corner is on the terrain" "$(sed -n 3p "$T/stdout" | cut -d, -f3)" 93 1e-9
[ "$(sed -n 4p "$T/stdout")" = "-1,0,,,," ] && ok || bad "off terrain: empty fields" "$(sed -n 4p "$T/stdout")"
[ "$(sed -n 5p "$T/stdout")" = "41,0,,,," ] && ok || bad "off terrain past the edge" "$(sed -n 5p "$T/stdout")"
[ "$(sed -n 6p "$T/stdout" | cut -d, -f1-3)" = "20,10,71" ] && ok ||
  bad "spaces and CRLF accepted" "$(sed -n 6p "$T/stdout")"
fields=$(sed -n 1p "$T/stdout" | awk -F, '{ print NF }')
[ "$fields" = 6 ] && ok || bad "query lines have 6 fields"
run query --default-terrain --points - < "$T/points.csv"; expect "query from stdin" 0
# A placement flag changes only what it names: --origin moves the default terrain and keeps its
# 2 m spacing, so a point 2,000 m in from the new origin is still on it (with 1 m it was off).
printf '%s\n' "2100,1200" "2148,1248" "2148,1249" > "$T/moved.csv"
run query --default-terrain --origin 100,-800 --points "$T/moved.csv"; expect "query --origin" 0
[ "$(sed -n 1p "$T/stdout" | cut -d, -f3)" != "" ] && ok ||
  bad "--origin keeps the default terrain's 2 m spacing (2,000 m in is on it)" "$out"
[ "$(sed -n 2p "$T/stdout" | cut -d, -f3)" != "" ] && ok || bad "--origin: far corner" "$out"
[ "$(sed -n 3p "$T/stdout")" = "2148,1249,,,," ] && ok || bad "--origin: past the far edge" "$out"
run info --default-terrain --origin 100,-800; expect "info --origin" 0
[[ "$(tr -d ' \n' <<< "$out")" == *'"extent":[2048.0,2048.0]'* ]] && ok ||
  bad "--origin keeps the 2,048 m extent" "$out"

for line in "1;2" "1,2,3" "nan,1" "1,inf" "1," ",1" "x,y" "1e999,0"; do
  printf '0,0\n1,1\n%s\n' "$line" > "$T/bad.csv"
  run query --default-terrain --points "$T/bad.csv"
  expect "query bad line '$line'" 1 "line 3"
done
run query --default-terrain; expect "query without --points" 2
run query --default-terrain --points "$T/none.csv"; expect "query missing points file" 1 "none.csv"
run query --heightmap "$T/missing.png" --points "$T/points.csv"; expect "query missing heightmap" 1 "no such file"

# ---- profile -------------------------------------------------------------------------------------
run profile --default-terrain --from 0,0 --to 2048,2048 --steps 48
expect "profile" 0
contains "profile title" "Profile of default terrain"
contains "profile summary" "Heights: min"
contains "profile sparkline" "sparkline"
rows=$(grep -cE '^ +[0-9]+ +[0-9.]+ +[0-9.]+ +[0-9.]+ +-?[0-9.]+$' <<< "$out")
[ "$rows" = 49 ] && ok || bad "profile table has 49 rows, got $rows"
# The plot's highest row is labelled with the maximum, and the max is at the top of a column.
grep -qE '^ +[0-9.]+ m \|.*#' <<< "$out" && ok || bad "profile plot has labelled rows"
run profile --heightmap "$PNG" --spacing 10 --from -10,0 --to 50,0 --steps 6 --json "$T/profile.json"
expect "profile partly off terrain" 0
contains "profile marks off-terrain points" "off"
grep -q '"height": null' "$T/profile.json" && ok || bad "profile JSON has null heights off terrain"
grep -q '"height": 1200.0' "$T/profile.json" && ok || bad "profile JSON has the height at x=20" "$(cat "$T/profile.json")"
run profile --default-terrain --from 0,0 --to 1,1 --steps 0; expect "profile steps 0" 1 "--steps"
run profile --default-terrain --from nan,0 --to 1,1; expect "profile nan" 1 "--from"
run profile --default-terrain --from 0,0; expect "profile without --to" 2
run profile --default-terrain --from 0,0 --to 1; expect "profile bad --to" 1 "--to"

# ---- bench queries -------------------------------------------------------------------------------
run bench queries --heightmap "$PNG" --points 2000 --repetitions 1 --seed 3
expect "bench queries" 0
contains "bench JSON names the terrain" '"terrain"'
for key in height_ns height_normal_ns vertical_ray_ns slanted_ray_ns; do
  v=$(json_num "$key")
  if [ -n "$v" ] && awk -v v="$v" 'BEGIN { exit !(v > 0) }'; then ok; else bad "bench $key > 0: '$v'"; fi
done
contains "bench JSON gives the point count" '"points": 2000'
run bench queries --heightmap "$PNG" --points 2000 --repetitions 1 --json "$T/bench.json"
expect "bench queries --json" 0
grep -q '"terrain"' "$T/bench.json" && ok || bad "bench --json file"
run bench queries --default-terrain --points 0; expect "bench points 0" 1 "--points"
run bench queries --default-terrain --repetitions x; expect "bench bad repetitions" 1 "--repetitions"
run bench queries --default-terrain --spacing nan; expect "bench bad terrain flag" 1 "--spacing"

# ---- deform, --load, bench deform ----------------------------------------------------------------
cat > "$T/edits.json" <<'JSON'
{"edits": [{"brush": "crater", "x": 1000, "z": 1000, "radius": 20, "depth": 5},
           {"brush": "flatten", "x": 300, "z": 400, "radius": 30, "height": 100},
           {"brush": "raise", "x": 9000, "z": 9000, "radius": 5}]}
JSON
run query --default-terrain --points <(echo "1000,1000"); before="$out"
run deform --default-terrain --edits "$T/edits.json" --save "$T/state.bin"
expect "deform" 0
contains "deform counts the no-op edit" '"edits_empty": 1'
hash=$(sed -n 's/.*"heights_hash": "\([0-9a-f]*\)".*/\1/p' <<< "$out")
[ -s "$T/state.bin" ] && ok || bad "deform --save wrote the state"
run query --default-terrain --load "$T/state.bin" --points <(echo "1000,1000")
expect "query --load" 0
[ "$out" != "$before" ] && ok || bad "query --load sees the crater" "$out"
echo '{"edits": []}' > "$T/none.json"
run deform --default-terrain --load "$T/state.bin" --edits "$T/none.json"
contains "deform --load restores the same heights hash" "\"heights_hash\": \"$hash\""
run deform --default-terrain --spacing 3 --load "$T/state.bin" --edits "$T/none.json"
expect "--load onto another terrain" 1 "another terrain"
head -c 100 "$T/state.bin" > "$T/cut.bin"
run info --default-terrain --load "$T/cut.bin"; expect "--load truncated" 1 "truncated"
cat > "$T/holes.json" <<'JSON'
{"edits": [{"brush": "hole", "x": 501, "z": 301, "radius": 3},
           {"brush": "hole", "x": 801, "z": 301, "radius": 3},
           {"brush": "fill_hole", "x": 801, "z": 301, "radius": 3}]}
JSON
run deform --default-terrain --edits "$T/holes.json" --save "$T/holes.bin"
expect "deform hole and fill_hole" 0
contains "deform counts the hole cells (3 x 3 cells of 2 m, three times)" '"hole_cells_changed": 27'
contains "deform leaves one hole" '"hole_cells": 9'
run deform --default-terrain --load "$T/holes.bin" --edits "$T/none.json"
contains "deform --load brings the hole back" '"hole_cells": 9'
echo '{"edits": [{"brush": "crater", "x": 1, "z": 1}]}' > "$T/e1.json"
run deform --default-terrain --edits "$T/e1.json"
expect "deform edit without radius" 1 "edits[0]: 'radius' is missing"
echo '{"edits": [{"brush": "dig", "x": 1, "z": 1, "radius": 2}]}' > "$T/e2.json"
run deform --default-terrain --edits "$T/e2.json"
expect "deform unknown brush" 1 "unknown brush 'dig'"
echo '{"edits": [{"brush": "crater", "x": 1, "z": 1, "radius": 1e9}]}' > "$T/e3.json"
run deform --default-terrain --edits "$T/e3.json"
expect "deform radius larger than the terrain" 1 "larger than the terrain"
run bench deform --default-terrain --count 5 --radii 5,20
expect "bench deform" 0
contains "bench deform reports medians" '"median_ms"'

# ---- bench detail --------------------------------------------------------------------------------
# A short synchronous flight over the default terrain (2 km), 3 levels: the JSON's figures.
run bench detail --default-terrain --detail-levels 3 --tile-reps 3 --workers 0 --distance 200 \
  --frames-every 10 --json "$T/detail.json"
expect "bench detail" 0
out=$(cat "$T/detail.json")
[ "$(grep -c '"level":' "$T/detail.json")" = 3 ] && ok || bad "bench detail: one tile figure per level"
contains "bench detail tile bytes" '"tile_bytes": 73004'
contains "bench detail frames" '"frames": 41,'
contains "bench detail virtual samples" '"virtual_samples": 67125249.0'
# Synchronous: every needed tile is there every frame, within the budget.
contains "bench detail needed tiles resident" '"needed_resident_fraction_min": 1.0'
contains "bench detail no late tile" '"worst_late_frames": 0,'
contains "bench detail within budget" '"resident_within_budget": true'
run bench detail --default-terrain --detail-levels 2 --tile-reps 3 --workers 2 --no-pace \
  --distance 100 --frames-every 0 --budget-mb 8
expect "bench detail asynchronous" 0
contains "bench detail asynchronous mode" '"mode": "asynchronous"'
run bench detail --default-terrain --detail-levels 2 --detail-gain 1.5
expect "bench detail bad gain" 1 "gain is 1.5"
run bench detail --default-terrain --detail-levels 13
expect "bench detail too many levels" 1 "--detail-levels"
run bench detail --default-terrain --detail-levels 0
expect "bench detail no levels" 1 "--detail-levels must be >= 1"
run bench detail --default-terrain --detail-levels 2 --detail-seed -1
expect "bench detail bad seed" 1 "--detail-seed"
run bench detail --default-terrain --detail-levels 2 --pixels 0
expect "bench detail bad pixels" 1 "pixels is 0"
run bench detail --default-terrain --detail-levels 2 --budget-mb 0.1
expect "bench detail budget below one tile per level" 1 "budget"
run bench detail --default-terrain --detail-levels 2 --budget-mb 8 --terrain-budget-mb 8
expect "bench detail two budgets" 1 "exclude each other"
run bench detail --default-terrain --detail-levels 2 --terrain-budget-mb 4
expect "bench detail terrain budget below the base" 1 "already take"
run bench detail --default-terrain --detail-levels 2 --from 5000,5000
expect "bench detail start off the terrain" 1 "off the terrain"
run bench detail --default-terrain --detail-levels 2 --speed 0
expect "bench detail speed 0" 1 "--speed"
run bench detail --default-terrain --detail-levels 2 --path "$T/missing.json"
expect "bench detail missing path" 1 "missing.json"
run bench detail --default-terrain --detail-levels 2 --path "$T/missing.json" --distance 5
expect "bench detail path with built-in flight flags" 1 "not with --path"
run bench detail --default-terrain --detail-levels 2 --detail-budget-mb 8
expect "bench detail refuses the query cache budget" 1 "--budget-mb"
run bench detail --default-terrain --detail-levels 2 --detail-flat-shape 2
expect "bench detail bad flat shape" 1 "flat shape is 2"
run info --default-terrain --detail-blur-radius 3
expect "detail shape flag without levels" 1 "--detail-blur-radius needs --detail-levels"
run info --heightmap "$PNG" --default-size 9
expect "default size without the default terrain" 1 "--default-size applies"
run info --default-terrain --default-size 1
expect "default size 1" 1 "--default-size"
run info --default-terrain --default-size 65
expect "default size 65" 0
contains "default size 65 gives 65 samples" '"width": 65'

# ---- procedural detail flags -----------------------------------------------------------------------
run info --heightmap "$PNG" --spacing 8 --detail-levels 3 --detail-seed 4
expect "info with detail" 0
contains "info reports the detail levels" '"detail_levels": 3'
contains "info reports the finest spacing" '"finest_spacing": ['
run info --default-terrain --detail-seed 4; expect "detail seed without levels" 1 "--detail-seed needs --detail-levels"
run info --default-terrain --detail-levels 13; expect "too many detail levels" 1 "--detail-levels"
run info --default-terrain --detail-levels 2 --detail-gain 0; expect "bad detail gain" 1 "gain is 0"
run mesh --heightmap "$PNG" --spacing 8 --detail-levels 2 --detail-amplitude 0.5 --eye 16,1700,-30 --target 16,1200,12 --threshold 1 --out "$T/detail.glb"
expect "mesh with detail" 0
[ -s "$T/detail.glb" ] && ok || bad "mesh with detail wrote a file"

echo "$passed passed, $failed failed"
[ "$failed" = 0 ]
