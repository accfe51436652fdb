#pragma once
// A GoogleTest fixture with a fresh folder per test, <temp>/<prefix>_<pid>_<test name>, created
// before the test and removed after it, unless the test failed: then its logs and models stay
// for a look, and the test's output names the folder (a fixture that overrides TearDown calls
// this one last).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>

namespace hystbench::test {

class TempDirTest : public ::testing::Test {
 protected:
  explicit TempDirTest(std::string prefix) : prefix_(std::move(prefix)) {}

  void SetUp() override {
    // A parameterised test's name holds a '/' ("Name/mpi"): one folder level, not two, so that
    // TearDown removes the whole folder.
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + "_" + std::to_string(::getpid()) + "_" + name);
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (HasFailure()) {
      std::cout << "kept for a look: " << dir_.string() << "\n";
    } else {
      std::filesystem::remove_all(dir_);
    }
  }

  /// `name` inside the test's folder.
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

}  // namespace hystbench::test
