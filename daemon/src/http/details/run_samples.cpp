#include "http/details/run_samples.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string_view>
#include <vector>

#include "hystbench/common/command_error.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "hystbench/daemon/loop/sample_record.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> cells;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma - start));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

double cell_value(std::string_view cell) {
  double v = std::numeric_limits<double>::quiet_NaN();
  const auto r = std::from_chars(cell.data(), cell.data() + cell.size(), v);
  return r.ec == std::errc() ? v : std::numeric_limits<double>::quiet_NaN();
}

// Column indices of one axis's yr, y, u and flags (suffix "" for one axis, "_x" for axis x).
struct AxisColumns {
  std::string name;
  std::size_t yr, y, u, flags;
};

std::size_t column(const std::vector<std::string_view>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  return it == header.end() ? std::string_view::npos
                            : static_cast<std::size_t>(it - header.begin());
}

std::vector<AxisColumns> axis_columns(const std::vector<std::string_view>& header) {
  std::vector<AxisColumns> axes;
  if (column(header, "y") != std::string_view::npos) {
    axes.push_back({"", column(header, "yr"), column(header, "y"), column(header, "u"),
                    column(header, "flags")});
    return axes;
  }
  for (const std::string_view h : header) {
    if (h.substr(0, 2) != "y_" || h.substr(0, 8) == "y_model_") continue;
    const std::string name(h.substr(2));
    axes.push_back({name, column(header, "yr_" + name), column(header, "y_" + name),
                    column(header, "u_" + name), column(header, "flags_" + name)});
  }
  return axes;
}

// The first line that is not a comment: the column names.
bool read_header(std::ifstream& in, std::string& line) {
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') return true;
  }
  return false;
}

}  // namespace

json decimated_run_log(const std::filesystem::path& log_dir, const std::string& run_id,
                       std::size_t points) {
  if (!valid_sample_log_id(run_id)) {
    throw common::CommandError("bad_params", "run_id: not a run's name ([A-Za-z0-9._-])");
  }
  const std::filesystem::path path = log_dir / (run_id + ".csv");
  std::error_code ec;
  const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) throw common::CommandError("unknown_run", "no sample log for run '" + run_id + "'");
  if (bytes > kMaxPlottedLogBytes) {
    throw common::CommandError("log_too_large",
                               "run '" + run_id + "': its log (" + std::to_string(bytes >> 20) +
                                   " MiB) is too large to plot in the page; read " + path.string());
  }
  std::ifstream in(path);
  std::string line;
  if (!read_header(in, line))
    throw common::CommandError("bad_log", "run '" + run_id + "': empty log");
  const std::string header_line = line;
  const std::vector<std::string_view> header = split(header_line);
  const std::size_t t_col = column(header, "t");
  const std::vector<AxisColumns> axes = axis_columns(header);
  if (t_col == std::string_view::npos || axes.empty()) {
    throw common::CommandError("bad_log", "run '" + run_id + "': no t and y columns in its log");
  }
  std::size_t rows = 0;
  while (std::getline(in, line)) rows += !line.empty() && line[0] != '#';
  const std::size_t stride =
      std::max<std::size_t>(1, (rows + points - 1) / std::max<std::size_t>(points, 1));

  in.clear();
  in.seekg(0);
  read_header(in, line);
  json t = json::array();
  std::vector<json> series(axes.size() * 3, json::array());
  const auto value_at = [](const std::vector<std::string_view>& cells, std::size_t i) {
    return i < cells.size() ? cell_value(cells[i]) : std::numeric_limits<double>::quiet_NaN();
  };
  for (std::size_t row = 0; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (row++ % stride != 0) continue;
    const std::vector<std::string_view> cells = split(line);
    t.push_back(value_at(cells, t_col));
    for (std::size_t a = 0; a < axes.size(); ++a) {
      // An open-loop row's yr is the model's output, not a reference: none is drawn there.
      const double flags = value_at(cells, axes[a].flags);
      const bool open_loop =
          std::isfinite(flags) && (static_cast<std::uint32_t>(flags) & kSampleOpenLoop) != 0U;
      series[3 * a].push_back(open_loop ? std::numeric_limits<double>::quiet_NaN()
                                        : value_at(cells, axes[a].yr));
      series[3 * a + 1].push_back(value_at(cells, axes[a].y));
      series[3 * a + 2].push_back(value_at(cells, axes[a].u));
    }
  }
  json out_axes = json::array();
  for (std::size_t a = 0; a < axes.size(); ++a) {
    out_axes.push_back({{"name", axes[a].name},
                        {"yr", std::move(series[3 * a])},
                        {"y", std::move(series[3 * a + 1])},
                        {"u", std::move(series[3 * a + 2])}});
  }
  return {{"run_id", run_id}, {"rows", rows}, {"t", std::move(t)}, {"axes", std::move(out_axes)}};
}

}  // namespace hystbench::daemon::details
