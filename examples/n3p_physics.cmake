# Neural3Points physics (normal) mode next to direct mode on dumped validation clips: foot skating,
# ground penetration, MPJPE full / upper / lower, residual wrench (see n3p_physics_eval.cpp).
add_executable(n3p_physics_eval ${CMAKE_CURRENT_LIST_DIR}/n3p_physics_eval.cpp)
target_link_libraries(n3p_physics_eval PRIVATE sparsebody::sparsebody sparsebody_dev_flags)
target_compile_definitions(n3p_physics_eval PRIVATE
  SPARSEBODY_N3P_WEIGHTS="${CMAKE_CURRENT_LIST_DIR}/weights/n3p")
