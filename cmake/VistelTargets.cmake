# Helpers that give every vistel target the same standards.

# Warnings as errors on our own targets only (third-party headers come in as SYSTEM).
function(vistel_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Werror)
  if(VISTEL_UNITY_BUILD AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # A unity batch #includes our .cpp files, so GCC takes a class that holds a file-local
    # type for one declared in a header and warns; in a .cpp that is by design. (Clang has
    # no such warning, and refuses the option.)
    target_compile_options(${target} PRIVATE -Wno-subobject-linkage)
  endif()
  target_compile_definitions(${target} PUBLIC GLM_ENABLE_EXPERIMENTAL)
endfunction()

# vistel_library(NAME [RUNTIME] [DEPS ...] [PRIVATE_DEPS ...]): a static library from
# every .cpp in the calling folder (one concept per file; adding a file needs no edit
# here). RUNTIME adds it to vistel_core, the set every runtime program links.
function(vistel_library name)
  cmake_parse_arguments(ARG "RUNTIME" "" "DEPS;PRIVATE_DEPS" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  file(GLOB headers CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.hpp)
  add_library(${name} STATIC ${sources} ${headers})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  vistel_warnings(${name})
  if(ARG_RUNTIME)
    set_property(GLOBAL APPEND PROPERTY VISTEL_RUNTIME_LAYERS ${name})
  endif()
endfunction()

# vistel_program(NAME SOURCES... DEPS ...): an executable of ours.
function(vistel_program name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  vistel_warnings(${name})
endfunction()

# vistel_test(NAME [SINGLE] [DEPS ...] [LABELS ...] [PROPERTIES ...]): one GoogleTest
# binary from every .cpp in the calling folder, registered with ctest test by test, or
# as one ctest test when SINGLE (for suites whose shared fixture is expensive to build
# once per process). Label "unit" tests also run under ASan+UBSan in scripts/test.
function(vistel_test name)
  cmake_parse_arguments(ARG "SINGLE" "" "DEPS;LABELS;PROPERTIES" ${ARGN})
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  if(NOT sources)
    return()
  endif()
  add_executable(${name} ${sources})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} vistel_testsupport GTest::gtest GTest::gtest_main)
  vistel_warnings(${name})
  # A test's own sources are glue around the code under test (GoogleTest macros, setup,
  # checks); the libraries they link keep the build's optimisation. Optimising the glue
  # was a third of a cold build on CI's two cores, so it gets -O1 in Release and -Og
  # under the sanitizers (test_server's batch: 31 s at -O2, 22 s at -O1; test_deform's
  # under ASan: 43 s at -O1, 25 s at -Og, 22 s at -O0, but -O0 ran its test loops 1.5x
  # slower).
  if(VISTEL_SANITIZE)
    target_compile_options(${name} PRIVATE -Og)
  else()
    target_compile_options(${name} PRIVATE $<$<CONFIG:Release>:-O1>)
  endif()
  if(NOT ARG_LABELS)
    set(ARG_LABELS unit)
  endif()
  if("unit" IN_LIST ARG_LABELS)
    add_dependencies(vistel_unit_tests ${name})  # what the sanitizer pass builds
  endif()
  if(ARG_SINGLE)
    add_test(NAME ${name} COMMAND ${name} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
    set_tests_properties(${name} PROPERTIES LABELS "${ARG_LABELS}" ${ARG_PROPERTIES})
  else()
    gtest_discover_tests(${name}
      WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
      PROPERTIES LABELS "${ARG_LABELS}" ${ARG_PROPERTIES}
      DISCOVERY_TIMEOUT 120)
  endif()
endfunction()

# Adds every immediate subfolder of the calling folder that has a CMakeLists.txt.
function(vistel_add_subfolders)
  file(GLOB children LIST_DIRECTORIES true ${CMAKE_CURRENT_SOURCE_DIR}/*)
  foreach(child ${children})
    if(IS_DIRECTORY ${child} AND EXISTS ${child}/CMakeLists.txt)
      add_subdirectory(${child})
    endif()
  endforeach()
endfunction()
