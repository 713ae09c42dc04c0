#!/usr/bin/env bash
# The runtime on 64-bit ARM, the build ARM CPUs run (the pair test's portable
# kernel in 2-lane NEON vectors):
#   1. compiles the runtime with -O3 and warnings as errors, so nothing
#      x86-only leaks into it;
#   2. builds the runtime's unit tests and the octscene driver for aarch64 and
#      runs the tests under qemu-aarch64 (user-mode emulation: results, not
#      speed);
#   3. runs every bundled scene at every LOD policy on both architectures and
#      requires byte-identical collision logs (positions, depths, box tests);
#   4. builds octbake for aarch64 and requires the same baked bytes and the
#      same error lines as x86-64's octbake (bundled assets, every occupancy;
#      assimp's OBJ, PLY, STL and OFF test models).
# Usage: scripts/check_aarch64.sh HOST_BUILD_DIR (a configured and built host
# build: its generated headers, octbake and octscene are used).
# Needs what scripts/setup.sh installs: g++-aarch64-linux-gnu, qemu-user and
# Debian's arm64 libzstd-dev and libassimp-dev (multiarch).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: scripts/check_aarch64.sh HOST_BUILD_DIR}
fail() { echo "check_aarch64: $*" >&2; exit 1; }
cxx=aarch64-linux-gnu-g++
arm_libs=/usr/lib/aarch64-linux-gnu
gtest_src=/usr/src/googletest/googletest
for tool in "$cxx" qemu-aarch64; do
  command -v "$tool" >/dev/null || fail "$tool not found (scripts/setup.sh installs it)"
done
for f in "$arm_libs/libzstd.so" "$arm_libs/libassimp.so" "$gtest_src/src/gtest-all.cc"; do
  [ -e "$f" ] || fail "$f missing (scripts/setup.sh installs it)"
done
for f in "$build/schema/generated" "$build/runtime/include/octbake/export.h" "$build/baker/octbake" "$build/octscene/octscene"; do
  [ -e "$f" ] || fail "$f missing: configure and build $build first"
done
root=$PWD
build=$(cd "$build" && pwd)
out=$build/aarch64
rm -rf "$out" && mkdir -p "$out"/{include,runtime,gtest,tests,octscene,baker,baked,logs,bake}
# Only header-only, arch-independent headers: adding all of /usr/include
# would mix the host's x86 C library headers in.
ln -s /usr/include/zstd.h /usr/include/zstd_errors.h /usr/include/flatbuffers /usr/include/eigen3/Eigen \
  /usr/include/nlohmann /usr/include/CLI /usr/include/assimp /usr/include/xxhash.h "$out/include/"
# The top CMakeLists.txt's flags for aarch64: no contracted multiply-adds, and
# none from Eigen's NEON code either (-U__ARM_FEATURE_FMA).
base=(-std=c++20 -DNDEBUG -Wall -Wextra -Werror -Wno-restrict -ffp-contract=off -U__ARM_FEATURE_FMA
  -DOCTBAKE_STATIC_DEFINE "-I$root/runtime/include" "-I$build/runtime/include" "-I$build/schema/generated"
  -isystem "$out/include")
