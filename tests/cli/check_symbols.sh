#!/usr/bin/env bash
# What the built core and the portable fallback call (docs/architecture.md, "Portability"), read
# from their object files with nm:
# - Ridgeline::terrain touches no file system in any build: no fopen / open / rename / unlink,
#   no std::filesystem, no file streams (an engine embeds it on its own file system; files are
#   Ridgeline::io's);
# - with RIDGELINE_PORTABLE=ON, the durable write (io/durable_file.cpp, in Ridgeline::world), the
#   edit files of Ridgeline::io (io/edit_file.cpp) and the core make no POSIX call (open, write, fsync,
#   getpid, mmap, ...). The core's src/roam/ is left to the view's own portable fallback (its
#   memory reservation and SIMD dispatch), a separate change: add it here when it lands.
# Usage: check_symbols.sh BUILD_DIR ON|OFF (RIDGELINE_PORTABLE)
set -u
build=${1:?usage: check_symbols.sh BUILD_DIR ON|OFF}
portable=${2:?usage: check_symbols.sh BUILD_DIR ON|OFF}
core=$build/module/CMakeFiles/ridgeline_terrain.dir/src
io=$build/module/CMakeFiles/ridgeline_io.dir/src/io
world=$build/module/CMakeFiles/ridgeline_world.dir/src/io  # the durable write is Ridgeline::world's
[ -d "$core" ] || { echo "FAIL: no core objects in $core (build Ridgeline::terrain first)"; exit 1; }

# Undefined symbols of the given object files, as "object: symbol" (demangled).
undefined() {
  local o
  for o in "$@"; do
    nm -u -C "$o" | awk -v o="${o#"$build"/}" '{ print o ": " $NF }'
  done
}

files='^(fopen|fopen64|freopen|freopen64|fread|fwrite|rename|remove|tmpfile|open|open64|openat|creat|unlink|fsync|fdatasync|mkdir|opendir)$|std::filesystem|std::basic_(i|o)?fstream|std::basic_filebuf'
posix='^(open|open64|openat|close|read|write|pread|pread64|pwrite|pwrite64|lseek|lseek64|fsync|fdatasync|ftruncate|unlink|getpid|fstat|fstat64|stat|stat64|mmap|mmap64|munmap|madvise|mprotect|sysconf|fcntl|dup|dup2|opendir)$'

failed=0
mapfile -t core_objects < <(find "$core" -name '*.o' | sort)
found=$(undefined "${core_objects[@]}" | awk -F': ' -v re="$files" '$2 ~ re')
if [ -n "$found" ]; then
  echo "FAIL: the core (Ridgeline::terrain) touches the file system:"
  echo "$found" | sed 's/^/  /'
  failed=1
fi
if [ "$portable" = ON ]; then
  mapfile -t objects < <({ find "$core" -name '*.o' -not -path '*/src/roam/*'
                           find "$world" -name 'durable_file.cpp.o'
                           find "$io" -name 'edit_file.cpp.o'; } | sort)
  [ ${#objects[@]} -gt 2 ] || { echo "FAIL: no objects of io/durable_file.cpp and io/edit_file.cpp in $world and $io"; exit 1; }
  found=$(undefined "${objects[@]}" | awk -F': ' -v re="$posix" '$2 ~ re')
  if [ -n "$found" ]; then
    echo "FAIL: the portable build calls POSIX:"
    echo "$found" | sed 's/^/  /'
    failed=1
  fi
fi
[ $failed -eq 0 ] && echo "symbols: the core touches no file system$([ "$portable" = ON ] && echo "; no POSIX call in the portable core and durable write")"
exit $failed
