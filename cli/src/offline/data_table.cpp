#include "hystbench/cli/offline/data_table.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string_view>
#include <utility>

#include "hystbench/compensation/number_text.hpp"

namespace hystbench::cli {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// Cells of one line: comma-separated, or (whitespace_separated) split on runs of blanks.
std::vector<std::string> split(const std::string& line, bool whitespace_separated) {
  std::vector<std::string> out;
  std::string cell;
  std::stringstream ss(line);
  if (whitespace_separated) {
    while (ss >> cell) out.push_back(cell);
    return out;
  }
  while (std::getline(ss, cell, ',')) out.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

bool is_number(const std::string& c) {
  if (c.empty()) return false;
  char* end = nullptr;
  std::strtod(c.c_str(), &end);
  return end == c.c_str() + c.size();
}

// A header name's bracket form `name [unit]`: the name and the unit (empty for `[]`).
std::optional<std::pair<std::string, std::string>> bracket_form(const std::string& header) {
  const auto open = header.rfind('[');
  if (header.empty() || header.back() != ']' || open == std::string::npos) return std::nullopt;
  std::string name = trim(header.substr(0, open));
  if (name.empty()) return std::nullopt;
  return std::pair{name, trim(header.substr(open + 1, header.size() - open - 2))};
}

// Powers of ten of the SI prefixes a unit may carry (µ in both spellings; u is written).
constexpr std::pair<std::string_view, int> kPrefixes[] = {
    {"G", 9},  {"M", 6},       {"k", 3},       {"c", -2}, {"m", -3},
    {"u", -6}, {"\u00b5", -6}, {"\u03bc", -6}, {"n", -9}, {"p", -12}};
constexpr std::string_view kPrefixed[] = {"m", "V", "N", "A", "Pa", "W", "s", "rad", "T", "Hz"};
constexpr std::string_view kUnprefixed[] = {"deg", "bar"};

bool prefixable(std::string_view unit) {
  return std::find(std::begin(kPrefixed), std::end(kPrefixed), unit) != std::end(kPrefixed);
}

// A known unit as (power of ten of its prefix, unit without prefix); unset for another string.
std::optional<std::pair<int, std::string>> known_unit(const std::string& unit) {
  for (const auto& [prefix, power] : kPrefixes) {
    if (unit.size() > prefix.size() && unit.starts_with(prefix) &&
        prefixable(std::string_view(unit).substr(prefix.size()))) {
      return std::pair{power, unit.substr(prefix.size())};
    }
  }
  if (prefixable(unit) ||
      std::find(std::begin(kUnprefixed), std::end(kUnprefixed), unit) != std::end(kUnprefixed)) {
    return std::pair{0, unit};
  }
  return std::nullopt;
}

// The unit of values in `unit` multiplied by `scale`: m with 1e6 is um, mV with 1e-3 is V.
// Unset when the scale is not a power of ten that moves a known unit onto a prefix.
std::optional<std::string> scaled_unit(const std::string& unit, double scale) {
  if (scale == 1.0) return unit;
  const auto known = known_unit(unit);
  if (!known || !(scale > 0.0)) return std::nullopt;
  const double decades = std::log10(scale);
  const auto power = static_cast<int>(std::lround(decades));
  if (std::abs(decades - power) > 1e-9) return std::nullopt;
  const int target = known->first - power;
  if (target == 0) return known->second;
  if (!prefixable(known->second)) return std::nullopt;
  for (const auto& [prefix, p] : kPrefixes) {
    if (p == target) return std::string(prefix) + known->second;
  }
  return std::nullopt;
}

// Units compared with µ (either spelling) read as u.
bool same_unit(const std::string& a, const std::string& b) {
  const auto plain = [](const std::string& unit) {
    const auto known = known_unit(unit);
    return known && known->first == -6 ? "u" + known->second : unit;
  };
  return plain(a) == plain(b);
}

// The number a data cell holds; throws DataFileError naming the file, line and column when it
// holds none, or one out of double's range.
double cell_value(const std::string& cell, const std::string& origin, std::size_t line_no,
                  const std::string& column) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(cell.c_str(), &end);
  if (cell.empty() || end != cell.c_str() + cell.size() || errno == ERANGE) {
    throw DataFileError(origin + ":" + std::to_string(line_no) + ": column '" + column + "': '" +
                        cell + "' is not a number");
  }
  return v;
}

}  // namespace

