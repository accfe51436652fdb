#include "hystbench/daemon/loop/sample_log_writer.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "hystbench/cli/offline/data_table.hpp"

namespace hd = hystbench::daemon;
namespace cli = hystbench::cli;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

// Each test writes into its own fresh folder, removed afterwards.
class SampleLogWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string test = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    dir_ = fs::temp_directory_path() / ("hystbench-log-" + test + "-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  hd::SampleLogOptions options(const std::string& run_id) const {
    hd::SampleLogOptions o;
    o.log_dir = dir_;
    o.run_id = run_id;
    return o;
  }
  fs::path dir_;
};

hd::SampleRecord record(std::uint64_t k) {
  hd::SampleRecord r;
  r.index = k;
  r.scheduled_ns = static_cast<std::int64_t>(k) * 100'000;
  r.wake_ns = r.scheduled_ns + 1'234 + static_cast<std::int64_t>(k % 17);
  r.exec_ns = 5'000 + static_cast<std::int64_t>(k % 3);
  r.reference = std::sin(0.001 * static_cast<double>(k)) * 40.0 + 50.0;
  r.u_ff = 1.0 / 3.0 * static_cast<double>(k);
  r.u_fb = -1e-300 * static_cast<double>(k);
  r.u_out = r.u_ff + r.u_fb;
  r.y_measured = std::nextafter(r.reference, 1e9);
  r.y_model = k % 2 ? std::numeric_limits<double>::quiet_NaN() : 0.1 * static_cast<double>(k);
  r.flags = static_cast<std::uint32_t>(k % 64);
  return r;
}

std::size_t data_rows(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::size_t rows = 0;
  bool header = false;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (!header) {
      header = true;
      continue;
    }
    if (line.back() == '\n' || line.find(',') != std::string::npos) ++rows;
  }
  return rows;
}

}  // namespace

TEST_F(SampleLogWriterTest, WritesEveryRecordExactlyAndTheFileReadsBack) {
  constexpr std::uint64_t kRecords = 50'000;
  auto options = this->options("run-0001");
  options.header = {{"params", {{"rate_hz", 10000}, {"mode", "closed-loop"}}},
                    {"model", {{"type", "mpi"}}}};
  hd::SampleLogWriter writer(options);
  EXPECT_EQ(writer.path(), dir_ / "run-0001.csv");
  for (std::uint64_t k = 0; k < kRecords; ++k) ASSERT_TRUE(writer.push(record(k)));
  const auto counts = writer.close();
  EXPECT_EQ(counts.written, kRecords);
  EXPECT_EQ(counts.dropped, 0u);
  EXPECT_TRUE(counts.error.empty()) << counts.error;

  const auto table = cli::DataTable::read_csv(writer.path().string());
  ASSERT_EQ(table.rows(), kRecords);
  const auto columns = hd::sample_log_columns();
  ASSERT_EQ(table.names().size(), columns.size());
  for (std::size_t i = 0; i < columns.size(); ++i) EXPECT_EQ(table.names()[i], columns[i]);
  for (std::uint64_t k = 0; k < kRecords; k += 997) {
    const auto r = record(k);
    EXPECT_EQ(table.column("index")[k], static_cast<double>(k));
    EXPECT_EQ(table.column("t")[k], static_cast<double>(r.scheduled_ns) / 1e9);
    EXPECT_EQ(table.column("t_wake_ns")[k], static_cast<double>(r.wake_ns));
    EXPECT_EQ(table.column("exec_ns")[k], static_cast<double>(r.exec_ns));
    // Shortest round-trip formatting: the exact same doubles come back.
    EXPECT_EQ(table.column("yr")[k], r.reference);
    EXPECT_EQ(table.column("u_ff")[k], r.u_ff);
    EXPECT_EQ(table.column("u_fb")[k], r.u_fb);
    EXPECT_EQ(table.column("u")[k], r.u_out);
    EXPECT_EQ(table.column("y")[k], r.y_measured);
    if (std::isnan(r.y_model)) {
      EXPECT_TRUE(std::isnan(table.column("y_model")[k]));
    } else {
      EXPECT_EQ(table.column("y_model")[k], r.y_model);
    }
    EXPECT_EQ(table.column("flags")[k], static_cast<double>(r.flags));
  }
  EXPECT_NO_THROW(table.require_increasing("t"));

  const auto header = hd::read_sample_log_header(writer.path());
  EXPECT_EQ(header["schema"], hd::kSampleLogSchema);
  EXPECT_EQ(header["run_id"], "run-0001");
  EXPECT_EQ(header["params"]["rate_hz"], 10000);
  EXPECT_EQ(header["model"]["type"], "mpi");
  EXPECT_EQ(header["units"]["u"], "V");
  EXPECT_EQ(header["units"]["y"], "um");
  EXPECT_EQ(header["flags"]["overrun"], hd::kSampleOverrun);
  ASSERT_EQ(header["columns"].size(), columns.size());
  EXPECT_EQ(header["columns"][1], "t");
  EXPECT_TRUE(header.contains("created"));
}

