#include "hystbench/cli/offline/data_table.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace cli = hystbench::cli;

namespace {
std::string error_of(const std::string& text) {
  try {
    cli::DataTable::parse_csv(text, "f.csv");
  } catch (const cli::DataFileError& e) {
    return e.what();
  }
  return "no error";
}
}  // namespace

TEST(DataTable, ReadsCommentsHeaderAndColumnsIgnoringExtras) {
  const auto t =
      cli::DataTable::parse_csv("# {\"run\":1}\n# second\nt,u,y,extra\n0,1,2,9\n0.001,1.5,2.5,9\n");
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
  const auto t = cli::DataTable::parse_csv("t,u\n0,1\n# c\n1,1\n1,2\n", "f.csv");
  try {
    t.require_increasing("t");
    FAIL();
  } catch (const cli::DataFileError& e) {
    EXPECT_NE(std::string(e.what()).find("f.csv:5: column 't' must be strictly increasing"),
              std::string::npos);
  }
  try {
    (void)t.column("y");
    FAIL();
  } catch (const cli::DataFileError& e) {
    EXPECT_NE(std::string(e.what()).find("missing column 'y' (columns: t, u)"), std::string::npos);
  }
}

TEST(DataTable, ReadsABlankSeparatedFileWithoutHeaderByColumnPosition) {
  // The shape of a MATLAB `save -ascii` export (the NTU piezo records): blanks, no header.
  const auto t = cli::DataTable::parse_csv(
      "   1.8000000e+00   0.0   -1.2310000e+02\n\t1.9e+00\t0.0\t-1.2e+02\n", "m.dat");
  ASSERT_EQ(t.rows(), 2u);
  EXPECT_EQ(t.names(), (std::vector<std::string>{"1", "2", "3"}));
  EXPECT_DOUBLE_EQ(t.column("1")[0], 1.8);
  EXPECT_DOUBLE_EQ(t.column("3")[1], -120.0);
  EXPECT_EQ(t.line_of_row(1), 2u);
  // A blank-separated file may still have a header; a ragged row names its line.
  EXPECT_DOUBLE_EQ(cli::DataTable::parse_csv("t u\n0 1\n1 2\n").column("u")[1], 2.0);
  EXPECT_NE(error_of("1 2 3\n4 5\n").find("f.csv:2: expected 3 values, found 2"),
            std::string::npos);
  // A comma-separated file without header is read the same way.
  EXPECT_DOUBLE_EQ(cli::DataTable::parse_csv("0,5\n1,6\n").column("2")[1], 6.0);
}

TEST(DataTable, WriteThenReadRoundTrips) {
  const auto path = std::filesystem::temp_directory_path() / "hystbench_data_table_test.csv";
  std::vector<double> a{0.0, 0.1, 0.2}, b{1.23456789012, -2.0, 3.5e-7};
  cli::write_csv(path, {"t", "v"}, {&a, &b}, {"hello"});
  const auto t = cli::DataTable::read_csv(path);
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
  cli::RecordColumns c;
  c.u = "drive_mV";
  c.y = "pos_m";
  c.u_scale = 1e-3;
  c.y_scale = 1e6;
  c.rate_hz = 6400.0;
  const cli::Record r = cli::read_record(path, c, true);
  ASSERT_EQ(r.t.size(), 3u);
  EXPECT_DOUBLE_EQ(r.t[2], 2.0 / 6400.0);
  EXPECT_DOUBLE_EQ(r.sample_period_s, 1.0 / 6400.0);
  EXPECT_DOUBLE_EQ(r.u[1], 0.2);
  EXPECT_DOUBLE_EQ(r.y[2], 4.0);
  EXPECT_EQ(r.units().input, "V");    // mV x 1e-3
  EXPECT_EQ(r.units().output, "um");  // m x 1e6

  auto error_of_record = [&](const cli::RecordColumns& cols) -> std::string {
    try {
      (void)cli::read_record(path, cols, true);
    } catch (const cli::DataFileError& e) {
      return e.what();
    }
    return "no error";
  };
  // Without a rate the time column is required and named in the error with what is there.
  cli::RecordColumns no_rate = c;
  no_rate.rate_hz = 0.0;
  EXPECT_NE(
      error_of_record(no_rate).find("no time column 't' (columns: k, drive_mV, pos_m, other); "
                                    "name it with --t-column, or give the sample rate with --rate"),
      std::string::npos);
  no_rate.t = "k";
  EXPECT_DOUBLE_EQ(cli::read_record(path, no_rate, true).sample_period_s, 1.0);
  cli::RecordColumns zero = c;
  zero.y_scale = 0.0;
  EXPECT_NE(error_of_record(zero).find("y scale must be a finite, non-zero number"),
            std::string::npos);
  // y is optional where the command allows it (simulate), required elsewhere.
  cli::RecordColumns no_y = c;
  no_y.y = "absent";
  EXPECT_TRUE(cli::read_record(path, no_y, false).y.empty());
  EXPECT_NE(error_of_record(no_y).find("no output column 'absent' (columns: k, drive_mV, pos_m, "
                                       "other); name it with --y-column"),
            std::string::npos);
  std::filesystem::remove(path);
}

