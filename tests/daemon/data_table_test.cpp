#include "hystbench/daemon/data_table.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace hd = hystbench::daemon;

namespace {
std::string error_of(const std::string& text) {
  try {
    hd::DataTable::parse_csv(text, "f.csv");
  } catch (const hd::DataFileError& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST(DataTable, ReadsCommentsHeaderAndColumnsIgnoringExtras) {
  const auto t =
      hd::DataTable::parse_csv("# {\"run\":1}\n# second\nt,u,y,extra\n0,1,2,9\n0.001,1.5,2.5,9\n");
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.comments().size(), 2u);
  EXPECT_DOUBLE_EQ(t.column("u")[1], 1.5);
  EXPECT_DOUBLE_EQ(t.sample_period(), 0.001);
  EXPECT_TRUE(t.has("extra"));
}

TEST(DataTable, ErrorsCarryTheLineNumber) {
  EXPECT_EQ(error_of("# only\n# comments\n"), "f.csv: no header row (column names) found");
  EXPECT_NE(error_of("t,u\n0,1\n1,abc\n").find("f.csv:3: column 'u': 'abc' is not a number"),
            std::string::npos);
  EXPECT_NE(error_of("t,u\n0,1\n1\n").find("f.csv:3: expected 2 values, found 1"),
            std::string::npos);
  EXPECT_NE(error_of("t,u,t\n0,1,2\n").find("duplicate column name 't'"), std::string::npos);
  EXPECT_NE(error_of("t,u\n").find("no data rows"), std::string::npos);
  const auto t = hd::DataTable::parse_csv("t,u\n0,1\n# c\n1,1\n1,2\n", "f.csv");
  try {
    t.require_increasing("t");
    FAIL();
  } catch (const hd::DataFileError& e) {
    EXPECT_NE(std::string(e.what()).find("f.csv:5: column 't' must be strictly increasing"),
              std::string::npos);
  }
  try {
    (void)t.column("y");
    FAIL();
  } catch (const hd::DataFileError& e) {
    EXPECT_NE(std::string(e.what()).find("missing column 'y' (columns: t, u)"), std::string::npos);
  }
}

TEST(DataTable, ReadsABlankSeparatedFileWithoutHeaderByColumnPosition) {
  // The shape of a MATLAB `save -ascii` export (the NTU piezo records): blanks, no header.
  const auto t = hd::DataTable::parse_csv(
      "   1.8000000e+00   0.0   -1.2310000e+02\n\t1.9e+00\t0.0\t-1.2e+02\n", "m.dat");
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.names(), (std::vector<std::string>{"1", "2", "3"}));
  EXPECT_DOUBLE_EQ(t.column("1")[0], 1.8);
  EXPECT_DOUBLE_EQ(t.column("3")[1], -120.0);
  EXPECT_EQ(t.line_of_row(1), 2u);
  // A blank-separated file may still have a header; a ragged row names its line.
  EXPECT_DOUBLE_EQ(hd::DataTable::parse_csv("t u\n0 1\n1 2\n").column("u")[1], 2.0);
  EXPECT_NE(error_of("1 2 3\n4 5\n").find("f.csv:2: expected 3 values, found 2"),
            std::string::npos);
  // A comma-separated file without header is read the same way.
  EXPECT_DOUBLE_EQ(hd::DataTable::parse_csv("0,5\n1,6\n").column("2")[1], 6.0);
}

TEST(DataTable, WriteThenReadRoundTrips) {
  const auto path = std::filesystem::temp_directory_path() / "hystbench_data_table_test.csv";
  std::vector<double> a{0.0, 0.1, 0.2}, b{1.23456789012, -2.0, 3.5e-7};
  hd::write_csv(path, {"t", "v"}, {&a, &b}, {"hello"});
  const auto t = hd::DataTable::read_csv(path);
  EXPECT_EQ(t.comments().front(), " hello");
  EXPECT_NEAR(t.column("v")[0], 1.23456789012, 1e-9);
  EXPECT_DOUBLE_EQ(t.column("v")[2], 3.5e-7);
  std::filesystem::remove(path);
}

TEST(DataTable, ReadRecordMapsNamesScalesAndARateForFilesWithoutTime) {
  const auto path = std::filesystem::temp_directory_path() / "hystbench_read_record_test.csv";
  {
    std::ofstream f(path);
    f << "k,drive_mV,pos_m,other\n0,100,1e-6,7\n1,200,2e-6,7\n2,300,4e-6,7\n";
  }
  hd::RecordColumns c;
  c.u = "drive_mV";
  c.y = "pos_m";
  c.u_scale = 1e-3;
  c.y_scale = 1e6;
  c.rate_hz = 6400.0;
  const hd::Record r = hd::read_record(path, c, true);
  ASSERT_EQ(r.t.size(), 3u);
  EXPECT_DOUBLE_EQ(r.t[2], 2.0 / 6400.0);
  EXPECT_DOUBLE_EQ(r.sample_period_s, 1.0 / 6400.0);
  EXPECT_DOUBLE_EQ(r.u[1], 0.2);
  EXPECT_DOUBLE_EQ(r.y[2], 4.0);

  auto error_of_record = [&](const hd::RecordColumns& cols) -> std::string {
    try {
      (void)hd::read_record(path, cols, true);
    } catch (const hd::DataFileError& e) {
      return e.what();
    }
    return "no error";
  };
  // Without a rate the time column is required and named in the error with what is there.
  hd::RecordColumns no_rate = c;
  no_rate.rate_hz = 0.0;
  EXPECT_NE(
      error_of_record(no_rate).find("no time column 't' (columns: k, drive_mV, pos_m, other); "
                                    "name it with --t-column, or give the sample rate with --rate"),
      std::string::npos);
  no_rate.t = "k";
  EXPECT_DOUBLE_EQ(hd::read_record(path, no_rate, true).sample_period_s, 1.0);
  hd::RecordColumns zero = c;
  zero.y_scale = 0.0;
  EXPECT_NE(error_of_record(zero).find("y scale must be a finite, non-zero number"),
            std::string::npos);
  // y is optional where the command allows it (simulate), required elsewhere.
  hd::RecordColumns no_y = c;
  no_y.y = "absent";
  EXPECT_TRUE(hd::read_record(path, no_y, false).y.empty());
  EXPECT_NE(error_of_record(no_y).find("no output column 'absent' (columns: k, drive_mV, pos_m, "
                                       "other); name it with --y-column"),
            std::string::npos);
  std::filesystem::remove(path);
}
