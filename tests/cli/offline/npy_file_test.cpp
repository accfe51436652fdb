// NumPy .npy files: arrays written byte by byte here read back with their shape and the same
// doubles; files the reader does not take (no magic, another dtype, Fortran order, truncated
// data, a malformed header) give an error naming the file and the cause. `hystbench convert`
// writes a U/Y pair as one CSV in realization, period, sample order, exactly; the measured
// CubeSpec mirror set (../shared/data/piezo-fsm-cubespec) reads and converts to the same values
// as the CSV shipped with it.
#include "hystbench/cli/offline/npy_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hystbench/cli/offline/convert_command.hpp"
#include "hystbench/cli/offline/data_table.hpp"
#include "support/temp_dir_test.hpp"

namespace cli = hystbench::cli;
namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

// Little-endian bytes of each value.
template <typename Bits, typename Float>
std::string little_endian(const std::vector<Float>& values) {
  std::string bytes;
  for (const Float v : values) {
    const auto bits = std::bit_cast<Bits>(v);
    for (std::size_t b = 0; b < sizeof(Bits); ++b) {
      bytes += static_cast<char>((bits >> (8 * b)) & 0xff);
    }
  }
  return bytes;
}
std::string float64_bytes(const std::vector<double>& v) { return little_endian<std::uint64_t>(v); }

// A .npy file as NumPy writes it: magic, version, header length, the dict padded with blanks to
// a multiple of 64 bytes and ended by '\n', then the data.
std::string npy_bytes(const std::string& dict, const std::string& data, int major_version = 1) {
  const std::size_t length_bytes = major_version == 1 ? 2 : 4;
  std::string header = dict;
  while ((6 + 2 + length_bytes + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string bytes("\x93NUMPY", 6);
  bytes += static_cast<char>(major_version);
  bytes += '\0';
  for (std::size_t b = 0; b < length_bytes; ++b) {
    bytes += static_cast<char>((header.size() >> (8 * b)) & 0xff);
  }
  return bytes + header + data;
}

std::string float64_dict(const std::string& shape) {
  return "{'descr': '<f8', 'fortran_order': False, 'shape': " + shape + ", }";
}

// The shared CubeSpec mirror data set; README.md there describes it.
const fs::path kCubeSpec = fs::path(HYSTBENCH_SHARED_DATA_DIR) / "piezo-fsm-cubespec";
constexpr std::size_t kCubeSpecSamples = 8192;  // per period
constexpr double kCubeSpecRateHz = 6400.0;
// The shipped CSV's columns besides k, in both it and `convert`'s output.
const std::vector<std::string> kCubeSpecColumns = {"period", "n_in_period", "u1_V", "u2_V",
                                                   "u3_V",   "y1_m",        "y2_m", "y3_m"};

bool cubespec_300mv_test_set_present() {
  return fs::exists(kCubeSpec / "u_300mV_test.npy") && fs::exists(kCubeSpec / "y_300mV_test.npy") &&
         fs::exists(kCubeSpec / "fsm_300mV_test_realization0.csv");
}

// The rows of the shipped CSV of realization 0 (k, period, n_in_period, u1_V..y3_m) where a
// value differs from value(k, column name), or k is not period * 8192 + n_in_period.
std::size_t rows_unlike_shipped_realization0(
    const std::function<double(std::size_t, const std::string&)>& value) {
  const cli::DataTable shipped =
      cli::DataTable::read_csv((kCubeSpec / "fsm_300mV_test_realization0.csv").string());
  EXPECT_EQ(shipped.rows(), 2 * kCubeSpecSamples);
  std::size_t differing = 0;
  for (std::size_t k = 0; k < shipped.rows(); ++k) {
    bool same = shipped.column("k")[k] == static_cast<double>(k) &&
                shipped.column("period")[k] * kCubeSpecSamples + shipped.column("n_in_period")[k] ==
                    static_cast<double>(k);
    for (const std::string& name : kCubeSpecColumns) {
      same = same && shipped.column(name)[k] == value(k, name);
    }
    if (!same) ++differing;
  }
  return differing;
}

class NpyFileTest : public hystbench::test::TempDirTest {
 protected:
  NpyFileTest() : TempDirTest("hystbench_npy_test") {}

  std::string write_file(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }
  // The message of the DataFileError read_npy throws; empty when the file reads.
  static std::string read_error(const std::string& file) {
    try {
      cli::read_npy(file);
    } catch (const cli::DataFileError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(NpyFileTest, ReadsShapeAndTheSameDoubles) {
  const std::vector<double> values = {0.1,
                                      -1.0 / 3.0,
                                      std::numeric_limits<double>::denorm_min(),
                                      std::numeric_limits<double>::max(),
                                      -0.0,
                                      -2.359454981218617e-06};
  const cli::NpyArray a =
      cli::read_npy(write_file("a.npy", npy_bytes(float64_dict("(2, 3)"), float64_bytes(values))));
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{2, 3}));
  ASSERT_EQ(a.values.size(), values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.values[i]), std::bit_cast<std::uint64_t>(values[i]))
        << "value " << i;
  }
}

TEST_F(NpyFileTest, ReadsFormat2AndFloat32) {
  const std::vector<float> values = {0.1F, -3.5F, 1e-30F};
  const cli::NpyArray a = cli::read_npy(
      write_file("f4.npy", npy_bytes("{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }",
                                     little_endian<std::uint32_t>(values), 2)));
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{3}));
  EXPECT_EQ(a.values, (std::vector<double>{0.1F, -3.5F, 1e-30F}));
}

