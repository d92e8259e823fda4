# The demo (LoBSTr, Neural3Points or QuestSim): BVH (synthesised trackers) or tracker CSV in, avatar BVH out, metrics when ground truth exists.
add_executable(sparsebody_demo ${CMAKE_CURRENT_SOURCE_DIR}/sparsebody_demo.cpp ${CMAKE_CURRENT_SOURCE_DIR}/demo_options.cpp
  ${CMAKE_CURRENT_SOURCE_DIR}/demo_input.cpp ${CMAKE_CURRENT_SOURCE_DIR}/demo_metrics.cpp ${CMAKE_CURRENT_SOURCE_DIR}/demo_viewer.cpp)
target_link_libraries(sparsebody_demo PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
target_compile_definitions(sparsebody_demo PRIVATE
  SPARSEBODY_DEFAULT_WEIGHTS="${CMAKE_CURRENT_SOURCE_DIR}/weights/lobstr_compact.weights.json"
  SPARSEBODY_DEFAULT_N3P_WEIGHTS="${CMAKE_CURRENT_SOURCE_DIR}/weights/n3p"
  SPARSEBODY_DEFAULT_N3P_PHYSICS_WEIGHTS="${CMAKE_CURRENT_SOURCE_DIR}/weights/n3p_physics"
  SPARSEBODY_DEFAULT_QUESTSIM_WEIGHTS="${CMAKE_CURRENT_SOURCE_DIR}/weights/questsim_policy.json")
# --html: the page template and npm's three.js (npm ci --prefix examples/viewer; the demo falls back
# to Debian's libjs-three when it is missing, and --three-js PATH overrides both).
set(SPARSEBODY_THREE_JS "${CMAKE_CURRENT_SOURCE_DIR}/viewer/node_modules/three/build/three.min.js" CACHE FILEPATH
  "three.js global build that sparsebody_demo --html inlines")
target_compile_definitions(sparsebody_demo PRIVATE
  SPARSEBODY_VIEWER_TEMPLATE="${CMAKE_CURRENT_SOURCE_DIR}/viewer/viewer.html"
  SPARSEBODY_THREE_JS="${SPARSEBODY_THREE_JS}")
