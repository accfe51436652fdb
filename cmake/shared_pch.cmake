# One precompiled header for every library (option HYSTBENCH_PCH, on in the default and demo
# presets): the third-party headers most files include and that cost most to parse (nlohmann/json in
# about 150 of the libraries' files, Eigen in about 110: 1-2 s each per file at -O2), compiled once
# in hystbench_pch and reused by each library (REUSE_FROM), so no library waits for a header of its
# own. Each file still includes what it uses: the debug preset compiles file by file without the
# header, so a missing include shows there.
option(HYSTBENCH_PCH "Precompile nlohmann/json and Eigen once and reuse them in every library" OFF)

set(HYSTBENCH_PCH_HEADERS <nlohmann/json.hpp> <Eigen/Dense>
    <algorithm> <cmath> <functional> <map> <memory> <optional> <span> <string> <vector>)
# GCC 12 reports libstdc++'s own string copies as out of bounds or overlapping once they are
# inlined from a precompiled header (a few files; none without it). The debug preset, without the
# header, keeps these warnings for the project's code.
set(HYSTBENCH_PCH_WARNINGS -Wno-array-bounds -Wno-stringop-overflow -Wno-restrict)

if(HYSTBENCH_PCH)
  add_library(hystbench_pch OBJECT ${CMAKE_CURRENT_LIST_DIR}/shared_pch.cpp)
  target_link_libraries(hystbench_pch PRIVATE Eigen3::Eigen nlohmann_json::nlohmann_json)
  target_precompile_headers(hystbench_pch PRIVATE ${HYSTBENCH_PCH_HEADERS})
endif()

# Makes `target` reuse the shared precompiled header (nothing without HYSTBENCH_PCH).
function(hystbench_shared_pch target)
  if(HYSTBENCH_PCH)
    target_precompile_headers(${target} REUSE_FROM hystbench_pch)
    target_compile_options(${target} PRIVATE ${HYSTBENCH_PCH_WARNINGS})
  endif()
endfunction()

# Gives a test executable its own precompiled header (nothing without HYSTBENCH_PCH): GoogleTest
# and the same third-party headers. Its own, because an executable compiles as position-independent
# executable code, which a library's header compiled for shared code does not match. A test file
# compiles on its own even in a unity build: the tests name their helpers freely (kDt, sine...)
# in each file's anonymous namespace.
function(hystbench_test_pch target)
  set_target_properties(${target} PROPERTIES UNITY_BUILD OFF)
  if(HYSTBENCH_PCH)
    target_link_libraries(${target} PRIVATE Eigen3::Eigen nlohmann_json::nlohmann_json)
    target_precompile_headers(${target} PRIVATE <gtest/gtest.h> <gmock/gmock.h> ${HYSTBENCH_PCH_HEADERS})
    target_compile_options(${target} PRIVATE ${HYSTBENCH_PCH_WARNINGS})
  endif()
endfunction()