TEST_F(NpyFileTest, ReadsKeysInAnyOrderAndAZeroDimensionalArray) {
  const cli::NpyArray a = cli::read_npy(write_file(
      "scalar.npy", npy_bytes("{\"shape\": (), \"fortran_order\": False, \"descr\": \"<f8\"}",
                              float64_bytes({2.5}))));
  EXPECT_TRUE(a.shape.empty());
  EXPECT_EQ(a.values, std::vector<double>{2.5});
  const cli::NpyArray empty =
      cli::read_npy(write_file("empty.npy", npy_bytes(float64_dict("(0, 3)"), "")));
  EXPECT_EQ(empty.shape, (std::vector<std::size_t>{0, 3}));
  EXPECT_TRUE(empty.values.empty());
}

TEST_F(NpyFileTest, RefusesAFileWithoutTheMagic) {
  const std::string file = write_file("table.npy", "t,u,y\n0,1,2\n");
  EXPECT_THAT(read_error(file), HasSubstr(file + ": not a .npy file"));
  EXPECT_THAT(read_error(path("absent.npy")), HasSubstr("absent.npy: cannot open"));
}

TEST_F(NpyFileTest, RefusesOtherDtypes) {
  const std::string big_endian = write_file(
      "big.npy",
      npy_bytes("{'descr': '>f8', 'fortran_order': False, 'shape': (1,), }", float64_bytes({1.0})));
  EXPECT_THAT(read_error(big_endian), HasSubstr(big_endian + ": unsupported dtype '>f8'"));
  const std::string integers = write_file(
      "int.npy",
      npy_bytes("{'descr': '<i4', 'fortran_order': False, 'shape': (2,), }", std::string(8, '\0')));
  EXPECT_THAT(read_error(integers), HasSubstr(integers + ": unsupported dtype '<i4'"));
  const std::string structured = write_file(
      "rec.npy", npy_bytes("{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (1,), }",
                           float64_bytes({1.0})));
  EXPECT_THAT(read_error(structured), HasSubstr("unsupported dtype (a structured array"));
}

TEST_F(NpyFileTest, RefusesFortranOrder) {
  const std::string file = write_file(
      "fortran.npy", npy_bytes("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 2), }",
                               float64_bytes({1, 2, 3, 4})));
  EXPECT_THAT(read_error(file), HasSubstr(file + ": Fortran order is not supported"));
}

TEST_F(NpyFileTest, RefusesTruncatedDataAndBytesAfterIt) {
  const std::string truncated =
      write_file("short.npy", npy_bytes(float64_dict("(2, 3)"), float64_bytes({1, 2, 3, 4, 5})));
  EXPECT_THAT(read_error(truncated),
              HasSubstr(truncated + ": truncated data: expected 48 bytes got 40"));
  const std::string longer =
      write_file("long.npy", npy_bytes(float64_dict("(2,)"), float64_bytes({1, 2, 3})));
  EXPECT_THAT(read_error(longer), HasSubstr(longer + ": 8 bytes after the data"));
}

