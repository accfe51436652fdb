#include "hystbench/cli/offline/npy_file.hpp"

#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string_view>

#include "hystbench/cli/offline/data_table.hpp"

namespace hystbench::cli {

namespace {

constexpr std::string_view kMagic{"\x93NUMPY", 6};

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<std::size_t> shape;
};

// The header's Python dict literal, as NumPy writes it:
//   {'descr': '<f8', 'fortran_order': False, 'shape': (8192, 3, 6, 2), }
// Exactly these three keys, each once, in any order; string values in ' or " quotes; blanks
// between tokens; a trailing comma in the dict and in the shape; blanks and a newline after it.
class NpyHeaderParser {
 public:
  NpyHeaderParser(std::string_view text, const std::string& path) : text_(text), path_(path) {}

  NpyHeader parse() {
    NpyHeader header;
    bool has_descr = false, has_fortran_order = false, has_shape = false;
    expect('{');
    while (!accept('}')) {
      const std::string key = quoted("a key");
      expect(':');
      if (key == "descr" && !has_descr) {
        skip_blanks();
        if (pos_ < text_.size() && text_[pos_] == '[') {
          throw DataFileError(path_ +
                              ": unsupported dtype (a structured array; '<f8' and '<f4' "
                              "are read)");
        }
        header.descr = quoted("the dtype");
        has_descr = true;
      } else if (key == "fortran_order" && !has_fortran_order) {
        header.fortran_order = boolean();
        has_fortran_order = true;
      } else if (key == "shape" && !has_shape) {
        header.shape = shape();
        has_shape = true;
      } else {
        fail("unexpected key '" + key + "'");
      }
      if (!accept(',')) {
        expect('}');
        break;
      }
    }
    skip_blanks();
    if (pos_ != text_.size()) fail("text after the dict");
    if (!has_descr) fail("no 'descr'");
    if (!has_fortran_order) fail("no 'fortran_order'");
    if (!has_shape) fail("no 'shape'");
    return header;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    constexpr std::size_t kShown = 160;
    std::string shown(text_.substr(0, kShown));
    while (!shown.empty() && (shown.back() == ' ' || shown.back() == '\n')) shown.pop_back();
    for (char& c : shown) {
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) c = '?';
    }
    throw DataFileError(path_ + ": bad header (" + what + " at character " + std::to_string(pos_) +
                        "): " + shown + (text_.size() > kShown ? "..." : ""));
  }
  void skip_blanks() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\n')) ++pos_;
  }
  bool accept(char c) {
    skip_blanks();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!accept(c)) fail(std::string("expected '") + c + "'");
  }
  std::string quoted(const char* what) {
    skip_blanks();
    const char quote = pos_ < text_.size() ? text_[pos_] : '\0';
    if (quote != '\'' && quote != '"') fail(std::string("expected ") + what + " in quotes");
    const std::size_t end = text_.find(quote, pos_ + 1);
    if (end == std::string_view::npos) fail("unterminated string");
    std::string value(text_.substr(pos_ + 1, end - pos_ - 1));
    pos_ = end + 1;
    return value;
  }
  bool boolean() {
    skip_blanks();
    for (const auto& [word, value] : {std::pair{"True", true}, std::pair{"False", false}}) {
      if (text_.substr(pos_).starts_with(word)) {
        pos_ += std::strlen(word);
        return value;
      }
    }
    fail("expected True or False");
  }
  std::size_t integer() {
    skip_blanks();
    const std::size_t start = pos_;
    std::size_t value = 0;
    constexpr std::size_t kMax = std::numeric_limits<std::size_t>::max();
    while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9') {
      const auto digit = static_cast<std::size_t>(text_[pos_] - '0');
      if (value > (kMax - digit) / 10) fail("dimension too large");
      value = value * 10 + digit;
      ++pos_;
    }
    if (pos_ == start) fail("expected a dimension");
    return value;
  }
  // A Python tuple of dimensions: (), (5,), (8192, 3, 6, 2) or (8192, 3, 6, 2,).
  std::vector<std::size_t> shape() {
    expect('(');
    std::vector<std::size_t> dims;
    bool trailing_comma = false;
    while (!accept(')')) {
      dims.push_back(integer());
      trailing_comma = accept(',');
      if (!trailing_comma) {
        expect(')');
        break;
      }
    }
    if (dims.size() == 1 && !trailing_comma) fail("a one-dimensional shape needs its comma");
    return dims;
  }

  std::string_view text_;
  const std::string& path_;
  std::size_t pos_ = 0;
};

