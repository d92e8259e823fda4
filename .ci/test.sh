#!/usr/bin/env bash
# Sets up a fresh machine and runs every test: C++ (doctest, via CTest), Python (pytest, via CTest),
# the storage-path tests built for other targets (x86-64-v3, x86-64, ARM64 under qemu) and the fuzz harnesses.
set -euo pipefail
cd "$(dirname "$0")/.."
bash .ci/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
(cd build && ctest --output-on-failure -j"$(nproc)" --timeout 1500)
# tests/nn + tests/determinism for AVX2, baseline x86-64 and ARM64 with/without dot product (qemu).
bash .ci/isa.sh
# libFuzzer harnesses (clang + ASan + UBSan), 60 s each; longer: bash .ci/fuzz.sh SECONDS
bash .ci/fuzz.sh 60
