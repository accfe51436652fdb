#include "hystbench/cli/offline/convert_command.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <ostream>
#include <set>
#include <stdexcept>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/offline/npy_file.hpp"
#include "hystbench/compensation/number_text.hpp"

namespace hystbench::cli {

namespace {

// Enough significant digits for every double to read back as the same double.
constexpr int kExactDigits = 17;

// An array's axes as (N, channel, realization, period); the axes a file leaves out are 1.
struct RecordLayout {
  std::size_t samples = 0, channels = 0, realizations = 1, periods = 1;

  static RecordLayout of(const NpyArray& array, const std::string& path) {
    const auto& shape = array.shape;
    if (shape.size() < 2 || shape.size() > 4) {
      throw DataFileError(path + ": shape " + shape_text(shape) +
                          " is not (N, channel), (N, channel, realization) or (N, channel, "
                          "realization, period)");
    }
    if (array.values.empty()) {
      throw DataFileError(path + ": shape " + shape_text(shape) + " holds no samples");
    }
    return {shape[0], shape[1], shape.size() > 2 ? shape[2] : 1, shape.size() > 3 ? shape[3] : 1};
  }
  bool same_record(const RecordLayout& other) const {
    return samples == other.samples && realizations == other.realizations &&
           periods == other.periods;
  }
  /// The C-order index of sample n of channel c in realization r, period p.
  std::size_t index(std::size_t n, std::size_t c, std::size_t r, std::size_t p) const {
    return ((n * channels + c) * realizations + r) * periods + p;
  }
};

// The given names, one per channel, or <prefix><i>_<unit> for i = 1, 2, ...
std::vector<std::string> channel_names(const std::vector<std::string>& given, std::size_t channels,
                                       const std::string& prefix, const std::string& unit,
                                       const std::string& option, const std::string& path) {
  if (given.empty()) {
    std::vector<std::string> names(channels, prefix);
    for (std::size_t c = 1; c <= channels; ++c) names[c - 1].append(std::to_string(c)).append(unit);
    return names;
  }
  if (given.size() != channels) {
    throw std::invalid_argument(option + " gives " + std::to_string(given.size()) + " names, " +
                                path + " has " + std::to_string(channels) + " channels");
  }
  const auto unusable = std::find_if(given.begin(), given.end(), [](const std::string& name) {
    return name.empty() || name.front() == '#' ||
           name.find_first_of(",\"\r\n") != std::string::npos;
  });
  if (unusable != given.end()) {
    throw std::invalid_argument(option + ": '" + *unusable + "' cannot be a CSV column name");
  }
  return given;
}

// The columns before the channels: a row's time, realization, period and sample in the period.
constexpr std::array<const char*, 4> kIndexColumns{"t", "realization", "period", "n_in_period"};

// The CSV's column names: the index columns, then the input and the output channels; each
// name once.
std::vector<std::string> column_names(const ConvertCommand& cmd, const RecordLayout& u_layout,
                                      const RecordLayout& y_layout) {
  std::vector<std::string> names(kIndexColumns.begin(), kIndexColumns.end());
  for (const auto& name :
       channel_names(cmd.u_names, u_layout.channels, "u", "_V", "--u-names", cmd.u_path)) {
    names.push_back(name);
  }
  for (const auto& name :
       channel_names(cmd.y_names, y_layout.channels, "y", "_m", "--y-names", cmd.y_path)) {
    names.push_back(name);
  }
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (!seen.insert(name).second) {
      throw std::invalid_argument("column name '" + name + "' is given twice");
    }
  }
  return names;
}

// The CSV's columns: a row per sample of each realization and period, in that order, with the
// index columns and then the channels of u and of y.
std::vector<std::vector<double>> record_columns(const NpyArray& u, const RecordLayout& u_layout,
                                                const NpyArray& y, const RecordLayout& y_layout,
                                                double rate_hz, std::size_t column_count) {
  const RecordLayout& layout = u_layout;
  const std::size_t rows = layout.samples * layout.realizations * layout.periods;
  std::vector<std::vector<double>> columns(column_count, std::vector<double>(rows));
  std::size_t row = 0;
  for (std::size_t r = 0; r < layout.realizations; ++r) {
    for (std::size_t p = 0; p < layout.periods; ++p) {
      for (std::size_t n = 0; n < layout.samples; ++n, ++row) {
        columns[0][row] = static_cast<double>(p * layout.samples + n) / rate_hz;
        columns[1][row] = static_cast<double>(r);
        columns[2][row] = static_cast<double>(p);
        columns[3][row] = static_cast<double>(n);
        std::size_t column = kIndexColumns.size();
        for (std::size_t c = 0; c < u_layout.channels; ++c) {
          columns[column++][row] = u.values[u_layout.index(n, c, r, p)];
        }
        for (std::size_t c = 0; c < y_layout.channels; ++c) {
          columns[column++][row] = y.values[y_layout.index(n, c, r, p)];
        }
      }
    }
  }
  return columns;
}

}  // namespace

int run_convert(const ConvertCommand& cmd, std::ostream& out, std::ostream& err) {
  try {
    if (!std::isfinite(cmd.rate_hz) || cmd.rate_hz <= 0.0) {
      throw std::invalid_argument("--rate must be the sample rate in Hz, positive and finite");
    }
    const NpyArray u = read_npy(cmd.u_path);
    const NpyArray y = read_npy(cmd.y_path);
    const RecordLayout u_layout = RecordLayout::of(u, cmd.u_path);
    const RecordLayout y_layout = RecordLayout::of(y, cmd.y_path);
    if (!u_layout.same_record(y_layout)) {
      throw DataFileError(cmd.u_path + " has shape " + shape_text(u.shape) + ", " + cmd.y_path +
                          " has shape " + shape_text(y.shape) +
                          ": N, realizations and periods must agree");
    }
    const std::vector<std::string> names = column_names(cmd, u_layout, y_layout);
    const RecordLayout& layout = u_layout;
    const std::size_t rows = layout.samples * layout.realizations * layout.periods;
    const std::vector<std::vector<double>> columns =
        record_columns(u, u_layout, y, y_layout, cmd.rate_hz, names.size());
    std::vector<const std::vector<double>*> column_pointers;
    column_pointers.reserve(columns.size());
    for (const auto& column : columns) column_pointers.push_back(&column);
    const std::string rate = compensation::significant(cmd.rate_hz, 10);
    write_csv(cmd.output_path, names, column_pointers,
              {"hystbench convert u=" + cmd.u_path + " y=" + cmd.y_path + " rate_hz=" + rate,
               "t [s] = (period * " + std::to_string(layout.samples) +
                   " + n_in_period) / rate, from 0 in each realization"},
              kExactDigits);

    if (cmd.json_output) {
      const nlohmann::json result = {{"output", cmd.output_path},
                                     {"rows", rows},
                                     {"u_channels", u_layout.channels},
                                     {"y_channels", y_layout.channels},
                                     {"realizations", layout.realizations},
                                     {"periods", layout.periods},
                                     {"samples_per_period", layout.samples},
                                     {"rate_hz", cmd.rate_hz},
                                     {"columns", names}};
      out << result.dump() << "\n";
    } else {
      out << "wrote " << cmd.output_path << ": " << rows << " rows, " << u_layout.channels
          << " input and " << y_layout.channels << " output channels, " << layout.realizations
          << " realizations x " << layout.periods << " periods x " << layout.samples
          << " samples at " << rate << " Hz\n";
    }
    return 0;
  } catch (const std::exception& e) {
    err << "hystbench: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace hystbench::cli
