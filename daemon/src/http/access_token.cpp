#include "hystbench/daemon/http/access_token.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace hystbench::daemon {

std::filesystem::path access_token_path(const std::string& configured) {
  if (!configured.empty()) return configured;
  const char* credentials = std::getenv("CREDENTIALS_DIRECTORY");
  if (credentials == nullptr || *credentials == '\0') return {};
  return std::filesystem::path(credentials) / "http-token";
}

std::string read_access_token(const std::filesystem::path& path) {
  if (path.empty()) {
    throw AccessTokenError(
        "no token file: set http.token_file, or run under systemd with "
        "LoadCredential=http-token:/etc/hystbench/http-token");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw AccessTokenError("cannot read the token file " + path.string() + ": " +
                           std::strerror(errno));
  }
  std::ostringstream text;
  text << in.rdbuf();
  std::string token = text.str();
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
  token.erase(token.begin(), std::find_if_not(token.begin(), token.end(), blank));
  token.erase(std::find_if_not(token.rbegin(), token.rend(), blank).base(), token.end());
  if (token.size() < kMinAccessTokenLength) {
    throw AccessTokenError("the token in " + path.string() + " is " + std::to_string(token.size()) +
                           " characters long; at least " + std::to_string(kMinAccessTokenLength) +
                           " needed (e.g. `head -c 24 /dev/urandom | base64`)");
  }
  if (std::any_of(token.begin(), token.end(),
                  [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; })) {
    throw AccessTokenError("the token in " + path.string() +
                           " holds a control character (one line of printable text)");
  }
  return token;
}

bool access_token_matches(std::string_view token, std::string_view given) noexcept {
  // Every byte of the longer one is looked at, whatever differs first.
  const std::size_t n = std::max(token.size(), given.size());
  unsigned char diff = token.size() == given.size() ? 0 : 1;
  for (std::size_t i = 0; i < n; ++i) {
    const auto a = static_cast<unsigned char>(i < token.size() ? token[i] : 0);
    const auto b = static_cast<unsigned char>(i < given.size() ? given[i] : 0);
    diff = static_cast<unsigned char>(diff | (a ^ b));
  }
  return diff == 0;
}

}  // namespace hystbench::daemon
