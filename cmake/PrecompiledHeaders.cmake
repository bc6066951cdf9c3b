# Precompiled headers for every C++ target (PICKSIGHT_PCH). Three sources in
# four include OpenCV's core and imgproc and the same standard headers, and
# every test source Catch2: parsed once per build instead of once per
# source. Hosts make them, one per set of flags a precompiled header must
# share with its users (the optimization level among them: __OPTIMIZE__
# changes the standard library's inlines): picksight_pch for the libraries,
# programs and benchmarks (the build type's -O2), picksight_test_pch for the
# test sources (-O0, tests/CMakeLists.txt) and, in a fuzzing build,
# picksight_fuzz_pch for the libraries with the fuzzers' coverage. Every
# other target reuses one of them (the hosts' own sources are empty).
#
# The headers are included ahead of each source, so a source that forgot
# one of them still compiles here: a tree without them (the option's
# default: a developer's, the demo's, the package's) shows it.

# The headers, in the order they are included: the standard ones that 20 or
# more sources include, and OpenCV's core and imgproc (three sources in
# four). Not the others that many sources include: with ZeroMQ's and
# Protobuf's the header took 0.7 s to load into a source that needs none of
# it (0.3 s without); with CLI11's, 8 s, and nlohmann-json's, 2 s (gcc
# compiles what their headers define, such as CLI11's validators, in every
# source that includes them, which no precompiling saves).
set(PICKSIGHT_PCH_HEADERS
  <algorithm> <array> <atomic> <chrono> <cmath> <cstdint> <cstring> <functional> <map> <memory>
  <mutex> <optional> <string> <thread> <vector> <opencv2/core.hpp> <opencv2/imgproc.hpp>)

# Every target defined in `dir` and the directories below it.
function(picksight_targets_below dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    picksight_targets_below(${sub} below)
    list(APPEND targets ${below})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

# Whether `target` links picksight_test_main, itself or through a library
# that does (picksight_test_support).
function(picksight_links_test_main target out)
  get_target_property(libs ${target} LINK_LIBRARIES)
  set(found FALSE)
  foreach(lib IN LISTS libs)
    if(lib STREQUAL "picksight_test_main")
      set(found TRUE)
    elseif(TARGET ${lib} AND lib MATCHES "^picksight_test")
      get_target_property(lib_type ${lib} TYPE)
      if(NOT lib_type STREQUAL "INTERFACE_LIBRARY")
        picksight_links_test_main(${lib} found)
      endif()
    endif()
    if(found)
      break()
    endif()
  endforeach()
  set(${out} ${found} PARENT_SCOPE)
endfunction()

# A target that compiles the headers and nothing else (cmake/pch_host.cpp
# is empty), with the flags its users share: those of OPTIONS and of the
# targets in LIBS (their usage requirements).
function(picksight_pch_host name)
  cmake_parse_arguments(H "" "" "OPTIONS;LIBS;HEADERS" ${ARGN})
  add_library(${name} OBJECT ${CMAKE_SOURCE_DIR}/cmake/pch_host.cpp)
  target_link_libraries(${name} PRIVATE ${H_LIBS} opencv_core opencv_imgproc picksight_warnings)
  target_compile_options(${name} PRIVATE ${H_OPTIONS})
  target_precompile_headers(${name} PRIVATE ${H_HEADERS})
endfunction()

# Called once, after every target is defined (the top CMakeLists.txt).
function(picksight_precompile_headers)
  # A header is used only where the predefined macros it reads are the
  # same: -Wpedantic (picksight_warnings) takes __cpp_runtime_arrays away
  # and -pthread (Threads::Threads, some targets) defines _REENTRANT. The
  # hosts link the warnings, and every target compiles with -pthread.
  set(flags -pthread)
  picksight_pch_host(picksight_pch OPTIONS ${flags} HEADERS ${PICKSIGHT_PCH_HEADERS})
  set(hosts picksight_pch)
  # clang refuses a header compiled without the fuzzers' coverage in a
  # source compiled with it (the libraries a request reaches, CMakeLists.txt).
  set(fuzz_option -fsanitize=fuzzer-no-link)
  if(PICKSIGHT_FUZZ)
    picksight_pch_host(picksight_fuzz_pch OPTIONS ${flags} ${fuzz_option}
      HEADERS ${PICKSIGHT_PCH_HEADERS})
    list(APPEND hosts picksight_fuzz_pch)
  endif()
  if(TARGET picksight_test_main)
    picksight_pch_host(picksight_test_pch OPTIONS ${flags} LIBS picksight_test_main
      HEADERS ${PICKSIGHT_PCH_HEADERS} <catch2/catch.hpp>)
    # picksight_test_main gives the host its flags, and has none: Catch2's
    # main is made where its header is first included with
    # CATCH_CONFIG_RUNNER defined, not behind a header that has it already.
    list(APPEND hosts picksight_test_pch picksight_test_main)
  endif()
  picksight_targets_below(${CMAKE_SOURCE_DIR} targets)
  foreach(target IN LISTS targets)
    if(target IN_LIST hosts)
      continue()
    endif()
    get_target_property(type ${target} TYPE)
    if(NOT type MATCHES "^(STATIC_LIBRARY|OBJECT_LIBRARY|EXECUTABLE)$")
      continue()
    endif()
    # Position-independent code (the Protobuf library, shared by the
    # Python module) needs a header compiled with -fPIC.
    get_target_property(pic ${target} POSITION_INDEPENDENT_CODE)
    if(pic)
      continue()
    endif()
    get_target_property(sources ${target} SOURCES)
    list(FILTER sources INCLUDE REGEX "\\.(cpp|cc)$")
    if(NOT sources)
      continue()
    endif()
    # The test sources compile at -O0 and see the tests' definitions
    # (picksight_test_main's): the tests' header.
    set(test FALSE)
    if(TARGET picksight_test_main)
      picksight_links_test_main(${target} test)
    endif()
    get_target_property(options ${target} COMPILE_OPTIONS)
    if(test)
      target_precompile_headers(${target} REUSE_FROM picksight_test_pch)
    elseif(PICKSIGHT_FUZZ AND fuzz_option IN_LIST options)
      target_precompile_headers(${target} REUSE_FROM picksight_fuzz_pch)
    else()
      target_precompile_headers(${target} REUSE_FROM picksight_pch)
    endif()
    target_compile_options(${target} PRIVATE ${flags})
  endforeach()
endfunction()