DataTable DataTable::parse_csv(const std::string& text, const std::string& origin) {
  DataTable t;
  t.origin_ = origin;
  std::istringstream in(text);
  std::string line;
  std::size_t line_no = 0;
  bool have_header = false;
  bool whitespace_separated = false;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string s = trim(line);
    if (s.empty()) continue;
    if (s[0] == '#') {
      t.comments_.push_back(s.substr(1));
      continue;
    }
    if (!have_header) whitespace_separated = s.find(',') == std::string::npos;
    const auto cells = split(s, whitespace_separated);
    if (!have_header && std::all_of(cells.begin(), cells.end(), is_number)) {
      // No header: a bare numeric export (MATLAB's save -ascii, a DAQ's .dat). The columns are
      // named by their 1-based position, and this line is the first row.
      for (std::size_t i = 0; i < cells.size(); ++i) {
        t.names_.push_back(std::to_string(i + 1));
        t.index_.emplace(t.names_.back(), i);
      }
      t.columns_.resize(cells.size());
      have_header = true;
    } else if (!have_header) {
      for (std::size_t i = 0; i < cells.size(); ++i) {
        if (cells[i].empty()) {
          throw DataFileError(origin + ":" + std::to_string(line_no) + ": header column " +
                              std::to_string(i + 1) + " has no name");
        }
        if (!t.index_.emplace(cells[i], i).second) {
          throw DataFileError(origin + ":" + std::to_string(line_no) + ": duplicate column name '" +
                              cells[i] + "'");
        }
      }
      // `F [N]` is found as `F` too, unless a column is named `F` or two are `F [...]`.
      std::map<std::string, int> bare;
      for (const auto& c : cells) {
        if (const auto b = bracket_form(c)) ++bare[b->first];
      }
      for (std::size_t i = 0; i < cells.size(); ++i) {
        const auto b = bracket_form(cells[i]);
        if (b && bare[b->first] == 1) t.index_.emplace(b->first, i);
      }
      t.names_ = cells;
      t.columns_.resize(cells.size());
      have_header = true;
      continue;
    }
    if (cells.size() != t.names_.size()) {
      throw DataFileError(origin + ":" + std::to_string(line_no) + ": expected " +
                          std::to_string(t.names_.size()) + " values, found " +
                          std::to_string(cells.size()));
    }
    for (std::size_t i = 0; i < cells.size(); ++i) {
      t.columns_[i].push_back(cell_value(cells[i], origin, line_no, t.names_[i]));
    }
    t.line_of_row_.push_back(line_no);
  }
  if (!have_header) throw DataFileError(origin + ": no header row (column names) found");
  if (t.rows() == 0) throw DataFileError(origin + ": no data rows after the header");
  return t;
}

DataTable DataTable::read_csv(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DataFileError(path + ": cannot open (" + std::string(std::strerror(errno)) + ")");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_csv(ss.str(), path);
}

const std::vector<double>& DataTable::column(const std::string& name) const {
  const auto it = index_.find(name);
  if (it == index_.end()) {
    std::string have;
    for (const auto& n : names_) have += (have.empty() ? "" : ", ") + n;
    throw DataFileError(origin_ + ": missing column '" + name + "' (columns: " + have + ")");
  }
  return columns_[it->second];
}

std::optional<std::string> DataTable::unit(const std::string& column) const {
  const auto it = index_.find(column);
  if (it == index_.end()) return std::nullopt;
  const std::string& header = names_[it->second];
  if (const auto b = bracket_form(header)) return b->second;
  const auto underscore = header.rfind('_');
  if (underscore == std::string::npos || underscore == 0) return std::nullopt;
  std::string suffix = header.substr(underscore + 1);
  if (!known_unit(suffix)) return std::nullopt;
  return suffix;
}