// Little-endian bytes of an IEEE float of Bits' width, whatever the host's byte order.
template <typename Float, typename Bits>
void decode_little_endian(const char* bytes, std::vector<double>& values) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    Bits bits = 0;
    for (std::size_t b = 0; b < sizeof(Bits); ++b) {
      bits |= static_cast<Bits>(static_cast<unsigned char>(bytes[i * sizeof(Bits) + b])) << (8 * b);
    }
    values[i] = static_cast<double>(std::bit_cast<Float>(bits));
  }
}

std::uint32_t little_endian_length(std::string_view bytes) {
  std::uint32_t value = 0;
  for (std::size_t b = 0; b < bytes.size(); ++b) {
    value |= static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[b])) << (8 * b);
  }
  return value;
}

}  // namespace

std::string shape_text(std::span<const std::size_t> shape) {
  std::string text = "(";
  for (std::size_t i = 0; i < shape.size(); ++i) {
    text += (i ? ", " : "") + std::to_string(shape[i]);
  }
  return text + (shape.size() == 1 ? ",)" : ")");
}

NpyArray read_npy(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataFileError(path + ": cannot open (" + std::strerror(errno) + ")");
  const std::string file{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw DataFileError(path + ": read failed");
  const std::string_view bytes(file);
  if (!bytes.starts_with(kMagic)) {
    throw DataFileError(path + ": not a .npy file (it does not start with \\x93NUMPY)");
  }
  // Magic, major and minor version, header length: 2 bytes in format 1.0, 4 in 2.0.
  std::size_t length_bytes = 0;
  if (bytes.size() >= 8) {
    const int major = static_cast<unsigned char>(bytes[6]);
    const int minor = static_cast<unsigned char>(bytes[7]);
    if ((major == 1 || major == 2) && minor == 0) {
      length_bytes = major == 1 ? 2 : 4;
    } else {
      throw DataFileError(path + ": unsupported .npy format version " + std::to_string(major) +
                          "." + std::to_string(minor) + " (1.0 and 2.0 are read)");
    }
  }
  const std::size_t header_start = 8 + length_bytes;
  if (length_bytes == 0 || bytes.size() < header_start) {
    throw DataFileError(path + ": bad header (the file ends inside the .npy preamble)");
  }
  const std::size_t header_length = little_endian_length(bytes.substr(8, length_bytes));
  if (bytes.size() - header_start < header_length) {
    throw DataFileError(path + ": bad header (it announces " + std::to_string(header_length) +
                        " bytes, the file holds " + std::to_string(bytes.size() - header_start) +
                        ")");
  }
  const NpyHeader header = NpyHeaderParser(bytes.substr(header_start, header_length), path).parse();

  std::size_t item_bytes = 0;
  if (header.descr == "<f8") {
    item_bytes = 8;
  } else if (header.descr == "<f4") {
    item_bytes = 4;
  } else {
    throw DataFileError(path + ": unsupported dtype '" + header.descr +
                        "' ('<f8' and '<f4' are read)");
  }
  if (header.fortran_order) {
    throw DataFileError(path + ": Fortran order is not supported (C order is read)");
  }
  std::size_t count = 1;
  for (const std::size_t dim : header.shape) {
    if (dim != 0 && count > std::numeric_limits<std::size_t>::max() / item_bytes / dim) {
      throw DataFileError(path + ": bad header (shape " + shape_text(header.shape) +
                          " is too large)");
    }
    count *= dim;
  }
  const std::size_t expected = count * item_bytes;
  const std::size_t data_start = header_start + header_length;
  const std::size_t got = bytes.size() - data_start;
  if (got < expected) {
    throw DataFileError(path + ": truncated data: expected " + std::to_string(expected) +
                        " bytes got " + std::to_string(got) + " (shape " +
                        shape_text(header.shape) + ", " + header.descr + ")");
  }
  if (got > expected) {
    throw DataFileError(path + ": " + std::to_string(got - expected) +
                        " bytes after the data (expected " + std::to_string(expected) +
                        " bytes for shape " + shape_text(header.shape) + ", " + header.descr + ")");
  }
  NpyArray array{header.shape, std::vector<double>(count)};
  const char* data = file.data() + data_start;
  if (item_bytes == 8) {
    decode_little_endian<double, std::uint64_t>(data, array.values);
  } else {
    decode_little_endian<float, std::uint32_t>(data, array.values);
  }
  return array;
}

}  // namespace hystbench::cli
