# Neural3Points physics (normal) mode next to direct mode on dumped validation clips: foot skating,
# ground penetration, MPJPE full / upper / lower, residual wrench (see n3p_physics_eval.cpp).
add_executable(n3p_physics_eval ${CMAKE_CURRENT_LIST_DIR}/n3p_physics_eval.cpp)
target_link_libraries(n3p_physics_eval PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
target_compile_definitions(n3p_physics_eval PRIVATE
  SPARSEBODY_N3P_WEIGHTS="${CMAKE_CURRENT_LIST_DIR}/weights/n3p_physics")
if(SPARSEBODY_BUILD_TESTS AND SPARSEBODY_PYTHON_TESTS)
  # The shipped correction policy against the model-based controller on validation clips (needs ../shared).
  add_test(NAME n3p_correction_policy_test
           COMMAND ${SPARSEBODY_PYTHON} -m pytest -q -s -p no:cacheprovider weights_tool/n3p_physics/test_correction_policy.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(n3p_correction_policy_test PROPERTIES
                       ENVIRONMENT "N3P_PHYSICS_EVAL=$<TARGET_FILE:n3p_physics_eval>;OMP_NUM_THREADS=1")
endif()
