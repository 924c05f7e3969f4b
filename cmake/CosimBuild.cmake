# Shared build helpers: warning flags and test registration.

# Warnings apply to project targets only (generated LCM headers are included as SYSTEM).
function(cosim_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
endfunction()

# cosim_add_gtest(NAME name SOURCES ... LIBS ... LABELS ... TIMEOUT seconds [PRIVATE_NETWORK])
# Builds a GoogleTest executable and registers it with CTest as one test with a timeout.
# PRIVATE_NETWORK runs it in its own network namespace (multi-process LCM tests).
function(cosim_add_gtest)
  cmake_parse_arguments(T "PRIVATE_NETWORK" "NAME;TIMEOUT" "SOURCES;LIBS;LABELS;ARGS" ${ARGN})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 120)
  endif()
  add_executable(${T_NAME} ${T_SOURCES})
  cosim_warnings(${T_NAME})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  if(T_PRIVATE_NETWORK)
    add_test(NAME ${T_NAME} COMMAND ${CMAKE_SOURCE_DIR}/tests/in_private_network.sh
                                    $<TARGET_FILE:${T_NAME}> ${T_ARGS})
  else()
    add_test(NAME ${T_NAME} COMMAND ${T_NAME} ${T_ARGS})
  endif()
  # Tests share the cores (ctest -j): solver threads sleep at once while they wait
  # (docs/performance.md, "How the threads wait"); tests that set their own ENVIRONMENT say
  # so too.
  set_tests_properties(${T_NAME} PROPERTIES TIMEOUT ${T_TIMEOUT} LABELS "${T_LABELS}"
                       WORKING_DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
                       ENVIRONMENT "OMP_WAIT_POLICY=passive")
endfunction()

set(COSIM_SHARED_REFERENCES "${CMAKE_SOURCE_DIR}/references" CACHE PATH "Validation reference data")
