#pragma once
// What one request to hystbenchd may carry, shared by the daemon's socket server and the CLI
// (docs/reference/protocol.md): a request line of at most 1 MiB, which holds a model file with
// its measured frequency responses (about 85 kB written out, a few responses of 200 lines) many
// times over; a model file sent in one (`model load FILE`) at most that less the request's own
// words.
#include <cstddef>

namespace hystbench::common {

inline constexpr std::size_t kMaxRequestLineBytes = std::size_t{1} << 20;
inline constexpr std::size_t kMaxModelFileBytes = kMaxRequestLineBytes - 4096;

}  // namespace hystbench::common
