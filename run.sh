#!/usr/bin/env bash
# Set up, build, bake the bundled assets into baked/, and show the result.
set -euo pipefail
cd "$(dirname "$0")"
./scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DOCTBAKE_BUILD_TESTS=OFF >/dev/null
cmake --build build -j"$(nproc)" --target octbake octscene
./build/baker/octbake -o baked assets/*.obj
./build/baker/octbake --info baked/*.oct
./build/octscene/octscene run assets/scenes/test1.json --lod thesis --max-depth 3
