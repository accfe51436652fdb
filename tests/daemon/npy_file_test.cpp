// NumPy .npy files: arrays written byte by byte here read back with their shape and the same
// doubles; files the reader does not take (no magic, another dtype, Fortran order, truncated
// data, a malformed header) give an error naming the file and the cause; the measured CubeSpec
// mirror set (../shared/data/piezo-fsm-cubespec) reads to the same values as the CSV shipped
// with it.
#include "hystbench/daemon/npy_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "hystbench/daemon/data_table.hpp"
#include "support/temp_dir_test.hpp"

namespace hd = hystbench::daemon;
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
// The shipped CSV's columns besides k.
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
  const hd::DataTable shipped =
      hd::DataTable::read_csv((kCubeSpec / "fsm_300mV_test_realization0.csv").string());
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
      hd::read_npy(file);
    } catch (const hd::DataFileError& e) {
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
  const hd::NpyArray a =
      hd::read_npy(write_file("a.npy", npy_bytes(float64_dict("(2, 3)"), float64_bytes(values))));
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{2, 3}));
  ASSERT_EQ(a.values.size(), values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a.values[i]), std::bit_cast<std::uint64_t>(values[i]))
        << "value " << i;
  }
}

TEST_F(NpyFileTest, ReadsFormat2AndFloat32) {
  const std::vector<float> values = {0.1F, -3.5F, 1e-30F};
  const hd::NpyArray a = hd::read_npy(
      write_file("f4.npy", npy_bytes("{'descr': '<f4', 'fortran_order': False, 'shape': (3,), }",
                                     little_endian<std::uint32_t>(values), 2)));
  EXPECT_EQ(a.shape, (std::vector<std::size_t>{3}));
  EXPECT_EQ(a.values, (std::vector<double>{0.1F, -3.5F, 1e-30F}));
}

TEST_F(NpyFileTest, ReadsKeysInAnyOrderAndAZeroDimensionalArray) {
  const hd::NpyArray a = hd::read_npy(write_file(
      "scalar.npy", npy_bytes("{\"shape\": (), \"fortran_order\": False, \"descr\": \"<f8\"}",
                              float64_bytes({2.5}))));
  EXPECT_TRUE(a.shape.empty());
  EXPECT_EQ(a.values, std::vector<double>{2.5});
  const hd::NpyArray empty =
      hd::read_npy(write_file("empty.npy", npy_bytes(float64_dict("(0, 3)"), "")));
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
  const hd::NpyArray u = hd::read_npy((kCubeSpec / "u_300mV_test.npy").string());
  const hd::NpyArray y = hd::read_npy((kCubeSpec / "y_300mV_test.npy").string());
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

}  // namespace