# compile DIR FLAGS... -- SOURCES...: one compiler per file, in parallel; any
# failing file fails the run.
compile() {
  local dir=$1; shift
  local flags=()
  while [ "$1" != -- ]; do flags+=("$1"); shift; done
  shift
  (cd "$dir" && printf '%s\0' "$@" | xargs -0 -n 1 -P "$(nproc)" "$cxx" "${flags[@]}" -c) ||
    fail "$dir: does not compile for aarch64 (errors above)"
}
compile "$out/runtime" "${base[@]}" -O3 "-I$root/runtime/src" -- "$root"/runtime/src/*.cpp
echo "check_aarch64: the runtime ($(ls runtime/src/*.cpp | wc -l) files) compiles for aarch64"

compile "$out/gtest" -std=c++20 -O2 "-I$gtest_src" -isystem "$gtest_src/include" -- \
  "$gtest_src/src/gtest-all.cc" "$gtest_src/src/gtest_main.cc"
# -Wno-psabi: GCC's note that std::pair's ARM calling convention changed in
# GCC 10.1 (nothing here crosses a library built by an older GCC).
compile "$out/tests" "${base[@]}" -O2 -Wno-psabi "-I$root/tests" "-I$root/runtime/src" -isystem "$gtest_src/include" \
  "-DOCTBAKE_SOURCE_DIR=\"$root\"" "-DOCTBAKE_BINARY_DIR=\"$out\"" \
  -DOCTBAKE_BIN=\"/nonexistent\" -DOCTSCENE_BIN=\"/nonexistent\" -- "$root"/tests/unit/runtime/*.cpp
compile "$out/octscene" "${base[@]}" -O2 "-I$root/octscene" -- "$root"/octscene/*.cpp
version=$("$build/baker/octbake" --version | cut -d' ' -f2)
compile "$out/baker" "${base[@]}" -O2 -DOCTBAKE_BAKER_STATIC_DEFINE "-DOCTBAKE_VERSION=\"$version\"" \
  "-I$root/baker" "-I$root/baker/include" "-I$build/baker/include" "-I$root/octscene" -- "$root"/baker/*.cpp
# Linked to Debian's arm64 shared libraries, as the x86-64 build is to its
# own: qemu runs them with the arm64 loader and libraries that multiarch
# installed. (Debian's static libzstd.a has no multithreading, whose frames
# for levels over 1 MiB differ from the shared library's.)
link() { "$cxx" -o "$@" "-L$arm_libs" "-Wl,-rpath-link=$arm_libs:/lib/aarch64-linux-gnu" -lzstd -pthread; }
link "$out/test_runtime" "$out"/tests/*.o "$out"/runtime/*.o "$out"/gtest/*.o
link "$out/octscene_aarch64" "$out"/octscene/*.o "$out"/runtime/*.o
link "$out/octbake_aarch64" "$out"/baker/*.o $(ls "$out"/octscene/*.o | grep -v '/main.o$\|/alloc_counter.o$') \
  "$out"/runtime/*.o -lassimp
for f in test_runtime octscene_aarch64 octbake_aarch64; do
  [ -x "$out/$f" ] || fail "linking $f for aarch64 failed (errors above)"
done

qemu-aarch64 "$out/test_runtime" --gtest_brief=1 || fail "runtime tests failed on aarch64 (above)"

# The same scenes, baked once by the host's octbake, on both architectures:
# the ARM run on 2 threads, the x86-64 one on 1 (results do not depend on it).
"$build/baker/octbake" -o "$out/baked" assets/*.obj >"$out/bake.log" 2>&1 ||
  fail "baking assets/*.obj failed: see $out/bake.log"
runs=0
for scene in assets/scenes/*.json; do
  name=$(basename "$scene" .json)
  for lod in fixed thesis screen; do
    args=(run "$scene" --lod "$lod" --baked "$out/baked")
    "$build/octscene/octscene" "${args[@]}" --threads 1 --log "$out/logs/${name}_$lod.x86_64.csv" >/dev/null
    qemu-aarch64 "$out/octscene_aarch64" "${args[@]}" --threads 2 --log "$out/logs/${name}_$lod.aarch64.csv" >/dev/null
    cmp "$out/logs/${name}_$lod.x86_64.csv" "$out/logs/${name}_$lod.aarch64.csv" ||
      fail "$scene --lod $lod: the aarch64 collision log differs from x86-64's (both in $out/logs)"
    runs=$((runs + 1))
  done
done

# The baker's own arithmetic (node transforms, triangle-box tests, flood
# fill) in double with no fused multiply-adds, so the same vertices give the
# same bytes. The test models are the formats whose vertices assimp only
# parses: it computes others itself (generated NFF shapes, Blender
# subdivision, some node transforms), and Debian's arm64 assimp does that with
# fused multiply-adds, so their last bits may differ (README, Known limits).
# The x86-64 bake runs on 1 thread, the aarch64 one on 2 (output bytes do not
# depend on -j).
bake_both() {  # NAME OCTBAKE_ARGS...
  local name=$1; shift
  "$build/baker/octbake" -q -j1 -o "$out/bake/$name.x86_64" "$@" >"$out/bake/$name.x86_64.log" 2>&1 || true
  qemu-aarch64 "$out/octbake_aarch64" -q -j2 -o "$out/bake/$name.aarch64" "$@" >"$out/bake/$name.aarch64.log" 2>&1 || true
  [ -n "$(ls "$out/bake/$name.x86_64")" ] || fail "$name: x86-64 octbake baked nothing (see $out/bake/$name.x86_64.log)"
  diff -r "$out/bake/$name.x86_64" "$out/bake/$name.aarch64" ||
    fail "$name: aarch64 octbake wrote other bytes than x86-64's (octbake $*)"
  diff <(sed "s#$out/bake/$name.x86_64#OUT#g" "$out/bake/$name.x86_64.log") \
    <(sed "s#$out/bake/$name.aarch64#OUT#g" "$out/bake/$name.aarch64.log") ||
    fail "$name: aarch64 octbake printed other lines than x86-64's"
  bakes=$((bakes + $(ls "$out/bake/$name.x86_64" | wc -l)))
}
bakes=0
for occupancy in surface solid vertices; do
  bake_both "assets_$occupancy" -d 8 --occupancy "$occupancy" assets/*.obj
done
for format in obj ply stl off; do
  mapfile -d '' models < <(find /usr/share/assimp/models -path '*/invalid' -prune -o -iname "*.$format" -print0 | sort -z)
  [ "${#models[@]}" -gt 0 ] || fail "no .$format test models in /usr/share/assimp/models (assimp-testmodels)"
  bake_both "models_$format" "${models[@]}"
done
echo "check_aarch64: runtime tests pass on aarch64; $runs scene runs give byte-identical logs and $bakes baked files the same bytes on aarch64 and x86-64"
