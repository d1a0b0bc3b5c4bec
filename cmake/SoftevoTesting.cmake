# Test registration helpers.
#
# softevo_add_test(NAME name SOURCES a.cpp ... LIBS lib ... [LABELS l ...] [COST seconds])
#   one GoogleTest executable, tests discovered individually by ctest.
# softevo_add_mpi_test(NAME name SOURCES a.cpp ... LIBS lib ... [LABELS l ...])
#   linked with the MPI GoogleTest main (tests/mpi_gtest_main.cpp); registered at np=2 and, with
#   --oversubscribe, at np=3. The root-user environment of Open MPI is set for every entry.
#
# COST: about the seconds of the executable's longest case in the sanitizer build. ctest -jN
# starts the costliest tests first; a fresh build tree has no timings of its own, and without a
# cost the long tests start wherever their number puts them and can run alone at the end while
# the other core idles (the sanitizer suite's last 166 s were one MPI test).
include(GoogleTest)

set(SOFTEVO_MPI_ENV "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1;OMPI_MCA_rmaps_base_oversubscribe=1")

# An instrumented build (SOFTEVO_SANITIZE) runs 2-5x slower: its tests get 3x the time, so that
# a test near its limit in the release build does not time out there.
macro(softevo_sanitized_timeout var)
  if(SOFTEVO_SANITIZE)
    math(EXPR ${var} "${${var}} * 3")
  endif()
endmacro()

function(softevo_add_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT;COST" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  # Tests include their shared helpers as "tests/..." from the source root.
  target_include_directories(${T_NAME} PRIVATE ${CMAKE_SOURCE_DIR})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  set_target_properties(${T_NAME} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  softevo_sanitized_timeout(T_TIMEOUT)
  if(NOT T_LABELS)
    set(T_LABELS unit)
  endif()
  if(NOT T_COST)
    set(T_COST 0)
  endif()
  # gtest_discover_tests flattens its PROPERTIES into one list (CMake 3.25), so a list-valued
  # ENVIRONMENT would keep only its first entry: the unit tests get just the source tree (the
  # build tree they find from their own executable; none of them starts mpirun).
  gtest_discover_tests(${T_NAME}
    WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}
    PROPERTIES LABELS "${T_LABELS}" TIMEOUT ${T_TIMEOUT} COST ${T_COST}
               ENVIRONMENT "SOFTEVO_SOURCE_DIR=${CMAKE_SOURCE_DIR}"
    DISCOVERY_TIMEOUT 60)
endfunction()

function(softevo_add_mpi_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT;COST" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES} ${CMAKE_SOURCE_DIR}/tests/mpi_gtest_main.cpp)
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} MPI::MPI_CXX GTest::gtest)
  set_target_properties(${T_NAME} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/tests)
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  softevo_sanitized_timeout(T_TIMEOUT)
  if(NOT T_COST)
    set(T_COST 0)
  endif()
  foreach(np 2 3)
    # The master rank waits for results (Open MPI yields when oversubscribed, which the
    # environment below sets): np ranks keep np - 1 cores busy.
    math(EXPR busy_cores "${np} - 1")
    add_test(NAME ${T_NAME}.np${np}
      COMMAND ${MPIEXEC_EXECUTABLE} ${MPIEXEC_NUMPROC_FLAG} ${np} --oversubscribe
              $<TARGET_FILE:${T_NAME}>
      WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
    set_tests_properties(${T_NAME}.np${np} PROPERTIES
      LABELS "mpi;${T_LABELS}" TIMEOUT ${T_TIMEOUT} PROCESSORS ${busy_cores} COST ${T_COST}
      ENVIRONMENT "SOFTEVO_SOURCE_DIR=${CMAKE_SOURCE_DIR};SOFTEVO_BINARY_DIR=${CMAKE_BINARY_DIR};${SOFTEVO_MPI_ENV}")
  endforeach()
endfunction()
