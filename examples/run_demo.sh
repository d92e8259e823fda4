#!/usr/bin/env bash
# The README's main command: installs the Debian dependencies (assimp-testmodels included), builds
# the demo, and runs the LoBSTr pipeline with the default (compact) weights on a CMU mocap clip.
#   bash examples/run_demo.sh [clip.bvh] [output.bvh]
# Open the output in Blender: File > Import > Motion Capture (.bvh), scale 0.01 (it is in cm).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
clip="${1:-/usr/share/assimp/models/BVH/01_01.bvh}"
out="${2:-$root/build-demo/avatar_$(basename "${clip%.*}").bvh}"
bash "$root/.ci/install-deps.sh"
cmake -S "$root" -B "$root/build-demo" -DCMAKE_BUILD_TYPE=Release \
      -DSPARSEBODY_BUILD_TESTS=OFF -DSPARSEBODY_BUILD_BENCH=OFF -DSPARSEBODY_BUILD_EXAMPLES=ON >/dev/null
cmake --build "$root/build-demo" --target sparsebody_demo -j"$(nproc)"
"$root/build-demo/examples/sparsebody_demo" "$clip" -o "$out" --trackers-out "${out%.bvh}_trackers.csv"
echo "open $out in Blender (File > Import > Motion Capture (.bvh), scale 0.01)"
