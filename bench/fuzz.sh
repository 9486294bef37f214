#!/usr/bin/env bash
# Runs every fuzz target of fuzz/ for SECONDS each (default 60) and prints, per target,
# executions and crashes; the last line is exactly `fuzz_crashes=<int>` (all targets, this run).
#
#   bash bench/fuzz.sh 600
#   bash bench/fuzz.sh 600 fuzz_mesh_import fuzz_yaml     # some targets only
#
# The C++ targets (fuzz/fuzz_*.cpp) are libFuzzer executables of an instrumented copy of
# the core built with clang (ASan, UBSan, libFuzzer coverage) in build-fuzz/; fuzz_yaml is
# the Python harness of scenario and scene-file validation (fuzz/fuzz_yaml.py, run with
# .venv: `make install` first). Working corpora live in build-fuzz/corpus/<target>/, seeded
# from fuzz/corpus/<target>/ (committed), Debian's assimp-testmodels, ../shared/assets (the
# Cornell box's OBJ meshes, Kenney's GLB vehicles, their PNG/EXR images; files up to
# 200 kB, larger ones as their first 64 kB) and scenarios/ (fuzz_yaml); every
# crash input is copied to fuzz/corpus/<target>/crash-<sha1> (fix the bug, commit the input:
# `make test` replays it).
set -uo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET="${1:-60}"
shift || true
ONLY="$*"
JOBS="${JOBS:-$(nproc)}"
BUILD=build-fuzz

if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DSYNTHGEN_FUZZ=ON \
    -DSYNTHGEN_BUILD_PYTHON=OFF -DSYNTHGEN_BUILD_TESTS=OFF -DSYNTHGEN_PORTABLE=ON > "$BUILD.log" 2>&1 \
    || { cat "$BUILD.log"; echo "fuzz_crashes=-1"; exit 1; }
fi
cmake --build "$BUILD" -j "$JOBS" >> "$BUILD.log" 2>&1 || { tail -30 "$BUILD.log"; echo "fuzz_crashes=-1"; exit 1; }
export SYNTHGEN_IMAGE_IO_PLUGIN="$PWD/$BUILD/libsynthgen_oiio.so"
export SYNTHGEN_VDB_PLUGIN="$PWD/$BUILD/libsynthgen_vdb.so"
export SYNTHGEN_READER="$PWD/$BUILD/synthgen-reader"   # the instrumented reader (fuzz_mesh_import)
# Leaks inside Debian's uninstrumented libraries are not ours; UBSan stops at the first report.
# A sanitizer report exits with status 86 (how fuzz_mesh_import recognizes one from
# synthgen-reader); SEGV is left to the default action (a crash inside uninstrumented assimp
# in the reader is then a signal, which synthgen handles, not a report; libFuzzer catches a
# SEGV of the target itself).
export ASAN_OPTIONS="detect_leaks=0:allocator_may_return_null=1:exitcode=86:handle_segv=0:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:exitcode=86:${UBSAN_OPTIONS:-}"

seed_extra() {  # target -> extra seed files (third-party, not committed)
  case "$1" in
    fuzz_mesh_import)
      for f in $(dpkg -L assimp-testmodels 2>/dev/null | grep -E '/(OBJ|PLY|glTF2)/[^/]*\.(obj|ply|gltf|glb)$' | head -200); do
        [ -f "$f" ] && [ "$(stat -c %s "$f")" -lt 200000 ] || continue
        case "$f" in *.obj) b=0;; *.ply) b=1;; *.gltf) b=2;; *.glb) b=3;; esac
        out="$2/assimp-$(sha1sum "$f" | cut -c1-12)"
        { printf "\\x0$b"; cat "$f"; } > "$out"
      done
      for f in $(find ../shared/assets -type f \( -name '*.obj' -o -name '*.glb' -o -name '*.gltf' -o -name '*.ply' \) 2>/dev/null); do
        [ "$(stat -c %s "$f")" -lt 200000 ] || continue
        case "$f" in *.obj) b=0;; *.ply) b=1;; *.gltf) b=2;; *.glb) b=3;; esac
        { printf "\\x0$b"; cat "$f"; } > "$2/shared-$(sha1sum "$f" | cut -c1-12)"
      done ;;
    fuzz_image)  # high bit: through a file, as synthgen reads textures and photos
      for f in $(find ../shared/assets -type f \( -name '*.png' -o -name '*.jpg' -o -name '*.exr' -o -name '*.hdr' \) 2>/dev/null); do
        case "$f" in *.png) b=80;; *.jpg) b=81;; *.exr) b=82;; *.hdr) b=83;; esac
        { printf "\\x$b"; head -c 65536 "$f"; } > "$2/shared-$(sha1sum "$f" | cut -c1-12)"
      done ;;
    fuzz_photo)  # photos whole, cut at a quarter and 40 bytes before the end (JPEG, PNG, EXR)
      for f in $(find ../shared/assets -type f \( -name '*.png' -o -name '*.jpg' -o -name '*.exr' \) 2>/dev/null); do
        [ "$(stat -c %s "$f")" -lt 65536 ] || continue
        case "$f" in *.jpg) b=00;; *.png) b=01;; *.exr) b=02;; esac
        n=$(stat -c %s "$f")
        for keep in "$n" $((n / 4)) $((n - 40)); do
          { printf "\\x$b"; head -c "$keep" "$f"; } > "$2/shared-$keep-$(sha1sum "$f" | cut -c1-12)"
        done
      done ;;
  esac
}

