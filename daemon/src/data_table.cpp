#include "hystbench/daemon/data_table.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

namespace hystbench::daemon {

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
      const std::string& c = cells[i];
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size() || errno == ERANGE) {
        throw DataFileError(origin + ":" + std::to_string(line_no) + ": column '" + t.names_[i] +
                            "': '" + c + "' is not a number");
      }
      t.columns_[i].push_back(v);
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

Record read_record(const std::string& path, const RecordColumns& columns, bool y_required) {
  for (const auto& [name, value] :
       {std::pair{"u scale", columns.u_scale}, std::pair{"y scale", columns.y_scale}}) {
    if (!std::isfinite(value) || value == 0.0) {
      throw DataFileError(std::string(name) + " must be a finite, non-zero number");
    }
  }
  if (!std::isfinite(columns.rate_hz) || columns.rate_hz < 0.0) {
    throw DataFileError("the sample rate must be a positive number of Hz (or 0: read t)");
  }
  const DataTable data = DataTable::read_csv(path);
  Record r;
  r.lines.resize(data.rows());
  for (std::size_t k = 0; k < r.lines.size(); ++k) r.lines[k] = data.line_of_row(k);
  // A missing column is named with the columns the file has and the option that picks another.
  auto require_column = [&](const std::string& name, const char* role, const char* option) {
    if (data.has(name)) return;
    std::string have;
    for (const auto& n : data.names()) have += (have.empty() ? "" : ", ") + n;
    throw DataFileError(path + ": no " + role + " column '" + name + "' (columns: " + have +
                        "); name it with " + option);
  };
  auto scaled = [&](const std::string& name, double scale) {
    std::vector<double> v = data.column(name);
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (!std::isfinite(v[k])) {
        throw DataFileError(path + ":" + std::to_string(data.line_of_row(k)) + ": column '" + name +
                            "', data row " + std::to_string(k + 1) + ": " + std::to_string(v[k]) +
                            " is not a finite number");
      }
      v[k] *= scale;
    }
    return v;
  };
  if (columns.rate_hz > 0.0) {
    r.t.resize(data.rows());
    for (std::size_t k = 0; k < r.t.size(); ++k) r.t[k] = static_cast<double>(k) / columns.rate_hz;
    r.sample_period_s = 1.0 / columns.rate_hz;
  } else {
    require_column(columns.t, "time", "--t-column, or give the sample rate with --rate");
    data.require_increasing(columns.t);
    r.t = data.column(columns.t);
    if (r.t.size() < 2) throw DataFileError(path + ": need at least 2 rows");
    r.sample_period_s = median_step(r.t);
  }
  require_column(columns.u, "input", "--u-column");
  r.u = scaled(columns.u, columns.u_scale);
  if (y_required) require_column(columns.y, "output", "--y-column");
  if (y_required || data.has(columns.y)) r.y = scaled(columns.y, columns.y_scale);
  return r;
}

void write_csv(const std::string& path, const std::vector<std::string>& names,
               const std::vector<const std::vector<double>*>& columns,
               const std::vector<std::string>& comments) {
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
      std::fprintf(f, "%s%.10g", i ? "," : "", r < c.size() ? c[r] : NAN);
    }
    std::fputc('\n', f);
  }
  if (std::fclose(f) != 0) throw DataFileError(path + ": write failed");
}

}  // namespace hystbench::daemon
