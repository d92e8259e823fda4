#!/usr/bin/env bash
# The main job on a fresh machine: installs what is missing, builds the demo and runs the tracking
# pipeline with the shipped default weights on real mocap nobody here made (a CMU clip from Debian's
# assimp-testmodels). Arguments: [clip.bvh] [output.bvh]. The benchmark suite is `bash .ci/bench.sh`.
set -euo pipefail
cd "$(dirname "$0")/.."
exec bash examples/run_demo.sh "$@"
