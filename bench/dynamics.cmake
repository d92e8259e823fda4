# Dynamics engine benchmarks; MuJoCo (Debian libmujoco-dev) is linked into the same binary when
# found, to report ratios. Its CMake package is bypassed (it lists a missing qhull include dir).
sparsebody_add_bench(bench_dynamics ${CMAKE_CURRENT_LIST_DIR}/bench_dynamics.cpp)
target_compile_options(bench_dynamics PRIVATE -O3)
find_path(SPARSEBODY_MUJOCO_INCLUDE_DIR mujoco/mujoco.h)
find_library(SPARSEBODY_MUJOCO_LIBRARY mujoco)
if(SPARSEBODY_MUJOCO_INCLUDE_DIR AND SPARSEBODY_MUJOCO_LIBRARY)
  target_include_directories(bench_dynamics PRIVATE ${SPARSEBODY_MUJOCO_INCLUDE_DIR})
  target_link_libraries(bench_dynamics PRIVATE ${SPARSEBODY_MUJOCO_LIBRARY})
  target_compile_definitions(bench_dynamics PRIVATE SPARSEBODY_HAVE_MUJOCO=1 SPARSEBODY_BENCH_DIR="${CMAKE_CURRENT_BINARY_DIR}")
else()
  message(STATUS "sparsebody: MuJoCo not found, bench_dynamics runs without the MuJoCo comparison")
endif()
