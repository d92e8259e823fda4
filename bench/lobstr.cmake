# Per-frame latency of the whole LoBSTr pipeline (resampling, sanitizing, features, network, IK).
sparsebody_add_bench(bench_lobstr ${CMAKE_CURRENT_LIST_DIR}/bench_lobstr.cpp)
target_include_directories(bench_lobstr PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_compile_definitions(bench_lobstr PRIVATE
  SPARSEBODY_LOBSTR_WEIGHTS="${PROJECT_SOURCE_DIR}/examples/weights/lobstr_compact.weights.json"
  SPARSEBODY_PIPELINE_GOLDEN_DIR="${PROJECT_SOURCE_DIR}/tests/pipeline/golden")