void DataTable::require_increasing(const std::string& name) const {
  const auto& c = column(name);
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (!std::isfinite(c[k]) || (k > 0 && !(c[k] > c[k - 1]))) {
      throw DataFileError(origin_ + ":" + std::to_string(line_of_row_[k]) + ": column '" + name +
                          "' must be strictly increasing (" + std::to_string(c[k]) +
                          (k > 0 ? " after " + std::to_string(c[k - 1]) : std::string()) + ")");
    }
  }
}

namespace {

// Median increment of a time column with at least 2 rows [its unit].
double median_step(const std::vector<double>& t) {
  std::vector<double> d(t.size() - 1);
  for (std::size_t k = 1; k < t.size(); ++k) d[k - 1] = t[k] - t[k - 1];
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

}  // namespace

double DataTable::sample_period() const {
  const auto& t = column("t");
  if (t.size() < 2)
    throw DataFileError(origin_ + ": need at least 2 rows to know the sample period");
  return median_step(t);
}

compensation::Units Record::units() const {
  compensation::Units units;
  if (u_unit) units.input = *u_unit;
  if (y_unit) units.output = *y_unit;
  return units;
}

namespace {

void check_options(const RecordColumns& columns) {
  std::vector<std::pair<const char*, double>> scales{{"u scale", columns.u_scale},
                                                     {"y scale", columns.y_scale}};
  for (const double v : columns.u_scales) scales.emplace_back("u scale", v);
  for (const double v : columns.y_scales) scales.emplace_back("y scale", v);
  for (const auto& [name, value] : scales) {
    if (!std::isfinite(value) || value == 0.0) {
      throw DataFileError(std::string(name) + " must be a finite, non-zero number");
    }
  }
  for (const auto& [option, unit] :
       {std::pair{"--u-unit", &columns.u_unit}, std::pair{"--y-unit", &columns.y_unit}}) {
    if (*unit && trim(**unit).empty()) {
      throw DataFileError(std::string(option) +
                          ": the unit is empty; name one (e.g. N, mm) or leave the option out");
    }
  }
  if (!std::isfinite(columns.rate_hz) || columns.rate_hz < 0.0) {
    throw DataFileError("the sample rate must be a positive number of Hz (or 0: read t)");
  }
}

// A missing column is named with the columns the file has and the option that picks another.
void require_column(const DataTable& data, const std::string& path, const std::string& name,
                    const char* role, const char* option) {
  if (data.has(name)) return;
  std::string have;
  for (const auto& n : data.names()) have += (have.empty() ? "" : ", ") + n;
  throw DataFileError(path + ": no " + role + " column '" + name + "' (columns: " + have +
                      "); name it with " + option);
}

std::vector<double> scaled_column(const DataTable& data, const std::string& path,
                                  const std::string& name, double scale) {
  std::vector<double> v = data.column(name);
  const auto bad = std::find_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); });
  if (bad != v.end()) {
    const auto k = static_cast<std::size_t>(bad - v.begin());
    throw DataFileError(path + ":" + std::to_string(data.line_of_row(k)) + ": column '" + name +
                        "', data row " + std::to_string(k + 1) + ": " + std::to_string(*bad) +
                        " is not a finite number");
  }
  for (double& x : v) x *= scale;
  return v;
}

// The unit after scaling: the option's, else the header's moved by the scale.
std::optional<std::string> unit_of(const DataTable& data, const std::string& path,
                                   const RecordColumns& columns, const std::string& name,
                                   double scale, const std::optional<std::string>& given,
                                   const char* unit_option, const char* scale_option) {
  if (!columns.read_units) return std::nullopt;
  if (given) return trim(*given);
  const auto header = data.unit(name);
  if (!header) return std::nullopt;
  if (header->empty()) {
    throw DataFileError(path + ": the header of column '" + name +
                        "' names an empty unit; name it with " + unit_option);
  }
  auto scaled = scaled_unit(*header, scale);
  if (!scaled) {
    throw DataFileError(path + ": column '" + name + "' is in " + *header + ", and " +
                        scale_option + " " + compensation::significant(scale, 6) +
                        " turns it into a unit that cannot be named from it; name it with " +
                        unit_option);
  }
  return scaled;
}

