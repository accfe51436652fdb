// The live view's token (http/access_token.hpp): read from the configured file or systemd's
// credentials folder, trimmed, refused when short, unreadable or not one line; compared whole.
#include "hystbench/daemon/http/access_token.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <fstream>

#include "support/temp_dir_test.hpp"

namespace hd = hystbench::daemon;

class AccessToken : public hystbench::test::TempDirTest {
 protected:
  AccessToken() : TempDirTest("access_token") {}
  std::filesystem::path write(const std::string& name, const std::string& text) {
    const auto p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  std::string error_of(const std::filesystem::path& p) {
    try {
      hd::read_access_token(p);
    } catch (const hd::AccessTokenError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(AccessToken, ReadsTheFileWithoutSurroundingBlanks) {
  EXPECT_EQ(hd::read_access_token(write("t", "  0123456789abcdefgh\n")), "0123456789abcdefgh");
}

TEST_F(AccessToken, RefusesWhatCannotServeAsOneNamingTheFile) {
  const auto short_one = write("short", "abc\n");
  EXPECT_NE(error_of(short_one).find(short_one.string()), std::string::npos);
  EXPECT_NE(error_of(short_one).find("at least 16"), std::string::npos);
  EXPECT_NE(error_of(write("lines", "0123456789abcdef\nsecond-line-here")).find("control"),
            std::string::npos);
  EXPECT_NE(error_of(dir_ / "absent").find("cannot read"), std::string::npos);
  EXPECT_NE(error_of({}).find("LoadCredential"), std::string::npos);
}

TEST_F(AccessToken, ComesFromSystemdsCredentialsWhenNoFileIsConfigured) {
  ::setenv("CREDENTIALS_DIRECTORY", dir_.c_str(), 1);
  EXPECT_EQ(hd::access_token_path(""), dir_ / "http-token");
  EXPECT_EQ(hd::access_token_path("/etc/x"), std::filesystem::path("/etc/x"));
  ::unsetenv("CREDENTIALS_DIRECTORY");
  EXPECT_TRUE(hd::access_token_path("").empty());
}

TEST(AccessTokenMatch, OnlyTheWholeTokenMatches) {
  EXPECT_TRUE(hd::access_token_matches("0123456789abcdef", "0123456789abcdef"));
  EXPECT_FALSE(hd::access_token_matches("0123456789abcdef", "0123456789abcde"));
  EXPECT_FALSE(hd::access_token_matches("0123456789abcdef", "0123456789abcdefg"));
  EXPECT_FALSE(hd::access_token_matches("0123456789abcdef", "1123456789abcdef"));
  EXPECT_FALSE(hd::access_token_matches("0123456789abcdef", ""));
}
