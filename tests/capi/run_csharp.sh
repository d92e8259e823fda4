#!/usr/bin/env bash
# The C# binding (examples/unity/Sparsebody.cs) on Mono: compiles it with tests/capi/CSharpTest.cs,
# writes the session CSV and the C++ pipelines' joint positions (capi_reference), streams the CSV
# through the shared library from C# and compares. Exit 77 (CTest: skipped) without mcs or mono.
#   run_csharp.sh SOURCE_DIR CAPI_REFERENCE LIB_DIR CLIP.bvh WORK_DIR
set -euo pipefail
src=$1 ref=$2 lib=$3 clip=$4 work=$5
for tool in mcs mono; do
  command -v "$tool" >/dev/null || { echo "skipped: $tool not found (apt-get install mono-mcs mono-runtime)"; exit 77; }
done
mkdir -p "$work"
mcs -nologo -unsafe -warnaserror -out:"$work/CSharpTest.exe" "$src/examples/unity/Sparsebody.cs" "$src/tests/capi/CSharpTest.cs"
"$ref" "$clip" "$src/examples/weights" "$work"
LD_LIBRARY_PATH="$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" mono "$work/CSharpTest.exe" "$work/session.csv" "$src/examples/weights" "$work"