TEST_F(NpyFileTest, RefusesMalformedHeaders) {
  const std::string data = float64_bytes({1.0, 2.0});
  for (const std::string& dict :
       {std::string("{'descr': '<f8', 'fortran_order': False}"),
        std::string("{'descr': '<f8', 'fortran_order': False, 'shape': (2), }"),
        std::string("{'descr': '<f8', 'fortran_order': 0, 'shape': (2,), }"),
        std::string("{'descr': '<f8', 'fortran_order': False, 'shape': (2,), 'extra': 1}"),
        std::string("{'descr': '<f8', 'descr': '<f8', 'fortran_order': False, 'shape': (2,)}"),
        std::string("{'descr': '<f8, 'fortran_order': False, 'shape': (2,), }"),
        std::string("{'descr': '<f8', 'fortran_order': False, 'shape': (-2,), }"),
        std::string("{'descr': '<f8', 'fortran_order': False, 'shape': (2,), } x"),
        std::string("['<f8', False, (2,)]")}) {
    const std::string file = write_file("header.npy", npy_bytes(dict, data));
    EXPECT_THAT(read_error(file), HasSubstr(file + ": bad header")) << dict;
  }
  // A header length beyond the end of the file, and a format version it does not read.
  std::string cut = npy_bytes(float64_dict("(2,)"), "");
  cut.resize(40);
  EXPECT_THAT(read_error(write_file("cut.npy", cut)), HasSubstr("bad header (it announces"));
  std::string version3 = npy_bytes(float64_dict("(2,)"), data, 2);
  version3[6] = 3;
  EXPECT_THAT(read_error(write_file("v3.npy", version3)),
              HasSubstr("unsupported .npy format version 3.0"));
}

TEST_F(NpyFileTest, MeasuredCubeSpecTestSetMatchesItsCsvConversion) {
  if (!cubespec_300mv_test_set_present()) {
    GTEST_SKIP() << "shared data set piezo-fsm-cubespec (u_300mV_test.npy, y_300mV_test.npy, "
                    "fsm_300mV_test_realization0.csv) not found under "
                 << HYSTBENCH_SHARED_DATA_DIR;
  }
  const cli::NpyArray u = cli::read_npy((kCubeSpec / "u_300mV_test.npy").string());
  const cli::NpyArray y = cli::read_npy((kCubeSpec / "y_300mV_test.npy").string());
  const std::vector<std::size_t> shape = {kCubeSpecSamples, 3, 3, 2};
  ASSERT_EQ(u.shape, shape);
  ASSERT_EQ(y.shape, shape);
  // Element (n, c, r, p) at ((n*3 + c)*3 + r)*2 + p; realization r = 0.
  const auto value = [&](std::size_t k, const std::string& name) {
    const std::size_t p = k / kCubeSpecSamples, n = k % kCubeSpecSamples;
    if (name == "period") return static_cast<double>(p);
    if (name == "n_in_period") return static_cast<double>(n);
    const std::size_t c = static_cast<std::size_t>(name[1] - '1');
    return (name[0] == 'u' ? u : y).values[((n * 3 + c) * 3 + 0) * 2 + p];
  };
  EXPECT_EQ(rows_unlike_shipped_realization0(value), 0U);
}

class ConvertCommandTest : public NpyFileTest {
 protected:
  int run(const cli::ConvertCommand& cmd) {
    std::ostringstream out, err;
    const int code = cli::run_convert(cmd, out, err);
    out_ = out.str();
    err_ = err.str();
    return code;
  }
  cli::ConvertCommand command(const std::string& u, const std::string& y, double rate_hz) const {
    cli::ConvertCommand cmd;
    cmd.u_path = u;
    cmd.y_path = y;
    cmd.rate_hz = rate_hz;
    cmd.output_path = path("record.csv");
    return cmd;
  }
  // An array of `shape` whose every value is its own C-order index plus `offset`.
  std::string write_counting(const std::string& name, const std::string& shape, std::size_t count,
                             double offset) const {
    std::vector<double> values(count);
    for (std::size_t i = 0; i < count; ++i) values[i] = static_cast<double>(i) + offset;
    return write_file(name, npy_bytes(float64_dict(shape), float64_bytes(values)));
  }

