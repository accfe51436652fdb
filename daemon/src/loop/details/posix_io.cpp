#include "loop/details/posix_io.hpp"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

namespace hystbench::daemon::details {

bool write_all(int fd, const void* data, std::size_t size) noexcept {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

std::string errno_message(const std::string& what) { return what + ": " + std::strerror(errno); }

void replace_symlink(const std::filesystem::path& link, const std::filesystem::path& target) {
  static std::atomic<unsigned> counter{0};
  std::string name = link.filename().string();
  name.insert(0, 1, '.');  // (not "." + name: GCC 12 warns falsely about that at -O3)
  name += ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter.fetch_add(1));
  const std::filesystem::path temp = link.parent_path() / name;
  if (::symlink(target.c_str(), temp.c_str()) != 0) {
    throw std::system_error(errno, std::generic_category(), "cannot create link " + temp.string());
  }
  if (std::rename(temp.c_str(), link.c_str()) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    throw std::system_error(err, std::generic_category(), "cannot replace link " + link.string());
  }
}

}  // namespace hystbench::daemon::details
