# CMake toolchain for an ARM64 (aarch64) cross build on Debian: g++-aarch64-linux-gnu, tests run
# under qemu-user. Used by .ci/test.sh; by hand:
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=.ci/aarch64-linux-gnu.cmake \
#         -DSPARSEBODY_MARCH=armv8.2-a+dotprod -DSPARSEBODY_QEMU_CPU=max
# The header-only dependencies (Eigen, xsimd, nlohmann-json, doctest) are the host's
# architecture-independent packages under /usr/include; the C++ runtime is the cross one.
# (Kept under .ci/: the top level has no cmake/ folder by design.)
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE BOTH)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE BOTH)  # header-only packages' configs live on the host
# Debian ships xsimd's (header-only) package config under the host's multiarch library folder.
file(GLOB _sparsebody_xsimd_dirs /usr/lib/*-linux-gnu*/cmake/xsimd)
if(_sparsebody_xsimd_dirs AND NOT xsimd_DIR)
  list(GET _sparsebody_xsimd_dirs 0 _sparsebody_xsimd_dir)
  set(xsimd_DIR ${_sparsebody_xsimd_dir} CACHE PATH "xsimd package config (header-only, host copy)")
endif()
# The CPU qemu emulates: "max" has every extension (dot product included); "cortex-a53" is an
# ARMv8.0 core without it (pair it with -DSPARSEBODY_MARCH=armv8-a).
set(SPARSEBODY_QEMU_CPU "max" CACHE STRING "qemu-aarch64 -cpu value for running the tests")
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64 -L /usr/aarch64-linux-gnu -cpu ${SPARSEBODY_QEMU_CPU})
