#!/usr/bin/env bash
# Compiles the runtime library for 64-bit ARM (compile only, -O3, warnings
# as errors): ARM CPUs run the pair test's portable build, so nothing
# x86-only may leak into it, and its vectors must suit 2-lane NEON registers.
# Usage: scripts/check_aarch64.sh HOST_BUILD_DIR (a configured host build:
# its generated schema and export headers are used).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: scripts/check_aarch64.sh HOST_BUILD_DIR}
cxx=aarch64-linux-gnu-g++
command -v "$cxx" >/dev/null || { echo "check_aarch64: $cxx not found (scripts/setup.sh installs it)" >&2; exit 1; }
for f in "$build/schema/generated" "$build/runtime/include/octbake/export.h"; do
  [ -e "$f" ] || { echo "check_aarch64: $f missing: configure and build $build first" >&2; exit 1; }
done
root=$PWD
out=$(cd "$build" && pwd)/aarch64
rm -rf "$out" && mkdir -p "$out/include"
# Only the header-only and arch-independent headers the runtime needs: adding
# all of /usr/include would mix the host's x86 C library headers in.
ln -s /usr/include/zstd.h /usr/include/zstd_errors.h /usr/include/flatbuffers /usr/include/eigen3/Eigen "$out/include/"
flags=(-std=c++20 -O3 -DNDEBUG -Wall -Wextra -Werror -Wno-restrict -ffp-contract=off -DOCTBAKE_STATIC_DEFINE
  "-I$root/runtime/include" "-I$root/runtime/src" "-I$out/../runtime/include" "-I$out/../schema/generated"
  -isystem "$out/include")
# One compiler per file, objects written in $out; a failing file fails the run.
(cd "$out" && printf '%s\0' "$root"/runtime/src/*.cpp | xargs -0 -n 1 -P "$(nproc)" "$cxx" "${flags[@]}" -c) ||
  { echo "check_aarch64: the runtime does not compile for aarch64 (errors above)" >&2; exit 1; }
echo "check_aarch64: the runtime ($(ls runtime/src/*.cpp | wc -l) files) compiles for aarch64"
