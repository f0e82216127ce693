#!/usr/bin/env bash
# Builds mmpm for an instruction set other than this machine's and runs the
# test suite there: the kernels size their vectors by the target's
# registers (kernels/lanes.hpp kRegisterVectorBytes), so a non-native build
# compiles other code paths than CI's -march=native one.
#
#   tools/check_portable.sh [MARCH] [BUILD_DIR]
#
# MARCH defaults to x86-64-v3 (AVX2 + FMA, no AVX-512); BUILD_DIR to
# build-MARCH. The CPU must run MARCH's instructions. Exit code: ctest's.
set -euo pipefail
cd "$(dirname "$0")/.."
march=${1:-x86-64-v3}
dir=${2:-build-$march}
if ! [[ $march =~ ^[A-Za-z0-9._-]+$ ]]; then
  echo "check_portable.sh: MARCH '$march' is not a -march name (letters, digits, . _ -)" >&2
  exit 2
fi
cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMMPM_NATIVE=OFF \
  "-DCMAKE_CXX_FLAGS=-march=$march"
cmake --build "$dir"
ctest --test-dir "$dir" -LE long --output-on-failure
