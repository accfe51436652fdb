#pragma once
// The live view's access token: the secret a request that changes the bench must carry
// (Authorization: Bearer <token>). It lives in a file only the service reads, under systemd a
// credential (LoadCredential=http-token:/etc/hystbench/http-token). Not real-time safe.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace hystbench::daemon {

inline constexpr std::size_t kMinAccessTokenLength = 16;

class AccessTokenError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The token file to read: `configured` when not empty, else
/// $CREDENTIALS_DIRECTORY/http-token; empty when neither names one.
std::filesystem::path access_token_path(const std::string& configured);

/// The file's content without surrounding blanks. Throws AccessTokenError naming the path and
/// the cause: unreadable, or shorter than kMinAccessTokenLength, or holding a control character.
std::string read_access_token(const std::filesystem::path& path);

/// Whether `given` equals `token`, in time that depends only on their lengths.
bool access_token_matches(std::string_view token, std::string_view given) noexcept;

}  // namespace hystbench::daemon
