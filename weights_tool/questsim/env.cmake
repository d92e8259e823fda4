# _questsim_env: the batched QuestSim training environment (include/sparsebody/training) as a Python
# module, next to the `sparsebody` module (weights_tool/questsim/env.py imports it from there).
# Included by weights_tool/native/CMakeLists.txt after it found Python3 and pybind11.
# NO_EXTRAS: no LTO, so the simulation compiles as in the run-time pipeline (same fused multiply-adds).
pybind11_add_module(_questsim_env NO_EXTRAS ${CMAKE_CURRENT_LIST_DIR}/env_module.cpp)
target_link_libraries(_questsim_env PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
set_target_properties(_questsim_env PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${SPARSEBODY_PYTHON_MODULE_DIR})
if(SPARSEBODY_BUILD_TESTS AND SPARSEBODY_PYTHON_TESTS)
  add_test(NAME training_env_pytest
           COMMAND ${SPARSEBODY_PYTHON} -m pytest -q -p no:cacheprovider weights_tool/questsim/test_env.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(training_env_pytest PROPERTIES ENVIRONMENT "SPARSEBODY_PYMOD_DIR=${SPARSEBODY_PYTHON_MODULE_DIR};MPLBACKEND=Agg")
endif()
