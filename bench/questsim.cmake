# QuestSim: one 36 Hz control step (observation + policy MLP [400, 300, 200] + 2 simulation
# substeps of 1/72 s) on the default avatar at a user's height, and its parts, with a random-weight
# policy generated in the benchmark; and the session (what the demo and the C API run) with the
# shipped trained policy, per 36 Hz tick from a 72 Hz stream.
sparsebody_add_bench(bench_questsim ${CMAKE_CURRENT_LIST_DIR}/bench_questsim.cpp)
target_compile_options(bench_questsim PRIVATE -O3)
target_compile_definitions(bench_questsim PRIVATE
  SPARSEBODY_QUESTSIM_SHIPPED_POLICY="${PROJECT_SOURCE_DIR}/examples/weights/questsim_policy.json")
