#!/usr/bin/env bash
# Installs, with apt-get, whatever of sparsebody's Debian dependencies is missing. Idempotent.
set -euo pipefail
pkgs=(cmake g++ make libeigen3-dev libxsimd-dev nlohmann-json3-dev doctest-dev libbenchmark-dev
      python3-torch python3-numpy python3-pytest libopenblas0-pthread
      libtorch-dev libmujoco-dev assimp-testmodels clang libclang-rt-14-dev
      g++-aarch64-linux-gnu qemu-user  # ARM64 cross build + emulator (.ci/isa.sh)
      mono-mcs mono-runtime)           # the C# binding's test (tests/capi, capi_csharp)
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