TEST_F(SampleLogWriterTest, LatestLinkPointsAtTheNewestRunAndRunsAreNeverOverwritten) {
  auto options = this->options("a");
  {
    hd::SampleLogWriter a(options);
    EXPECT_EQ(fs::read_symlink(dir_ / "latest.csv"), fs::path("a.csv"));
    options.run_id = "b";
    hd::SampleLogWriter b(options);
    EXPECT_EQ(fs::read_symlink(dir_ / "latest.csv"), fs::path("b.csv"));
    b.push(record(0));
  }
  EXPECT_EQ(fs::canonical(dir_ / "latest.csv"), fs::canonical(dir_ / "b.csv"));
  EXPECT_EQ(data_rows(dir_ / "latest.csv"), 1u);
  options.run_id = "a";
  EXPECT_THROW(hd::SampleLogWriter again(options), std::system_error);
  std::size_t temporaries = 0;
  for (const auto& e : fs::directory_iterator(dir_)) {
    temporaries += e.path().filename().string().starts_with(".") ? 1 : 0;
  }
  EXPECT_EQ(temporaries, 0u);
}

TEST_F(SampleLogWriterTest, RefusesBadRunIdsAndReservedHeaderKeys) {
  auto options = this->options("");
  for (const char* id : {"", "../escape", "latest", ".hidden", "a b", "x/y"}) {
    options.run_id = id;
    EXPECT_THROW(hd::SampleLogWriter w(options), std::invalid_argument) << id;
  }
  options.run_id = "ok";
  options.header = {{"columns", 1}};
  EXPECT_THROW(hd::SampleLogWriter w(options), std::invalid_argument);
  options.header = nlohmann::json::array();
  EXPECT_THROW(hd::SampleLogWriter w(options), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir_ / "ok.csv"));
}

TEST_F(SampleLogWriterTest, CountsDropsWhenTheRingIsFull) {
  auto options = this->options("drops");
  options.ring_capacity = 8;
  options.poll_interval = 1h;  // the writer drains only at close()
  hd::SampleLogWriter writer(options);
  int accepted = 0;
  for (std::uint64_t k = 0; k < 20; ++k) accepted += writer.push(record(k)) ? 1 : 0;
  EXPECT_EQ(accepted, 8);
  EXPECT_EQ(writer.dropped(), 12u);
  const auto counts = writer.close();
  EXPECT_EQ(counts.written, 8u);
  EXPECT_EQ(counts.dropped, 12u);
  EXPECT_FALSE(writer.push(record(99)));  // after close: refused and counted
  EXPECT_EQ(writer.dropped(), 13u);
  EXPECT_EQ(writer.close().written, 8u);  // idempotent
  const auto table = cli::DataTable::read_csv(writer.path().string());
  ASSERT_EQ(table.rows(), 8u);
  EXPECT_EQ(table.column("index").back(), 7.0);  // the oldest were kept
}

TEST_F(SampleLogWriterTest, FlushesPeriodicallyWhileTheRunGoesOn) {
  auto options = this->options("flush");
  options.poll_interval = 5ms;
  options.flush_interval = 20ms;
  hd::SampleLogWriter writer(options);
  for (std::uint64_t k = 0; k < 10; ++k) writer.push(record(k));
  // Not a timing assertion: wait (up to 10 s) until the rows show up before close().
  const auto give_up = std::chrono::steady_clock::now() + 10s;
  while (data_rows(writer.path()) < 10 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(data_rows(writer.path()), 10u);
  EXPECT_EQ(writer.written(), 10u);
  writer.close();
}
