#!/usr/bin/env bash
# Builds the libFuzzer harnesses (tests/fuzz) with clang, AddressSanitizer and UBSan, makes their
# seed corpora from the shipped files and runs each for SECONDS (default 60). A crash, leak,
# sanitizer report or over-long error message fails the run and leaves the input in
# build-fuzz/artifacts/. Longer runs: `bash .ci/fuzz.sh 3600`, or one harness by hand:
#   build-fuzz/tests/fuzz/fuzz_bvh -max_total_time=3600 build-fuzz/corpus/bvh
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_EACH="${1:-60}"
B=build-fuzz
CXX=clang++ cmake -S . -B $B -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSPARSEBODY_FUZZ=ON -DSPARSEBODY_TEST_DIRS=fuzz \
  -DSPARSEBODY_BUILD_BENCH=OFF -DSPARSEBODY_BUILD_EXAMPLES=OFF -DSPARSEBODY_NATIVE=OFF -DSPARSEBODY_INSTALL=OFF -DSPARSEBODY_BUILD_PYTHON=OFF -DSPARSEBODY_BUILD_C_API=OFF > /dev/null
cmake --build $B -j"$(nproc)"
C=$B/corpus
rm -rf $C; mkdir -p $C/weights_json $C/model_json $C/bvh $C/tracker_csv $C/pipelines $C/capi $B/artifacts
find tests/golden -name '*.weights.json' -size -16k -exec cp {} $C/weights_json/ \; 2>/dev/null || true
find tests -name '*.json' -size -64k | grep -i model | head -20 | xargs -r -I{} cp {} $C/model_json/ || true
/usr/bin/python3 - "$C" <<'PY'
import json, sys, os
c = sys.argv[1]
# A small valid model (two bodies) so the model fuzzer starts inside the format.
m = {"name": "seed", "gravity": [0, -9.81, 0], "bodies": [
    {"name": "root", "parent": None, "joint": "free", "pos": [0, 1, 0], "quat": [1, 0, 0, 0], "mass": 5,
     "com": [0, 0, 0], "inertia": [0.1, 0.1, 0.1, 0, 0, 0], "shapes": [{"type": "sphere", "pos": [0, 0, 0], "radius": 0.1}]},
    {"name": "arm", "parent": "root", "joint": "revolute", "axis": [0, 0, 1], "pos": [0.2, 0, 0], "quat": [1, 0, 0, 0],
     "mass": 1, "com": [0.1, 0, 0], "inertia": [0.01, 0.01, 0.01, 0, 0, 0], "kp": 10, "kd": 1, "limits": [-1, 1]}]}
open(os.path.join(c, "model_json", "seed.json"), "w").write(json.dumps(m))
PY
for f in /usr/share/assimp/models/BVH/*.bvh; do head -c 60000 "$f" > $C/bvh/$(basename "$f"); done 2>/dev/null || true
find tests -name '*.bvh' -size -200k -exec cp {} $C/bvh/ \; 2>/dev/null || true
find tests examples -name '*.csv' -size -200k -exec cp {} $C/tracker_csv/ \; 2>/dev/null || true
printf 'time,head_px\n' > $C/tracker_csv/short.csv
head -c 4096 /dev/urandom > $C/pipelines/random0
head -c 4096 /dev/urandom > $C/capi/random0
# fuzz_pipelines runs the shipped QuestSim policy (SPARSEBODY_QUESTSIM_POLICY=FILE for another one)
status=0
# the crash inputs found so far, first (tests/fuzz/regressions/<harness>-<what>)
for r in tests/fuzz/regressions/*; do
  h=$(basename "$r"); h=${h%%-*}
  $B/tests/fuzz/fuzz_$h "$r" > $B/regression.log 2>&1 || { echo "[fuzz] regression $r FAILED"; tail -20 $B/regression.log; status=1; }
done
for h in weights_json model_json bvh tracker_csv pipelines capi; do
  max_len=16384; [ $h = pipelines ] && max_len=3000; [ $h = capi ] && max_len=6000
  echo "[fuzz] $h: ${SECONDS_EACH} s"
  if ! $B/tests/fuzz/fuzz_$h -max_total_time="$SECONDS_EACH" -max_len=$max_len -rss_limit_mb=2048 -timeout=60 \
        -print_final_stats=1 -artifact_prefix=$B/artifacts/$h- $C/$h > $B/fuzz_$h.log 2>&1; then
    echo "[fuzz] $h FAILED: see $B/fuzz_$h.log and $B/artifacts/"; tail -40 $B/fuzz_$h.log; status=1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" $B/fuzz_$h.log | tr '\n' ' '; echo
done
exit $status
