# The demo (LoBSTr or Neural3Points): BVH (synthesised trackers) or tracker CSV in, avatar BVH out, metrics when ground truth exists.
add_executable(sparsebody_demo ${CMAKE_CURRENT_SOURCE_DIR}/sparsebody_demo.cpp ${CMAKE_CURRENT_SOURCE_DIR}/demo_options.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/demo_input.cpp ${CMAKE_CURRENT_SOURCE_DIR}/demo_metrics.cpp)
target_link_libraries(sparsebody_demo PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
target_compile_definitions(sparsebody_demo PRIVATE
  SPARSEBODY_DEFAULT_WEIGHTS="${CMAKE_CURRENT_SOURCE_DIR}/weights/lobstr_compact.weights.json"
  SPARSEBODY_DEFAULT_N3P_WEIGHTS="${CMAKE_CURRENT_SOURCE_DIR}/weights/n3p")
