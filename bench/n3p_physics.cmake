# Neural3Points physics (normal) mode: a whole 30 Hz frame (direct-mode predictor step, 4 simulation
# steps at 120 Hz, the 10 Hz control step amortised) and its parts, on the default weights.
sparsebody_add_bench(bench_n3p_physics ${CMAKE_CURRENT_LIST_DIR}/bench_n3p_physics.cpp)
target_compile_definitions(bench_n3p_physics PRIVATE SPARSEBODY_N3P_WEIGHTS="${PROJECT_SOURCE_DIR}/examples/weights/n3p_physics")