void require_time_in_seconds(const DataTable& data, const std::string& path,
                             const RecordColumns& columns) {
  require_column(data, path, columns.t, "time", "--t-column, or give the sample rate with --rate");
  if (const auto unit = data.unit(columns.t); unit && *unit != "s") {
    throw DataFileError(path + ": the header of time column '" + columns.t + "' names the unit '" +
                        *unit +
                        "'; the time column must be in s (or give the sample rate with "
                        "--rate)");
  }
}

std::vector<std::string> comma_list(const std::string& s) {
  std::vector<std::string> out;
  std::size_t from = 0;
  while (true) {
    const std::size_t comma = s.find(',', from);
    out.push_back(
        trim(s.substr(from, comma == std::string::npos ? std::string::npos : comma - from)));
    if (comma == std::string::npos) break;
    from = comma + 1;
  }
  return out;
}

}  // namespace

Record read_record(const std::string& path, const RecordColumns& columns, bool y_required) {
  check_options(columns);
  if (!columns.u_scales.empty() || !columns.y_scales.empty()) {
    throw DataFileError(
        "--u-scale / --y-scale: several values for one input and one output column");
  }
  const DataTable data = DataTable::read_csv(path);
  Record r;
  r.lines.resize(data.rows());
  for (std::size_t k = 0; k < r.lines.size(); ++k) r.lines[k] = data.line_of_row(k);
  if (columns.rate_hz > 0.0) {
    r.t.resize(data.rows());
    for (std::size_t k = 0; k < r.t.size(); ++k) r.t[k] = static_cast<double>(k) / columns.rate_hz;
    r.sample_period_s = 1.0 / columns.rate_hz;
  } else {
    require_time_in_seconds(data, path, columns);
    data.require_increasing(columns.t);
    r.t = data.column(columns.t);
    if (r.t.size() < 2) throw DataFileError(path + ": need at least 2 rows");
    r.sample_period_s = median_step(r.t);
  }
  require_column(data, path, columns.u, columns.u_role.c_str(), columns.u_option.c_str());
  r.u = scaled_column(data, path, columns.u, columns.u_scale);
  r.u_unit = unit_of(data, path, columns, columns.u, columns.u_scale, columns.u_unit, "--u-unit",
                     "--u-scale");
  if (y_required) require_column(data, path, columns.y, "output", "--y-column");
  if (y_required || data.has(columns.y)) {
    r.y = scaled_column(data, path, columns.y, columns.y_scale);
    r.y_unit = unit_of(data, path, columns, columns.y, columns.y_scale, columns.y_unit, "--y-unit",
                       "--y-scale");
  }
  return r;
}

bool names_several(const RecordColumns& columns) {
  return columns.u.find(',') != std::string::npos || columns.y.find(',') != std::string::npos;
}

