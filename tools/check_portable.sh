#!/usr/bin/env bash
# Compiles mmpm for instruction sets other than this machine's: the kernels
# size their vectors by the target's registers (kernels/lanes.hpp
# kRegisterVectorBytes) and keep AVX-512-only paths (the packed 2D linear
# kernels), so a non-native build compiles code that CI's -march=native
# build never sees.
#
#   tools/check_portable.sh [MARCH] [BUILD_DIR]
#       builds for MARCH (default x86-64-v3: AVX2 + FMA, no AVX-512) in
#       BUILD_DIR (default build-MARCH) and runs the test suite there; the
#       CPU must run MARCH's instructions (~15 min on 2 cores).
#   tools/check_portable.sh --syntax-only [MARCH ...]
#       compiles the translation units of the built build/ whose code can
#       depend on the target (those including a kernels/ header or testing
#       __AVX*/__SSE*/__FMA*) with -fsyntax-only -march=MARCH -Werror
#       (default: x86-64-v3 x86-64, the SSE2 baseline), ~1 min per MARCH on
#       2 cores; CI runs this. It
#       catches what the front end sees (types, templates, constexpr
#       branches, static_asserts, front-end warnings), not the warnings
#       that need the optimiser or wrong results: those need the full build.
#
# Exit code: the compiler's or ctest's; 2 for a bad argument.
set -euo pipefail
cd "$(dirname "$0")/.."

check_march() {
  if ! [[ $1 =~ ^[A-Za-z0-9._-]+$ ]]; then
    echo "check_portable.sh: MARCH '$1' is not a -march name (letters, digits, . _ -)" >&2
    exit 2
  fi
}

if [[ ${1-} == --syntax-only ]]; then
  shift
  marches=("$@")
  [[ ${#marches[@]} -eq 0 ]] && marches=(x86-64-v3 x86-64)
  if [[ ! -f build/build.ninja ]]; then
    echo "check_portable.sh: configure build/ first (the README's build command)" >&2
    exit 2
  fi
  # The objects whose code can depend on the target: those that include a
  # kernels/ header (ninja's dependency log, so build/ must have been
  # built) or test the target's macros themselves.
  mapfile -t objects < <(
    ninja -C build -t deps | awk '/^[^ ].*\.o: /{o=$1; sub(/:$/, "", o)} /kernels\//{print o}'
    for f in $(grep -rlE '__(AVX|SSE|FMA)' src tests bench tools --include='*.cpp'); do
      echo "CMakeFiles/mmpm_core.dir/$f.o"
    done
  )
  if [[ ${#objects[@]} -eq 0 ]]; then
    echo "check_portable.sh: build/ has no dependency log; build it first" >&2
    exit 2
  fi
  # Their compile commands, with the object file and dependency outputs
  # replaced by -fsyntax-only and -march=native by the target.
  mapfile -t commands < <(ninja -C build -t commands | grep -- ' -c ' |
    grep -F -f <(printf -- '-o %s \n' "${objects[@]}" | sort -u))
  for march in "${marches[@]}"; do
    check_march "$march"
    list=$(mktemp)
    for c in "${commands[@]}"; do
      s=$(sed -e "s/-march=native/-march=$march/" \
        -e 's/ -MD -MT [^ ]* -MF [^ ]* -o [^ ]* -c / -fsyntax-only /' <<<"$c")
      if [[ $s != *-fsyntax-only* || $s != *-march=$march* ]]; then
        echo "check_portable.sh: cannot rewrite the compile command: $c" >&2
        exit 2
      fi
      printf '%s\n' "$s" >>"$list"
    done
    start=$SECONDS
    if ! (cd build && xargs -P "$(nproc)" -d '\n' -I{} sh -c '{}' <"$list"); then
      rm -f "$list"
      echo "check_portable.sh: $march: compile errors above" >&2
      exit 1
    fi
    echo "check_portable.sh: $march: ${#commands[@]} translation units compile ($((SECONDS - start)) s)"
    rm -f "$list"
  done
  exit 0
fi

march=${1:-x86-64-v3}
dir=${2:-build-$march}
check_march "$march"
cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DMMPM_NATIVE=OFF \
  "-DCMAKE_CXX_FLAGS=-march=$march"
cmake --build "$dir"
ctest --test-dir "$dir" -LE long --output-on-failure