selected() { [ -z "$ONLY" ] || [[ " $ONLY " == *" $1 "* ]]; }

report() {  # name log crashes-dir corpus-dir
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$2" | grep -o '[0-9]*$' | tail -1)
  # A run that stopped at a crash prints no final stats: its last status line has the count.
  [ -n "$execs" ] || execs=$(grep -oE '^#[0-9]+' "$2" | tr -d '#' | tail -1)
  crashes=$(find "$3" -type f ! -name '*.txt' 2>/dev/null | wc -l)
  for c in "$3"/*; do
    [ -f "$c" ] || continue
    case "$c" in *.txt) continue;; esac
    base=$(basename "$c")
    case "$base" in crash-scenario-*|crash-scene-*) dest="$base";; *) dest="crash-$(sha1sum "$c" | cut -c1-12)";; esac
    cp "$c" "fuzz/corpus/$1/$dest"
  done
  echo "$1: executions=${execs:-0} crashes=$crashes seconds=$SECONDS_PER_TARGET corpus=$(ls "$4" | wc -l)"
  total=$((total + crashes))
}

total=0
for bin in "$BUILD"/fuzz_*; do
  [ -x "$bin" ] || continue
  name=$(basename "$bin")
  selected "$name" || continue
  corpus="$BUILD/corpus/$name"
  crashes_dir="$BUILD/crashes/$name"
  rm -rf "$crashes_dir"
  mkdir -p "$corpus" "$crashes_dir"
  cp -n fuzz/corpus/"$name"/* "$corpus"/ 2>/dev/null
  seed_extra "$name" "$corpus"
  log="$BUILD/$name.log"
  "$bin" "$corpus" -max_total_time="$SECONDS_PER_TARGET" -timeout=25 -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$crashes_dir/" > "$log" 2>&1
  report "$name" "$log" "$crashes_dir" "$corpus"
done

if selected fuzz_yaml; then
  name=fuzz_yaml
  crashes_dir="$BUILD/crashes/$name"
  rm -rf "$crashes_dir"
  mkdir -p "$BUILD/corpus/$name" "$crashes_dir"
  log="$BUILD/$name.log"
  if [ -x .venv/bin/python ]; then
    # The package's own reader and image plugin: the instrumented ones are for the C++ targets
    # (an ASan reader cannot start under the address-space limit fuzz_yaml.py sets).
    env -u SYNTHGEN_READER -u SYNTHGEN_IMAGE_IO_PLUGIN -u SYNTHGEN_VDB_PLUGIN .venv/bin/python fuzz/fuzz_yaml.py --seconds "$SECONDS_PER_TARGET" --corpus "$BUILD/corpus/$name" \
      --crashes "$crashes_dir" > "$log" 2>&1
  else
    echo "fuzz_yaml: .venv is missing (make install)" > "$log"
    touch "$crashes_dir/missing-venv"
  fi
  report "$name" "$log" "$crashes_dir" "$BUILD/corpus/$name"
fi
echo "fuzz_crashes=$total"
