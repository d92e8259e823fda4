# XNNPACK (Debian libxnnpack-dev, 0.0~git20220216, and libpthreadpool-dev for the pthreadpool.h it
# includes) as a peer of the papers' MLPs: its fully-connected operators in f32 and qs8 against the
# library's dense layers in float and q8 storage, in the same run (bench_xnnpack.cpp). Optional:
# without XNNPACK the target is a placeholder that only says so (so `--target bench_xnnpack`, as
# .ci/bench.sh builds it, still works), and no benchmark binary is made.
find_path(SPARSEBODY_XNNPACK_INCLUDE_DIR xnnpack.h)
find_path(SPARSEBODY_PTHREADPOOL_INCLUDE_DIR pthreadpool.h)
find_library(SPARSEBODY_XNNPACK_LIBRARY XNNPACK)
if(SPARSEBODY_XNNPACK_INCLUDE_DIR AND SPARSEBODY_PTHREADPOOL_INCLUDE_DIR AND SPARSEBODY_XNNPACK_LIBRARY)
  message(STATUS "sparsebody bench: XNNPACK found (${SPARSEBODY_XNNPACK_LIBRARY}), bench_xnnpack compares the MLPs against it")
  sparsebody_add_bench(bench_xnnpack ${CMAKE_CURRENT_LIST_DIR}/bench_xnnpack.cpp)
  target_include_directories(bench_xnnpack PRIVATE ${PROJECT_SOURCE_DIR}/tests ${SPARSEBODY_XNNPACK_INCLUDE_DIR}
                             ${SPARSEBODY_PTHREADPOOL_INCLUDE_DIR})
  target_link_libraries(bench_xnnpack PRIVATE ${SPARSEBODY_XNNPACK_LIBRARY})
else()
  message(STATUS "sparsebody bench: XNNPACK not found (apt-get install libxnnpack-dev libpthreadpool-dev), bench_xnnpack skipped")
  add_custom_target(bench_xnnpack COMMAND ${CMAKE_COMMAND} -E echo "bench_xnnpack: XNNPACK not found at configure time, nothing built")
endif()
