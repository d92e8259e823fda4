#!/usr/bin/env bash
# Builds and runs the tests that cover every weight storage path (tests/nn: layers, float/f16/int8
# storage, every int8 kernel against the portable one; tests/determinism: whole LoBSTr and
# Neural3Points pipelines with float, f16 and int8 weights) and the dynamics (tests/dynamics: ABA's
# two-lane steps are SSE2 or NEON vectors) for targets other than this machine:
#   x86-64-v3 (AVX2 + F16C + FMA), x86-64 (baseline SSE2: the generic, portable paths),
#   ARM64 with the dot product (armv8.2-a+dotprod, qemu -cpu max) and without (armv8-a, qemu -cpu
#   cortex-a53; tests/nn only: the pipelines under qemu take ~3 minutes and run in the first ARM64 build).
# Usage: bash .ci/isa.sh [x86-64-v3|x86-64|arm64-dotprod|arm64-v8.0 ...] (default: all four).
# About 16 minutes on this project's loaded 2-vCPU VM, half of it the two ARM64 builds (README "Tests").
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
common=(-DCMAKE_BUILD_TYPE=Release -DSPARSEBODY_BUILD_BENCH=OFF -DSPARSEBODY_BUILD_EXAMPLES=OFF
        -DSPARSEBODY_INSTALL=OFF "-DSPARSEBODY_TEST_DIRS=nn;determinism;dynamics" -DSPARSEBODY_PYTHON_TESTS=OFF
        -DSPARSEBODY_BUILD_PYTHON=OFF
        -DSPARSEBODY_BUILD_C_API=OFF)  # the C API library is built and tested by the main build (tests/capi)
arm=(-DCMAKE_TOOLCHAIN_FILE=.ci/aarch64-linux-gnu.cmake)
one() {
  local name=$1; shift
  local t0=$SECONDS
  echo "=== [isa] $name: $*"
  mkdir -p "build-$name"
  cmake -S . -B "build-$name" "${common[@]}" "$@" > "build-$name/configure.log" || { cat "build-$name/configure.log"; return 1; }
  cmake --build "build-$name" -j"$jobs"
  (cd "build-$name" && ctest --output-on-failure -j"$jobs" --timeout 1500)
  echo "=== [isa] $name: $((SECONDS - t0)) s"
}
targets=("$@")
((${#targets[@]})) || targets=(x86-64-v3 x86-64 arm64-dotprod arm64-v8.0)
for t in "${targets[@]}"; do
  case "$t" in
    x86-64-v3)
      if grep -qw avx2 /proc/cpuinfo && grep -qw fma /proc/cpuinfo && grep -qw f16c /proc/cpuinfo; then
        one x86-64-v3 -DSPARSEBODY_MARCH=x86-64-v3
      else
        echo "=== [isa] x86-64-v3: SKIPPED, this CPU has no AVX2/FMA/F16C"
      fi ;;
    x86-64) one x86-64 -DSPARSEBODY_MARCH=x86-64 ;;
    arm64-dotprod) one arm64-dotprod "${arm[@]}" -DSPARSEBODY_MARCH=armv8.2-a+dotprod -DSPARSEBODY_QEMU_CPU=max ;;
    arm64-v8.0) one arm64-v8.0 "${arm[@]}" -DSPARSEBODY_MARCH=armv8-a -DSPARSEBODY_QEMU_CPU=cortex-a53 -DSPARSEBODY_TEST_DIRS=nn ;;
    *) echo "unknown target $t"; exit 2 ;;
  esac
done
