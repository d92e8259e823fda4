# The soak run (examples/soak): hours of validation clips with session events through one pipeline,
# checking finiteness, allocations, resident memory and drift. CI runs a short variant
# (tests/soak); `sparsebody_soak --hours 10` is the long one (README).
add_executable(sparsebody_soak ${CMAKE_CURRENT_LIST_DIR}/soak/sparsebody_soak.cpp)
target_link_libraries(sparsebody_soak PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
target_include_directories(sparsebody_soak PRIVATE ${PROJECT_SOURCE_DIR}/tests)  # support/alloc_counter.hpp
target_compile_definitions(sparsebody_soak PRIVATE
  SPARSEBODY_DEFAULT_WEIGHTS="${CMAKE_CURRENT_LIST_DIR}/weights/lobstr_compact.weights.json"
  SPARSEBODY_DEFAULT_N3P_WEIGHTS="${CMAKE_CURRENT_LIST_DIR}/weights/n3p"
  SPARSEBODY_DEFAULT_N3P_PHYSICS_WEIGHTS="${CMAKE_CURRENT_LIST_DIR}/weights/n3p_physics"
  SPARSEBODY_DEFAULT_QUESTSIM_WEIGHTS="${CMAKE_CURRENT_LIST_DIR}/weights/questsim_policy.json")
