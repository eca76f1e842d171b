#!/usr/bin/env bash
# Facts the docs state that the code decides, compared with what the code gives, so that a change
# on either side fails here instead of leaving the reference wrong. Fails naming the page, what it
# says and what the code says.
# Usage: check_docs.sh REPO_ROOT [--ridge RIDGE] [--game GAME] [--tmp DIR]
#   always:  the README lists every page of docs/; lua_api.md says where ridgeline.so is installed
#            (the install rule's destination) and does not call it uninstalled; deformation.md's
#            edit file version is the one edit_file.cpp writes; no page names a commit, an issue
#            or the work's diary ("this round");
#   --ridge: data_model.md's default terrain content hash is what `ridge info --default-terrain`
#            prints; deformation.md's JSON edit list is accepted by `ridge deform`;
#   --game:  game.md's defaults of --detail-levels and --detail-amplitude are the game's --help's.
set -u
root=${1:?usage: check_docs.sh REPO_ROOT [--ridge RIDGE] [--game GAME] [--tmp DIR]}
shift
ridge="" game="" tmp=${TMPDIR:-/tmp}
while [ $# -gt 0 ]; do
  case $1 in
    --ridge) ridge=$2; shift 2 ;;
    --game) game=$2; shift 2 ;;
    --tmp) tmp=$2; shift 2 ;;
    *) echo "check_docs.sh: unknown argument '$1'"; exit 2 ;;
  esac
done
cd "$root" || exit 1
failed=0 checked=0
pass() { checked=$((checked + 1)); }
fail() { echo "FAIL: $*"; failed=1; }

# README: every page of docs/ is linked from the README.
for page in docs/*.md; do
  if grep -q "](${page})" README.md; then pass; else fail "README.md does not list $page"; fi
done

# lua_api.md: ridgeline.so's install destination, as the root CMakeLists.txt installs it.
dest=$(sed -n 's/.*install(TARGETS ridgeline_lua_module LIBRARY DESTINATION \([^ )]*\)).*/\1/p' CMakeLists.txt)
if [ -z "$dest" ]; then
  fail "CMakeLists.txt installs no ridgeline_lua_module: update this check and docs/lua_api.md"
elif ! grep -q "<prefix>/$dest/" docs/lua_api.md; then
  fail "docs/lua_api.md does not say ridgeline.so is installed in <prefix>/$dest/ (CMakeLists.txt installs it there)"
else
  pass
fi
if grep -n -i -E "not installed|install rules for" docs/lua_api.md; then
  fail "docs/lua_api.md calls something of the Lua binding uninstalled (lines above); CMakeLists.txt installs Ridgeline::lua and ridgeline.so"
else
  pass
fi

# Every page is reference: no commit hashes, issue numbers or work-diary words (history lives in
# git; the data files under docs/benchmarks/ may record the commit of their run).
diary=$(grep -nE "\bcommit [0-9a-f]{7,40}\b|\bat [0-9a-f]{7,12}\b|\bissues? #?[0-9]+\b|(^|[ (])#[0-9]{2,3}\b|\bthis (stop|round|session)\b" \
  README.md docs/*.md docs/*/*.md 2>/dev/null)
if [ -n "$diary" ]; then
  echo "$diary"
  fail "the lines above name a commit, an issue or the work's diary; docs are reference (say what is, with the command that shows it)"
else
  pass
fi

# deformation.md: the edit file's version.
code_version=$(sed -n 's/^constexpr std::uint32_t kVersion = \([0-9]*\);.*/\1/p' module/src/edit/edit_file.cpp)
doc_version=$(sed -n 's/^## The edit file (version \([0-9]*\).*/\1/p' docs/deformation.md)
if [ -n "$code_version" ] && [ "$code_version" = "$doc_version" ]; then
  pass
else
  fail "docs/deformation.md describes edit file version '${doc_version}'; module/src/edit/edit_file.cpp writes version '${code_version}'"
fi

if [ -n "$ridge" ]; then
  # data_model.md: the default terrain's content hash.
  doc_hash=$(sed -n 's/^| content hash | `\([0-9a-f]*\)`.*/\1/p' docs/data_model.md)
  out=$("$ridge" info --default-terrain 2>&1)
  code_hash=$(sed -n 's/.*"content_hash": *"\([0-9a-f]*\)".*/\1/p' <<< "$out" | head -1)
  if [ -n "$code_hash" ] && [ "$doc_hash" = "$code_hash" ]; then
    pass
  else
    fail "docs/data_model.md gives the default terrain's content hash as '${doc_hash}'; ridge info --default-terrain gives '${code_hash}'"
  fi

  # deformation.md: the JSON example is an edit list ridge deform accepts, with every edit.
  mkdir -p "$tmp"
  json=$tmp/docs_deformation_example.json
  awk '/^### Edit lists as JSON/ { in_section = 1 }
       in_section && /^```json/ { in_block = 1; next }
       in_block && /^```/ { exit }
       in_block { print }' docs/deformation.md > "$json"
  count=$(grep -c '"brush"' "$json")
  if [ "$count" -eq 0 ]; then
    fail "docs/deformation.md has no JSON example under \"### Edit lists as JSON\""
  elif out=$("$ridge" deform --default-terrain --edits "$json" 2>&1) &&
       [[ "$(tr -d ' \n' <<< "$out")" == *"\"edits\":$count,"* ]]; then
    pass
  else
    fail "docs/deformation.md's JSON example ($count edits) is not what ridge deform accepts: $out"
  fi
fi

if [ -n "$game" ]; then
  # game.md: the defaults of the detail options, as --help states them (from the code's defaults).
  # One line per option (CLI11 may put the description on the line after the option's name).
  help=$("$game" --help 2>&1 | awk '/^ *--/ { if (line != "") print line; line = $0; next }
                                   { line = line " " $0 } END { print line }')
  levels=$(sed -n 's/.*--detail-levels.*(0: none; default \([0-9]*\)).*/\1/p' <<< "$help")
  amplitude=$(sed -n 's/.*first detail octave, metres (default \([0-9.]*\)).*/\1/p' <<< "$help")
  row=$(grep -- '`--detail-levels N`' docs/game.md)
  level_word=level; [ "$levels" != 1 ] && level_word=levels
  if [ -n "$levels" ] && [ -n "$amplitude" ] &&
     [[ "$row" == *"default $levels $level_word, $amplitude m"* ]]; then
    pass
  else
    fail "docs/game.md says '$row'; the game's --help gives $levels detail level(s), amplitude $amplitude m"
  fi
fi

[ $failed -eq 0 ] && echo "docs: $checked facts match the code"
exit $failed
