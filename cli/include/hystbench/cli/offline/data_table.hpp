#pragma once
// Columnar numeric data files (CSV): lines starting with '#' are comments, the first other line
// is a header naming the columns, every following line is one row of numbers. Bench run logs
// (sample_log) use the same format, so they can be read back here. A first line without a comma
// makes the file blank-separated (spaces or tabs); a first line of numbers only means the file
// has no header, and its columns are named "1", "2", ... by position (a MATLAB or DAQ .dat).
// A header name may carry its unit: `F [N]` (bracket form; the column is also found as `F`) or
// `x_mm` (suffix form, for a known unit: an SI prefix G, M, k, c, m, u, µ, n, p and m, V, N, A,
// Pa, W, s, rad, T or Hz; or deg, bar).
// Errors carry the file name and line number. Not real-time safe.
#include <map>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"

namespace hystbench::cli {

class DataFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DataTable {
 public:
  /// Reads a CSV file. Throws DataFileError (cannot open, no header, ragged or non-numeric row
  /// with its line number, duplicate column name, no rows).
  static DataTable read_csv(const std::string& path);
  /// Parses CSV text; `origin` names it in messages.
  static DataTable parse_csv(const std::string& text, const std::string& origin = "<text>");

  bool has(const std::string& column) const { return index_.count(column) != 0; }
  /// The named column; throws DataFileError listing the available columns when missing.
  const std::vector<double>& column(const std::string& name) const;
  /// Requires `t` to be strictly increasing (error names the first offending line).
  void require_increasing(const std::string& name) const;
  std::size_t rows() const { return columns_.empty() ? 0 : columns_.front().size(); }
  /// The file's line number of data row `row` (0-based), for messages.
  std::size_t line_of_row(std::size_t row) const { return line_of_row_.at(row); }
  const std::vector<std::string>& names() const { return names_; }
  /// The unit the header names for `column` (as column() finds it): unset when it names none,
  /// empty for an empty bracket `F []`.
  std::optional<std::string> unit(const std::string& column) const;
  const std::string& origin() const { return origin_; }
  /// Comment lines (without the leading '#'), e.g. a run log's JSON header.
  const std::vector<std::string>& comments() const { return comments_; }
  /// Median sample period of column `t` [s]; throws when fewer than 2 rows.
  double sample_period() const;

 private:
  std::string origin_;
  std::vector<std::string> names_;
  std::vector<std::vector<double>> columns_;
  std::map<std::string, std::size_t> index_;
  std::vector<std::size_t> line_of_row_;
  std::vector<std::string> comments_;
};

/// Which columns of a data file hold time, input and output, their scale and their units: a
/// lab's export rarely says t, u, y in s, V and um. The defaults read `t`, `u`, `y` as they are.
struct RecordColumns {
  std::string t = "t", u = "u", y = "y";
  double u_scale = 1.0;  ///< u = column * u_scale (e.g. 1e-3 for mV -> V)
  double y_scale = 1.0;  ///< y = column * y_scale (e.g. 1e6 for m -> um)
  /// Several columns: one scale per column, in their order (empty: u_scale / y_scale for all).
  std::vector<double> u_scales, y_scales;
  double rate_hz = 0.0;  ///< > 0: the file has no usable time column; t = row / rate_hz [s]
  /// Units of u and y after scaling (e.g. "N", "mm"); unset: the column header's (its unit
  /// moved by the scale's power of 1000: m with 1e6 is um), else V and um.
  std::optional<std::string> u_unit, y_unit;
  /// False for a reader that takes the values in units it knows (a reference in the model's
  /// output unit, a drive in V): the record's units stay unset and are not checked.
  bool read_units = true;
  /// What the u column holds and the option that names it, for messages (a reference read
  /// as the input column: "reference", "--yr-column").
  std::string u_role = "input", u_option = "--u-column";
};

/// A record read through RecordColumns: t [s] strictly increasing, u and y finite (y empty when
/// the file has no y column and it was optional).
struct Record {
  std::vector<double> t, u, y;
  double sample_period_s = 0.0;    ///< median of the t increments
  std::vector<std::size_t> lines;  ///< the file's line number of each row, for messages
  /// The units of u and y the options or the header name; unset where neither does.
  std::optional<std::string> u_unit, y_unit;

  /// Those units, V and um where nothing names them.
  compensation::Units units() const;
};

/// Reads path's CSV as a record. Throws DataFileError naming the file, the column and the line
/// (missing column with the columns there are, non-finite value, t not increasing, scale or
/// rate not positive and finite, an empty unit, a time column not in s, a header unit the
/// scale turns into a unit it cannot name).
Record read_record(const std::string& path, const RecordColumns& columns, bool y_required);

/// True where RecordColumns names several input or output columns (comma lists: "u1,u2,u3").
bool names_several(const RecordColumns& columns);

/// A record of several inputs and outputs: the columns that RecordColumns' u and y name as comma
/// lists, each scaled by its entry of u_scales / y_scales or else by u_scale / y_scale, and the
/// record's layout where the file has `realization` and `period` columns (whole numbers; else
/// empty): experiments that each start from rest, and the periods of a periodic excitation within
/// them.
struct MultiRecord {
  std::vector<std::string> u_names, y_names;
  std::vector<std::vector<double>> u, y;  ///< per column, scaled; y empty where optional and absent
  std::vector<std::optional<std::string>> u_units, y_units;  ///< as Record's, per column
  std::vector<double> realization, period;                   ///< per row, or empty
  double sample_period_s = 0.0;  ///< median t step within realizations, or 1 / rate
  std::size_t rows = 0;
};

/// Reads path's CSV as a MultiRecord. Throws DataFileError as read_record does, and for a
/// layout column that holds other than whole numbers >= 0, or t not increasing within a
/// realization.
MultiRecord read_multi_record(const std::string& path, const RecordColumns& columns,
                              bool y_required);

/// The units of records read together (several of one device, or one with a model): each unit
/// a record names must agree with the others' and with `given`'s (a model's; unset: none);
/// V and um where nothing names them. Throws DataFileError naming the path and both units.
compensation::Units common_units(std::span<const Record> records,
                                 std::span<const std::string> paths,
                                 const std::optional<compensation::Units>& given = std::nullopt);

/// Writes columns as CSV with a header row and optional '#' comment lines first.
/// Values use `significant_digits` significant digits (17 reads back every double exactly).
/// Throws DataFileError when the file cannot be written.
void write_csv(const std::string& path, const std::vector<std::string>& names,
               const std::vector<const std::vector<double>*>& columns,
               const std::vector<std::string>& comments = {}, int significant_digits = 10);

}  // namespace hystbench::cli
