# _questsim_env: the batched QuestSim training environment as a Python module (weights_tool/questsim/env.py
# imports it from ${CMAKE_BINARY_DIR}/python). Debian's python3-torch lives in /usr/bin/python3, so
# the module is built for that interpreter's headers.
if(EXISTS /usr/bin/python3 AND NOT DEFINED Python_EXECUTABLE)
  set(Python_EXECUTABLE /usr/bin/python3)
endif()
find_package(Python 3 COMPONENTS Interpreter Development.Module QUIET)
find_package(pybind11 CONFIG QUIET)
if(Python_FOUND AND pybind11_FOUND)
  # NO_EXTRAS: no LTO, so the simulation compiles as in the run-time pipeline (same fused multiply-adds).
  pybind11_add_module(_questsim_env NO_EXTRAS ${CMAKE_CURRENT_LIST_DIR}/env_module.cpp)
  target_link_libraries(_questsim_env PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
  set_target_properties(_questsim_env PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/python)
else()
  message(STATUS "sparsebody: pybind11 or the Python headers not found: the QuestSim training environment is not built")
endif()
