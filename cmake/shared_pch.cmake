# One precompiled header for every library (option HYSTBENCH_PCH, on in the demo preset): the
# third-party headers most files include and that cost most to parse (nlohmann/json in about 150
# of the libraries' files, Eigen in about 110: 1-2 s each per file at -O2), compiled once in
# hystbench_pch and reused by each library (REUSE_FROM), so no library waits for a header of
# its own. Each file still includes what it uses: the default build has no PCH, and
# source_limits' include checks run there.
option(HYSTBENCH_PCH "Precompile nlohmann/json and Eigen once and reuse them in every library" OFF)

if(HYSTBENCH_PCH)
  add_library(hystbench_pch OBJECT ${CMAKE_CURRENT_LIST_DIR}/shared_pch.cpp)
  target_link_libraries(hystbench_pch PRIVATE Eigen3::Eigen nlohmann_json::nlohmann_json)
  target_precompile_headers(hystbench_pch PRIVATE
    <nlohmann/json.hpp> <Eigen/Dense>
    <algorithm> <cmath> <functional> <map> <memory> <optional> <span> <string> <vector>)
endif()

# Makes `target` reuse the shared precompiled header (nothing without HYSTBENCH_PCH).
function(hystbench_shared_pch target)
  if(HYSTBENCH_PCH)
    target_precompile_headers(${target} REUSE_FROM hystbench_pch)
    # GCC 12 reports libstdc++'s own string copies as out of bounds once they are inlined from the
    # precompiled header (three files; none without it). The default build, without the header,
    # keeps both warnings for the project's code.
    target_compile_options(${target} PRIVATE -Wno-array-bounds -Wno-stringop-overflow)
  endif()
endfunction()