  std::string out_, err_;
};

TEST_F(ConvertCommandTest, WritesRowsInRealizationPeriodSampleOrder) {
  // (N=3, channel, realization=2, period=2): U with 2 channels, Y with 1.
  cli::ConvertCommand cmd = command(write_counting("u.npy", "(3, 2, 2, 2)", 24, 0.0),
                                    write_counting("y.npy", "(3, 1, 2, 2)", 12, 0.5), 4.0);
  cmd.json_output = true;
  ASSERT_EQ(run(cmd), 0) << err_;
  const nlohmann::json result = nlohmann::json::parse(out_);
  EXPECT_EQ(result.at("rows"), 12);
  EXPECT_EQ(result.at("realizations"), 2);
  EXPECT_EQ(result.at("periods"), 2);
  EXPECT_EQ(result.at("samples_per_period"), 3);
  const cli::DataTable t = cli::DataTable::read_csv(cmd.output_path);
  EXPECT_EQ(t.names(), (std::vector<std::string>{"t", "realization", "period", "n_in_period",
                                                 "u1_V", "u2_V", "y1_m"}));
  ASSERT_EQ(t.rows(), 12U);
  std::size_t row = 0;
  for (std::size_t r = 0; r < 2; ++r) {
    for (std::size_t p = 0; p < 2; ++p) {
      for (std::size_t n = 0; n < 3; ++n, ++row) {
        EXPECT_EQ(t.column("t")[row], static_cast<double>(p * 3 + n) / 4.0) << row;
        EXPECT_EQ(t.column("realization")[row], static_cast<double>(r));
        EXPECT_EQ(t.column("period")[row], static_cast<double>(p));
        EXPECT_EQ(t.column("n_in_period")[row], static_cast<double>(n));
        EXPECT_EQ(t.column("u1_V")[row], static_cast<double>(((n * 2 + 0) * 2 + r) * 2 + p));
        EXPECT_EQ(t.column("u2_V")[row], static_cast<double>(((n * 2 + 1) * 2 + r) * 2 + p));
        EXPECT_EQ(t.column("y1_m")[row], static_cast<double>((n * 2 + r) * 2 + p) + 0.5);
      }
    }
  }
}

TEST_F(ConvertCommandTest, TakesTwoAndThreeDimensionalArraysAndGivenNames) {
  // (N, channel): one realization, one period.
  cli::ConvertCommand cmd = command(write_counting("u2.npy", "(4, 2)", 8, 0.0),
                                    write_counting("y2.npy", "(4, 1)", 4, 0.0), 2.0);
  cmd.u_names = {"V_a", "V_b"};
  cmd.y_names = {"x_um"};
  ASSERT_EQ(run(cmd), 0) << err_;
  EXPECT_THAT(out_, HasSubstr("4 rows, 2 input and 1 output channels, 1 realizations x 1 periods"));
  EXPECT_THAT(out_, HasSubstr(cmd.output_path));
  cli::DataTable t = cli::DataTable::read_csv(cmd.output_path);
  EXPECT_EQ(t.names(), (std::vector<std::string>{"t", "realization", "period", "n_in_period", "V_a",
                                                 "V_b", "x_um"}));
  EXPECT_EQ(t.column("t"), (std::vector<double>{0.0, 0.5, 1.0, 1.5}));
  EXPECT_EQ(t.column("V_b"), (std::vector<double>{1, 3, 5, 7}));
  // (N, channel, realization): one period; t starts again with each realization.
  cmd = command(write_counting("u3.npy", "(2, 1, 3)", 6, 0.0),
                write_counting("y3.npy", "(2, 1, 3)", 6, 0.25), 10.0);
  ASSERT_EQ(run(cmd), 0) << err_;
  t = cli::DataTable::read_csv(cmd.output_path);
  EXPECT_EQ(t.column("t"), (std::vector<double>{0.0, 0.1, 0.0, 0.1, 0.0, 0.1}));
  EXPECT_EQ(t.column("realization"), (std::vector<double>{0, 0, 1, 1, 2, 2}));
  EXPECT_EQ(t.column("u1_V"), (std::vector<double>{0, 3, 1, 4, 2, 5}));
  EXPECT_EQ(t.column("y1_m"), (std::vector<double>{0.25, 3.25, 1.25, 4.25, 2.25, 5.25}));
}

