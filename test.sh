#!/usr/bin/env bash
# Set up, build with warnings as errors, and run every test: once optimised,
# once under AddressSanitizer + UndefinedBehaviorSanitizer, the thread-safety
# test once under ThreadSanitizer; the runtime on ARM (emulated); a short
# fuzzing pass; then a small shared-library pass.
set -euo pipefail
cd "$(dirname "$0")"
./scripts/setup.sh
jobs=$(nproc)
# Benchmarks are built (never run) so they cannot rot unnoticed.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DOCTBAKE_WERROR=ON -DOCTBAKE_BUILD_TESTS=ON -DOCTBAKE_BENCH=ON >/dev/null
cmake --build build -j"$jobs"
ctest --test-dir build --output-on-failure -j"$jobs"
# The runtime on 64-bit ARM, the pair test's portable build: compiled with
# -Werror, its unit tests under qemu-aarch64, and the bundled scenes' logs
# byte-identical to x86-64's.
./scripts/check_aarch64.sh build
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-g -O1" -DOCTBAKE_WERROR=ON -DOCTBAKE_SANITIZE=ON -DOCTBAKE_BUILD_TESTS=ON >/dev/null
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j"$jobs"
# ThreadSanitizer: only the small tests/tsan folder (runtime library + three
# test files), so this pass stays short: baked files and loaded trees shared
# across threads, CollisionWorld's parallel parts on a 3-thread pool, and
# encode_file's helper threads.
cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="" \
  -DCMAKE_CXX_FLAGS="-fsanitize=thread -g -O1" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=thread" \
  -DOCTBAKE_WERROR=ON -DOCTBAKE_BUILD_TESTS=ON >/dev/null
cmake --build build-tsan -j"$jobs" --target test_tsan
TSAN_OPTIONS=halt_on_error=1 ctest --test-dir build-tsan --output-on-failure -L tsan
# Fuzzing: both libFuzzer targets built with clang (ASan + UBSan, -Werror),
# each run for a fixed number of inputs from a fixed seed, so a run is
# repeatable; seeds: the golden baked files and the bundled scenes (read
# only: libFuzzer adds the inputs it finds to the first folder, here one in
# build-fuzz/). A crash, leak, hang (20 s an input) or a refusal without a
# reason fails the run; the input that did it is left in build-fuzz/.
CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-g -O1" \
  -DCMAKE_CXX_FLAGS="-fsanitize=fuzzer-no-link" -DOCTBAKE_WERROR=ON -DOCTBAKE_FUZZ=ON -DOCTBAKE_SANITIZE=ON \
  -DOCTBAKE_BUILD_TESTS=OFF >/dev/null
cmake --build build-fuzz -j"$jobs" --target fuzz_baked_file fuzz_scene
fuzz_options=(-seed=1 -timeout=20 -rss_limit_mb=2048 -artifact_prefix=build-fuzz/ -print_final_stats=1)
rm -rf build-fuzz/corpus && mkdir -p build-fuzz/corpus/baked build-fuzz/corpus/scene
build-fuzz/tests/fuzz_baked_file "${fuzz_options[@]}" -runs=2000000 build-fuzz/corpus/baked tests/golden 2>&1 | tail -n 12
build-fuzz/tests/fuzz_scene "${fuzz_options[@]}" -runs=50000 -max_len=8192 build-fuzz/corpus/scene assets/scenes 2>&1 |
  tail -n 12
# Shared libraries (BUILD_SHARED_LIBS=ON) without the analysis tools (so FCL,
# octomap and stb are proven optional): builds only the runtime, the baker and
# the public-API test, and runs it and the install consumer (which also checks
# the exported symbols).
cmake -S . -B build-shared -DCMAKE_BUILD_TYPE=Release -DOCTBAKE_WERROR=ON -DOCTBAKE_BUILD_TESTS=ON \
  -DBUILD_SHARED_LIBS=ON -DOCTBAKE_ANALYSIS=OFF >/dev/null
cmake --build build-shared -j"$jobs" --target test_api
ctest --test-dir build-shared --output-on-failure -j"$jobs" -R '^(BakerApi[.]|install_consumer$)'
