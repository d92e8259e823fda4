#!/usr/bin/env bash
# Installs, with apt-get, whatever of sparsebody's Debian dependencies is missing. Idempotent.
set -euo pipefail
pkgs=(cmake g++ make libeigen3-dev libxsimd-dev nlohmann-json3-dev doctest-dev libbenchmark-dev
      python3-torch python3-numpy python3-pytest libopenblas0-pthread
      pybind11-dev python3-dev python3-matplotlib  # the Python module (weights_tool/native) and its plots
      libtorch-dev libmujoco-dev assimp-testmodels clang libclang-rt-14-dev
      libxnnpack-dev libpthreadpool-dev  # XNNPACK, the peer of bench_xnnpack (its header includes pthreadpool.h)
      g++-aarch64-linux-gnu qemu-user  # ARM64 cross build + emulator (.ci/isa.sh)
      chromium libjs-three  # sparsebody_demo --html and its browser test (tests/viewer)
      mono-mcs mono-runtime)  # the C# binding's test (tests/capi, capi_csharp)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "[install-deps] installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "[install-deps] all dependencies present"
fi

# three.js for sparsebody_demo --html, the version examples/viewer/package-lock.json pins (node_modules
# is not committed). Without it the demo falls back to Debian's libjs-three (r111), which the page
# also supports, so a failed download is a warning, not an error.
viewer="$(cd "$(dirname "$0")/.." && pwd)/examples/viewer"
if [ ! -f "$viewer/node_modules/three/build/three.min.js" ]; then
  if ! command -v npm >/dev/null; then
    echo "[install-deps] installing: npm"
    SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends npm
  fi
  echo "[install-deps] npm ci --prefix examples/viewer (three.js for the --html page)"
  npm ci --prefix "$viewer" --no-audit --no-fund ||
    echo "[install-deps] warning: npm ci failed; sparsebody_demo --html falls back to Debian's libjs-three"
fi
