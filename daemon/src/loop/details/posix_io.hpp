#pragma once
// Small POSIX helpers shared by the daemon's units (not part of the public API).
#include <cstddef>
#include <filesystem>
#include <string>

namespace hystbench::daemon::details {

/// write() until everything is written, retrying EINTR; false with errno set on failure.
bool write_all(int fd, const void* data, std::size_t size) noexcept;

/// "what: strerror(errno)".
std::string errno_message(const std::string& what);

/// Points `link` at `target` atomically: a symlink under a temporary name in the same folder,
/// then rename() over `link`. Throws std::system_error naming the link.
void replace_symlink(const std::filesystem::path& link, const std::filesystem::path& target);

}  // namespace hystbench::daemon::details
