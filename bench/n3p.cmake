# Neural3Points: one 30 Hz frame of the pose predictor (Eq. (2), paper sizes 64/128/128) and of the
# whole direct-mode pipeline, on the default weights (examples/weights/n3p_*.json).
sparsebody_add_bench(bench_n3p ${CMAKE_CURRENT_LIST_DIR}/bench_n3p.cpp)
target_compile_definitions(bench_n3p PRIVATE SPARSEBODY_N3P_WEIGHTS="${PROJECT_SOURCE_DIR}/examples/weights/n3p")