TEST_F(ConvertCommandTest, RefusesShapesThatDisagreeAndBadNamesWritingNothing) {
  const std::string u = write_counting("u.npy", "(4, 2, 3)", 24, 0.0);
  cli::ConvertCommand cmd = command(u, write_counting("y.npy", "(4, 2, 2)", 16, 0.0), 1.0);
  EXPECT_EQ(run(cmd), 1);
  EXPECT_THAT(err_, HasSubstr("u.npy has shape (4, 2, 3)"));
  EXPECT_THAT(err_, HasSubstr("y.npy has shape (4, 2, 2)"));
  cmd.y_path = write_counting("y1.npy", "(8,)", 8, 0.0);
  EXPECT_EQ(run(cmd), 1);
  EXPECT_THAT(err_, HasSubstr("y1.npy: shape (8,) is not (N, channel)"));
  cmd.y_path = write_counting("y_ok.npy", "(4, 1, 3)", 12, 0.0);
  cmd.u_names = {"a"};
  EXPECT_EQ(run(cmd), 1);
  EXPECT_THAT(err_, HasSubstr("--u-names gives 1 names, " + u + " has 2 channels"));
  cmd.u_names = {"a", "t"};
  EXPECT_EQ(run(cmd), 1);
  EXPECT_THAT(err_, HasSubstr("column name 't' is given twice"));
  cmd.u_names = {"a", "#b"};
  EXPECT_EQ(run(cmd), 1);
  EXPECT_THAT(err_, HasSubstr("--u-names: '#b' cannot be a CSV column name"));
  cmd.u_names.clear();
  cmd.rate_hz = 0.0;
  EXPECT_EQ(run(cmd), 1);
  EXPECT_THAT(err_, HasSubstr("--rate must be the sample rate in Hz"));
  EXPECT_FALSE(fs::exists(cmd.output_path));
}

TEST_F(ConvertCommandTest, MeasuredCubeSpecPairConvertsToTheShippedValues) {
  if (!cubespec_300mv_test_set_present()) {
    GTEST_SKIP() << "shared data set piezo-fsm-cubespec (u_300mV_test.npy, y_300mV_test.npy, "
                    "fsm_300mV_test_realization0.csv) not found under "
                 << HYSTBENCH_SHARED_DATA_DIR;
  }
  cli::ConvertCommand cmd = command((kCubeSpec / "u_300mV_test.npy").string(),
                                    (kCubeSpec / "y_300mV_test.npy").string(), kCubeSpecRateHz);
  ASSERT_EQ(run(cmd), 0) << err_;
  EXPECT_THAT(out_, HasSubstr("49152 rows, 3 input and 3 output channels, 3 realizations x 2 "
                              "periods x 8192 samples at 6400 Hz"));
  const cli::DataTable t = cli::DataTable::read_csv(cmd.output_path);
  ASSERT_EQ(t.rows(), 3 * 2 * kCubeSpecSamples);
  // Realization 0 is the first 2 * 8192 rows; t = k / 6400 as the shipped CSV's README says.
  const auto value = [&](std::size_t k, const std::string& name) { return t.column(name)[k]; };
  EXPECT_EQ(rows_unlike_shipped_realization0(value), 0U);
  for (std::size_t k = 0; k < 2 * kCubeSpecSamples; ++k) {
    ASSERT_EQ(t.column("realization")[k], 0.0) << k;
    ASSERT_EQ(t.column("t")[k], static_cast<double>(k) / kCubeSpecRateHz) << k;
  }
  EXPECT_EQ(t.column("realization")[2 * kCubeSpecSamples], 1.0);
  EXPECT_EQ(t.column("t")[2 * kCubeSpecSamples], 0.0);
}

}  // namespace
