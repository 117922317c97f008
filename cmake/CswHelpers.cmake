# csw_add_library(NAME SOURCES ... DEPS ...): one static library per module,
# warnings on, -Werror under CSW_WERROR.
function(csw_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
  if(CSW_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

function(csw_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  add_library(csw::${name} ALIAS ${name})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  csw_set_warnings(${name})
endfunction()

# csw_add_test(MODULE NAME SOURCES ... DEPS ...): a GoogleTest program whose
# tests are registered with ctest as MODULE.Suite.Test, so `ctest -R io.` runs
# one module.
function(csw_add_test module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  set(target test_${module}_${name})
  add_executable(${target} ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE ${ARG_DEPS} csw_testing GTest::gtest GTest::gtest_main)
  csw_set_warnings(${target})
  # Paths to ../shared/data and the source tree are compiled into csw_testing.
  gtest_discover_tests(${target} TEST_PREFIX "${module}." DISCOVERY_TIMEOUT 60)
endfunction()
