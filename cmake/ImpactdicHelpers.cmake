# Small helpers so every module, test and benchmark is declared the same way.

# Warnings and sanitizers shared by every target of ours.
function(impactdic_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wno-missing-field-initializers)
  if(IMPACTDIC_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(IMPACTDIC_PYTHON)
    # The module libraries are position-independent code for the Python module
    # (impactdic_add_module): our functions are not replaced at load time, so GCC may inline them
    # as in an executable's code.
    target_compile_options(${target} PRIVATE -fno-semantic-interposition)
  endif()
  if(IMPACTDIC_SANITIZE)
    # GCC 12's -Wmaybe-uninitialized gives false positives inside libstdc++ (std::regex,
    # std::function) once the sanitizers instrument the code; the Release build keeps the warning.
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
                                             -fno-sanitize-recover=undefined
                                             -Wno-maybe-uninitialized)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()

# impactdic_add_module(NAME dic SOURCES a.cc b.cc DEPS impactdic::core PRIVATE_DEPS ...)
# creates the library impactdic_<NAME> with the alias impactdic::<NAME>.
function(impactdic_add_module)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  set(target impactdic_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SOURCES})
  add_library(impactdic::${ARG_NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
                                              $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  impactdic_target_defaults(${target})
  if(IMPACTDIC_PYTHON)  # Linked into the Python module, a shared object.
    set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  endif()
  # Installed as impactdic::<NAME> of the exported package (top CMakeLists.txt, "Install").
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${ARG_NAME})
  install(TARGETS ${target} EXPORT impactdicTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
endfunction()

# impactdic_registered_sources(VAR reference_update_policies.def) sets VAR to the source files named
# by a registration list: each line `IMPACTDIC_<WHAT>(..., "file.cc")` of the list (a file included
# by the C++ code to declare and table the built-ins) names the file defining that entry, relative
# to the list's folder. So a built-in policy, ODE method or output writer is one new file and one
# line in its list, with no CMake edit (docs/development.md, "Extension points"); CMake configures
# again when the list changes, and a line naming a missing file stops the configuration.
function(impactdic_registered_sources var list_file)
  get_filename_component(list_path ${list_file} ABSOLUTE)
  get_filename_component(list_dir ${list_path} DIRECTORY)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${list_path})
  file(STRINGS ${list_path} lines REGEX "^IMPACTDIC_[A-Z_]+\\(")
  set(sources)
  foreach(line IN LISTS lines)
    if(NOT line MATCHES ", *\"([^\"]+\\.cc)\"\\) *$")
      message(FATAL_ERROR
              "${list_path}: '${line}' does not end with its source file: ..., \"file.cc\")")
    endif()
    set(source ${list_dir}/${CMAKE_MATCH_1})
    if(NOT EXISTS ${source})
      message(FATAL_ERROR "${list_path}: '${line}' names ${source}, which does not exist")
    endif()
    list(APPEND sources ${source})
  endforeach()
  if(NOT sources)
    message(FATAL_ERROR
            "${list_path}: no registration line: expected IMPACTDIC_...(..., \"file.cc\")")
  endif()
  list(REMOVE_DUPLICATES sources)
  set(${var} ${sources} PARENT_SCOPE)
endfunction()

# The headers nearly every test includes (GoogleTest, OpenCV's core, the standard library), compiled
# once per build and reused by every test program: they were about half of each test file's compile
# time. A test whose flags differ from the precompiling target's falls back to reading the headers.
function(impactdic_test_precompiled_headers target)
  if(NOT TARGET impactdic_test_pch)
    file(WRITE ${CMAKE_BINARY_DIR}/impactdic_test_pch.cc "// Only compiles the tests' headers.\n")
    add_library(impactdic_test_pch OBJECT ${CMAKE_BINARY_DIR}/impactdic_test_pch.cc)
    target_link_libraries(impactdic_test_pch PRIVATE GTest::gtest impactdic_deps::opencv_codecs
                                                     impactdic::core)
    impactdic_target_defaults(impactdic_test_pch)
    target_precompile_headers(impactdic_test_pch PRIVATE
        <gtest/gtest.h> <opencv2/core.hpp> <opencv2/imgproc.hpp> <fmt/format.h>
        <algorithm> <cmath> <cstdint> <filesystem> <fstream> <map> <memory> <sstream> <string>
        <vector>)
  endif()
  target_precompile_headers(${target} REUSE_FROM impactdic_test_pch)
endfunction()

# impactdic_add_test(NAME dic_bspline_test SOURCES bspline_test.cc DEPS impactdic::dic [LABELS slow]
#                    [WHOLE])
# Each test case is its own CTest test (run in parallel processes), unless WHOLE: then the program
# is one CTest test, for suites whose expensive shared fixture must run once. A label listed in
# IMPACTDIC_SKIP_TEST_LABELS leaves the program out of the default build and of CTest.
function(impactdic_add_test)
  cmake_parse_arguments(ARG "WHOLE" "NAME" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${ARG_NAME} ${ARG_SOURCES})
  impactdic_test_precompiled_headers(${ARG_NAME})
  # Tests may read and write images with OpenCV directly (the library itself does not link it).
  target_link_libraries(${ARG_NAME} PRIVATE ${ARG_DEPS} impactdic_deps::opencv_codecs GTest::gtest
                                            GTest::gtest_main impactdic_test_worker_threads
                                            impactdic_test_paths
                                            impactdic::core)
  impactdic_target_defaults(${ARG_NAME})
  foreach(label IN LISTS ARG_LABELS)
    if(label IN_LIST IMPACTDIC_SKIP_TEST_LABELS)
      set_target_properties(${ARG_NAME} PROPERTIES EXCLUDE_FROM_ALL TRUE)
      return()
    endif()
  endforeach()
  if(ARG_WHOLE)
    add_test(NAME ${ARG_NAME} COMMAND ${ARG_NAME})
    set_tests_properties(${ARG_NAME} PROPERTIES LABELS "${ARG_LABELS}")
  else()
    gtest_discover_tests(${ARG_NAME} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
  endif()
endfunction()

# impactdic_add_benchmark(NAME dic_benchmark SOURCES dic_benchmark.cc DEPS impactdic::dic)
function(impactdic_add_benchmark)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;DEPS" ${ARGN})
  add_executable(${ARG_NAME} ${ARG_SOURCES})
  target_link_libraries(${ARG_NAME} PRIVATE ${ARG_DEPS} impactdic_deps::opencv_codecs
                                            benchmark::benchmark)
  impactdic_target_defaults(${ARG_NAME})
endfunction()
