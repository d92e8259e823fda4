#!/usr/bin/env bash
# The main job on a fresh machine: installs what is missing, builds, and runs it on the shipped
# default weights. (Until the tracking demo lands this runs the benchmark suite.)
set -euo pipefail
cd "$(dirname "$0")/.."
exec bash .ci/bench.sh "$@"
