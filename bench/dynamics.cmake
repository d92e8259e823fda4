# Dynamics engine benchmarks. Peers are linked into the same binary so ratios come from one run:
# MuJoCo (Debian libmujoco-dev) when found, its CMake package bypassed (it lists a missing qhull
# include dir); RBDL 3.3.1 when its source tarball is beside the project (../shared/peers), built
# static from it into this build folder. Neither is needed for anything but these comparisons.
sparsebody_add_bench(bench_dynamics ${CMAKE_CURRENT_LIST_DIR}/bench_dynamics.cpp)
target_compile_options(bench_dynamics PRIVATE -O3)
find_path(SPARSEBODY_MUJOCO_INCLUDE_DIR mujoco/mujoco.h)
find_library(SPARSEBODY_MUJOCO_LIBRARY mujoco)
if(SPARSEBODY_MUJOCO_INCLUDE_DIR AND SPARSEBODY_MUJOCO_LIBRARY)
  target_include_directories(bench_dynamics PRIVATE ${SPARSEBODY_MUJOCO_INCLUDE_DIR})
  target_link_libraries(bench_dynamics PRIVATE ${SPARSEBODY_MUJOCO_LIBRARY})
  target_compile_definitions(bench_dynamics PRIVATE SPARSEBODY_HAVE_MUJOCO=1 SPARSEBODY_BENCH_DIR="${CMAKE_CURRENT_BINARY_DIR}")
else()
  message(STATUS "sparsebody: MuJoCo not found, bench_dynamics runs without the MuJoCo comparison")
endif()

# RBDL: a peer to time against, never part of the project (see ../shared/peers/README.md). Built
# with the flags of this build (Release and its -march: SPARSEBODY_MARCH, or native when
# SPARSEBODY_NATIVE) so both sides get the same compiler treatment.
set(SPARSEBODY_RBDL_TARBALL ${PROJECT_SOURCE_DIR}/../shared/peers/rbdl-3.3.1-src.tar.gz)
if(EXISTS ${SPARSEBODY_RBDL_TARBALL})
  set(_sparsebody_rbdl_default ON)
else()
  set(_sparsebody_rbdl_default OFF)
endif()
option(SPARSEBODY_BENCH_RBDL "Build RBDL 3.3.1 from ../shared/peers and compare bench_dynamics against it"
       ${_sparsebody_rbdl_default})
if(SPARSEBODY_BENCH_RBDL AND NOT EXISTS ${SPARSEBODY_RBDL_TARBALL})
  message(STATUS "sparsebody: ${SPARSEBODY_RBDL_TARBALL} not found, bench_dynamics runs without RBDL")
elseif(SPARSEBODY_BENCH_RBDL)
  include(ExternalProject)
  set(_rbdl_dir ${CMAKE_CURRENT_BINARY_DIR}/rbdl)
  set(_rbdl_flags "${_sparsebody_march}")  # the build's ISA (CMakeLists.txt), e.g. -march=x86-64-v3
  set(_rbdl_timestamp)
  if(CMAKE_VERSION VERSION_GREATER_EQUAL 3.24)
    set(_rbdl_timestamp DOWNLOAD_EXTRACT_TIMESTAMP TRUE)
  endif()
  set(_rbdl_off)
  foreach(o TESTS EXECUTABLES PYTHON_WRAPPER CASADI ADDON_URDFREADER ADDON_BENCHMARK ADDON_LUAMODEL
            ADDON_GEOMETRY ADDON_MUSCLE ADDON_BALANCE)
    list(APPEND _rbdl_off -DRBDL_BUILD_${o}=OFF)
  endforeach()
  file(SHA256 ${SPARSEBODY_RBDL_TARBALL} _rbdl_sha256)  # the extraction is checked against the file read here
  ExternalProject_Add(sparsebody_rbdl_build
    URL ${SPARSEBODY_RBDL_TARBALL}
    URL_HASH SHA256=${_rbdl_sha256}
    ${_rbdl_timestamp}
    PREFIX ${_rbdl_dir}
    INSTALL_DIR ${_rbdl_dir}/install
    CMAKE_ARGS -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CMAKE_CXX_COMPILER} "-DCMAKE_CXX_FLAGS=${_rbdl_flags}"
               -DCMAKE_INSTALL_PREFIX=<INSTALL_DIR> -DCMAKE_INSTALL_LIBDIR=lib -DRBDL_BUILD_STATIC=ON ${_rbdl_off}
    BUILD_BYPRODUCTS ${_rbdl_dir}/install/lib/librbdl.a
    LOG_CONFIGURE ON LOG_BUILD ON LOG_INSTALL ON LOG_OUTPUT_ON_FAILURE ON)
  file(MAKE_DIRECTORY ${_rbdl_dir}/install/include)  # an imported target's include dir must exist
  add_library(sparsebody_rbdl STATIC IMPORTED)
  set_target_properties(sparsebody_rbdl PROPERTIES IMPORTED_LOCATION ${_rbdl_dir}/install/lib/librbdl.a
                        INTERFACE_INCLUDE_DIRECTORIES ${_rbdl_dir}/install/include)
  add_dependencies(sparsebody_rbdl sparsebody_rbdl_build)
  target_link_libraries(bench_dynamics PRIVATE sparsebody_rbdl)
  target_compile_definitions(bench_dynamics PRIVATE SPARSEBODY_HAVE_RBDL=1)
  message(STATUS "sparsebody: bench_dynamics is compared against RBDL 3.3.1 (built from ${SPARSEBODY_RBDL_TARBALL})")
endif()
