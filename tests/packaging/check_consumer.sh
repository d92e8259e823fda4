#!/usr/bin/env bash
# Installs sparsebody from the build tree into a temporary prefix, builds the consumer against the
# installed package and against add_subdirectory(), and runs both.
set -euo pipefail
src=$1; bin=$2; work=$3
rm -rf "$work" && mkdir -p "$work"
cmake --install "$bin" --prefix "$work/prefix" > "$work/install.log"
test -f "$work/prefix/include/sparsebody/nn/network.hpp"
test -n "$(find "$work/prefix" -name sparsebodyConfig.cmake)"
test -f "$work/prefix/include/sparsebody/c/sparsebody.h"
test -n "$(find "$work/prefix" -name 'libsparsebody_c.so*')"  # the C API library (sparsebody::c)
cmake -S "$src/tests/packaging/consumer" -B "$work/installed" -DCMAKE_PREFIX_PATH="$work/prefix" -DMODE=INSTALLED > "$work/configure1.log"
cmake --build "$work/installed" > "$work/build1.log"
"$work/installed/consumer" "$src/tests/golden/policy_small.weights.json"
cmake -S "$src/tests/packaging/consumer" -B "$work/subdir" -DMODE=SUBDIR -DSPARSEBODY_SOURCE="$src" > "$work/configure2.log"
cmake --build "$work/subdir" > "$work/build2.log"
"$work/subdir/consumer" "$src/tests/golden/policy_small.weights.json"
echo "packaging ok"
