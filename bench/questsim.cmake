# QuestSim: one 36 Hz control step (observation + policy MLP [400, 300, 200] + 2 simulation
# substeps of 1/72 s) on the default avatar at a user's height, and its parts. The policy has random
# weights generated in the benchmark (trained QuestSim policies are not shipped).
sparsebody_add_bench(bench_questsim ${CMAKE_CURRENT_LIST_DIR}/bench_questsim.cpp)
target_compile_options(bench_questsim PRIVATE -O3)
