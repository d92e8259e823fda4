# The C API's cost per frame (push + read) against the same C++ calls, in one run; the API is
# compiled into the benchmark with its flags (SPARSEBODY_C_STATIC), so only the layer differs.
sparsebody_add_bench(bench_capi ${CMAKE_CURRENT_LIST_DIR}/bench_capi.cpp)
target_compile_definitions(bench_capi PRIVATE SPARSEBODY_C_STATIC
  SPARSEBODY_LOBSTR_WEIGHTS="${PROJECT_SOURCE_DIR}/examples/weights/lobstr_compact.weights.json"
  SPARSEBODY_N3P_WEIGHTS="${PROJECT_SOURCE_DIR}/examples/weights/n3p")
