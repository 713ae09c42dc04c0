#!/usr/bin/env bash
# Installs every Debian package the build, tests and benchmarks need.
set -euo pipefail
packages=(
  build-essential cmake pkg-config git
  ninja-build                              # the consumer tests build with Ninja and with Make
  libassimp-dev assimp-testmodels          # mesh import + real test meshes
  libflatbuffers-dev flatbuffers-compiler  # baked file format
  libeigen3-dev libzstd-dev                # math, level compression
  libgtest-dev libbenchmark-dev            # tests, benchmarks
  libfcl-dev liboctomap-dev                # exact oracle + peer benchmark
  nlohmann-json3-dev libcli11-dev libstb-dev  # scene JSON, CLIs, PNG output
  libxxhash-dev                            # source-file hash (header-only use)
  clang libclang-rt-dev                    # libFuzzer targets (test.sh's fuzzing pass)
  # The runtime built, tested and run for ARM (test.sh, scripts/check_aarch64.sh):
  # cross compiler, user-mode emulator, GoogleTest's sources, arm64 zstd and assimp.
  g++-aarch64-linux-gnu qemu-user googletest libzstd-dev:arm64 libassimp-dev:arm64
  python3
)
sudo_cmd=(); [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
# Debian multiarch, for the arm64 libraries above.
if ! dpkg --print-foreign-architectures | grep -qx arm64; then
  "${sudo_cmd[@]}" dpkg --add-architecture arm64
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}"
fi
