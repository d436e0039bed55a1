# overstep_module(<name> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...] [EXTERNAL_PUBLIC ...]
#                 [EXTERNAL_PRIVATE ...])
# Declares library overstep_<name> with include/ as its public include directory. PUBLIC_DEPS and
# PRIVATE_DEPS are overstep module names; each must appear in OVERSTEP_ALLOWED_<name>, which keeps the
# module graph the DAG documented in docs/architecture.md (a violation stops the configure step).
function(overstep_module name)
  cmake_parse_arguments(M "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS;EXTERNAL_PUBLIC;EXTERNAL_PRIVATE" ${ARGN})
  if(NOT DEFINED OVERSTEP_ALLOWED_${name})
    message(FATAL_ERROR "module '${name}' is not in the module graph (OVERSTEP_ALLOWED_${name})")
  endif()
  foreach(dep IN LISTS M_PUBLIC_DEPS M_PRIVATE_DEPS)
    if(NOT dep IN_LIST OVERSTEP_ALLOWED_${name})
      message(FATAL_ERROR "module '${name}' may not depend on '${dep}' (allowed: ${OVERSTEP_ALLOWED_${name}})")
    endif()
  endforeach()
  list(TRANSFORM M_PUBLIC_DEPS PREPEND overstep_)
  list(TRANSFORM M_PRIVATE_DEPS PREPEND overstep_)
  add_library(overstep_${name} ${M_SOURCES})
  target_include_directories(overstep_${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(overstep_${name} PUBLIC ${M_PUBLIC_DEPS} ${M_EXTERNAL_PUBLIC}
                                         PRIVATE ${M_PRIVATE_DEPS} ${M_EXTERNAL_PRIVATE})
  target_compile_definitions(overstep_${name} PRIVATE OVERSTEP_DATA_DIR="${OVERSTEP_DATA_DIR}")
endfunction()

# overstep_gtest(<name> SOURCES ... LIBS ... [LABELS ...])
# A GoogleTest executable registered with CTest test by test.
function(overstep_gtest name)
  cmake_parse_arguments(T "" "" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${T_SOURCES})
  target_link_libraries(${name} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE OVERSTEP_DATA_DIR="${OVERSTEP_DATA_DIR}")
  target_include_directories(${name} PRIVATE ${OVERSTEP_DATA_DIR}/tests/support)
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                       PROPERTIES LABELS "${T_LABELS}")
  # `unit_tests` builds every unit-test binary and nothing else (the sanitizer job runs only them).
  if("unit" IN_LIST T_LABELS)
    if(NOT TARGET unit_tests)
      add_custom_target(unit_tests)
    endif()
    add_dependencies(unit_tests ${name})
  endif()
endfunction()