// Units come from the header (`name [unit]`, found as `name` too, or `name_unit` for a known
// unit), moved by the scale's power of 1000, and an option names them outright; V and um where
// nothing does. An empty unit, a time column not in s and a scale that leaves the unit unnamed
// are refused with a message naming the option.
TEST(DataTable, ReadRecordTakesTheUnitsFromTheHeaderOrTheOptions) {
  const auto dir = std::filesystem::temp_directory_path();
  const auto write = [&](const std::string& name, const std::string& header) {
    const auto p = (dir / name).string();
    std::ofstream(p) << header << "\n0,1,2\n0.001,2,3\n0.002,4,5\n";
    return p;
  };
  const std::string bracket = write("hystbench_units_bracket.csv", "t [s],F [N],x [mm]");
  cli::RecordColumns c;
  c.u = "F";
  c.y = "x";
  cli::Record r = cli::read_record(bracket, c, true);
  EXPECT_EQ(r.u_unit, "N");
  EXPECT_EQ(r.y_unit, "mm");
  EXPECT_EQ(r.units().input, "N");
  EXPECT_EQ(r.units().output, "mm");
  EXPECT_DOUBLE_EQ(r.y[2], 5.0);
  c.u = "F [N]";  // the whole header name finds the column too
  EXPECT_EQ(cli::read_record(bracket, c, true).u_unit, "N");

  // The scale moves the unit: m x 1e3 is mm; the option wins over the header.
  const std::string suffix = write("hystbench_units_suffix.csv", "t,u_N,y_m");
  c = {};
  c.u = "u_N";
  c.y = "y_m";
  c.y_scale = 1e3;
  r = cli::read_record(suffix, c, true);
  EXPECT_EQ(r.u_unit, "N");
  EXPECT_EQ(r.y_unit, "mm");
  EXPECT_DOUBLE_EQ(r.y[1], 3e3);
  c.y_unit = "um";
  c.u_unit = "kN";
  r = cli::read_record(suffix, c, true);
  EXPECT_EQ(r.y_unit, "um");
  EXPECT_EQ(r.u_unit, "kN");

  // Nothing names them: V and um.
  const std::string plain = write("hystbench_units_plain.csv", "t,u,y_model");
  c = {};
  c.y = "y_model";  // "model" is no unit
  r = cli::read_record(plain, c, true);
  EXPECT_FALSE(r.u_unit.has_value());
  EXPECT_FALSE(r.y_unit.has_value());
  EXPECT_EQ(r.units().input, "V");
  EXPECT_EQ(r.units().output, "um");

  auto error_of_record = [](const std::string& path, const cli::RecordColumns& cols) {
    try {
      (void)cli::read_record(path, cols, true);
    } catch (const cli::DataFileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  c = {};
  c.y_unit = " ";
  EXPECT_NE(error_of_record(plain, c).find("--y-unit: the unit is empty"), std::string::npos);
  c = {};
  c.u = "F";
  c.y = "x";
  const std::string empty = write("hystbench_units_empty.csv", "t,F [],x [mm]");
  EXPECT_NE(error_of_record(empty, c).find("the header of column 'F' names an empty unit; name it "
                                           "with --u-unit"),
            std::string::npos);
  c.y_scale = 2.5;
  EXPECT_NE(
      error_of_record(bracket, c).find("column 'x' is in mm, and --y-scale 2.5 turns it into"),
      std::string::npos);
  cli::RecordColumns values_only = c;
  values_only.read_units = false;  // invert's reference, an upload: values only
  EXPECT_FALSE(cli::read_record(bracket, values_only, true).y_unit.has_value());
  c.y_unit = "mm";  // named: any scale goes
  EXPECT_EQ(error_of_record(bracket, c), "no error");
  const std::string ms = write("hystbench_units_ms.csv", "t [ms],F [N],x [mm]");
  c = {};
  c.u = "F";
  c.y = "x";
  EXPECT_NE(error_of_record(ms, c).find("time column 't' names the unit 'ms'"), std::string::npos);
  for (const auto& p : {bracket, suffix, plain, empty, ms}) std::filesystem::remove(p);
}

// Records read together must agree on the units they name, and with a model's.
TEST(DataTable, CommonUnitsOfRecordsAgreeOrNameTheOneThatDiffers) {
  cli::Record a, b, none;
  a.y_unit = "mm";
  b.y_unit = "um";
  const std::vector<std::string> paths{"a.csv", "b.csv"};
  EXPECT_EQ(cli::common_units(std::vector{a, none}, paths).output, "mm");
  EXPECT_EQ(cli::common_units(std::vector{none, none}, paths).output, "um");
  try {
    (void)cli::common_units(std::vector{a, b}, paths);
    ADD_FAILURE() << "mm and um agreed";
  } catch (const cli::DataFileError& e) {
    EXPECT_STREQ(e.what(), "b.csv: the output is in um, a.csv's in mm");
  }
  hystbench::compensation::Units model;
  model.output = "\u00b5m";  // the same unit as um
  EXPECT_EQ(cli::common_units(std::vector{b, none}, paths, model).output, "\u00b5m");
  try {
    (void)cli::common_units(std::vector{none, a}, paths, model);
    ADD_FAILURE() << "mm and the model's um agreed";
  } catch (const cli::DataFileError& e) {
    EXPECT_STREQ(e.what(), "b.csv: the output is in mm, the model's in \u00b5m");
  }
}