MultiRecord read_multi_record(const std::string& path, const RecordColumns& columns,
                              bool y_required) {
  check_options(columns);
  const DataTable data = DataTable::read_csv(path);
  MultiRecord r;
  r.rows = data.rows();
  if (r.rows < 2) throw DataFileError(path + ": need at least 2 rows");
  for (const char* layout : {"realization", "period"}) {
    if (!data.has(layout)) continue;
    auto& ids = std::string(layout) == "realization" ? r.realization : r.period;
    ids = scaled_column(data, path, layout, 1.0);
    for (std::size_t k = 0; k < ids.size(); ++k) {
      if (ids[k] < 0.0 || ids[k] != std::floor(ids[k])) {
        throw DataFileError(path + ":" + std::to_string(data.line_of_row(k)) + ": column '" +
                            layout + "' holds " + std::to_string(ids[k]) +
                            ", not a whole number >= 0");
      }
    }
  }
  if (columns.rate_hz > 0.0) {
    r.sample_period_s = 1.0 / columns.rate_hz;
  } else {
    // t increases within each realization (each starts its own clock).
    require_time_in_seconds(data, path, columns);
    const auto& t = data.column(columns.t);
    std::vector<double> steps;
    for (std::size_t k = 1; k < t.size(); ++k) {
      if (!r.realization.empty() && r.realization[k] != r.realization[k - 1]) continue;
      if (!(t[k] > t[k - 1])) {
        throw DataFileError(path + ":" + std::to_string(data.line_of_row(k)) + ": time column '" +
                            columns.t + "' does not increase (" + std::to_string(t[k - 1]) +
                            " then " + std::to_string(t[k]) + ")");
      }
      steps.push_back(t[k] - t[k - 1]);
    }
    if (steps.empty()) throw DataFileError(path + ": need at least 2 rows per realization");
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2),
                     steps.end());
    r.sample_period_s = steps[steps.size() / 2];
  }
  const auto read = [&](const std::string& list, double scale, const std::vector<double>& scales,
                        const std::optional<std::string>& unit, std::vector<std::string>& names,
                        std::vector<std::vector<double>>& values,
                        std::vector<std::optional<std::string>>& units, const char* role,
                        const char* option, const char* unit_option, const char* scale_option) {
    names = comma_list(list);
    if (!scales.empty() && scales.size() != names.size()) {
      throw DataFileError(std::string(scale_option) + ": " + std::to_string(scales.size()) +
                          " scales for " + std::to_string(names.size()) + " " + role +
                          " columns; give one for all, or one per column");
    }
    for (std::size_t c = 0; c < names.size(); ++c) {
      const std::string& name = names[c];
      if (name.empty()) throw DataFileError(std::string(option) + ": an empty column name");
      require_column(data, path, name, role, option);
      const double sc = scales.empty() ? scale : scales[c];
      values.push_back(scaled_column(data, path, name, sc));
      units.push_back(unit_of(data, path, columns, name, sc, unit, unit_option, scale_option));
    }
  };
  read(columns.u, columns.u_scale, columns.u_scales, columns.u_unit, r.u_names, r.u, r.u_units,
       "input", "--u-column", "--u-unit", "--u-scale");
  if (y_required || data.has(comma_list(columns.y).front())) {
    read(columns.y, columns.y_scale, columns.y_scales, columns.y_unit, r.y_names, r.y, r.y_units,
         "output", "--y-column", "--y-unit", "--y-scale");
  }
  return r;
}

compensation::Units common_units(std::span<const Record> records,
                                 std::span<const std::string> paths,
                                 const std::optional<compensation::Units>& given) {
  compensation::Units units = given.value_or(compensation::Units{});
  auto agree = [&](std::optional<std::string> Record::*unit, std::string compensation::Units::*out,
                   const char* what) {
    std::optional<std::string> named;
    std::string by;
    if (given) named = (*given).*out, by = "the model's";
    for (std::size_t i = 0; i < records.size(); ++i) {
      const std::optional<std::string>& u = records[i].*unit;
      if (!u) continue;
      if (!named) {
        named = *u, by = paths[i] + "'s";
      } else if (!same_unit(*u, *named)) {
        throw DataFileError(paths[i] + ": the " + what + " is in " + *u + ", " + by + " in " +
                            *named);
      }
    }
    if (named) units.*out = *named;
  };
  agree(&Record::u_unit, &compensation::Units::input, "input");
  agree(&Record::y_unit, &compensation::Units::output, "output");
  return units;
}

void write_csv(const std::string& path, const std::vector<std::string>& names,
               const std::vector<const std::vector<double>*>& columns,
               const std::vector<std::string>& comments, int significant_digits) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) throw DataFileError(path + ": cannot write (" + std::strerror(errno) + ")");
  for (const auto& c : comments) std::fprintf(f, "# %s\n", c.c_str());
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::fprintf(f, "%s%s", i ? "," : "", names[i].c_str());
  }
  std::fputc('\n', f);
  std::size_t rows = 0;
  for (const auto* c : columns) rows = std::max(rows, c->size());
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t i = 0; i < columns.size(); ++i) {
      const auto& c = *columns[i];
      std::fprintf(f, "%s%.*g", i ? "," : "", significant_digits, r < c.size() ? c[r] : NAN);
    }
    std::fputc('\n', f);
  }
  if (std::fclose(f) != 0) throw DataFileError(path + ": write failed");
}

}  // namespace hystbench::cli
