#include "hystbench/cli/report/plot_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>
#include <stdexcept>

#include "hystbench/cli/offline/data_table.hpp"
#include "report/details/gnuplot.hpp"

namespace hystbench::cli {

namespace fs = std::filesystem;

namespace {

// Points per curve at most: gnuplot draws a 1 M-sample run in seconds this way, and the error
// curve keeps each bin's extremes.
constexpr std::size_t kMaxPoints = 20000;

bool any_finite(const std::vector<double>& c) {
  return std::any_of(c.begin(), c.end(), [](double v) { return std::isfinite(v); });
}

// The column when the log has it with a value somewhere; else nullptr (not drawn).
const std::vector<double>* drawn_column(const DataTable& t, const std::string& name) {
  return t.has(name) && any_finite(t.column(name)) ? &t.column(name) : nullptr;
}

// The log's reference without its open-loop rows: there a run log's yr holds the model's
// output (the header's `open_loop` flag bit says which rows), and no reference was followed.
std::vector<double> followed_reference(const DataTable& t, const std::vector<double>& yr) {
  std::vector<double> out = yr;
  if (!t.has("flags")) return out;
  std::uint32_t bit = 0;
  for (const std::string& c : t.comments()) {
    const auto j = nlohmann::json::parse(c, nullptr, false);
    if (j.is_object() && j.contains("flags") && j["flags"].is_object()) {
      bit = j["flags"].value("open_loop", 0U);
    }
  }
  if (bit == 0) return out;
  const std::vector<double>& flags = t.column("flags");
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (std::isfinite(flags[k]) && (static_cast<std::uint32_t>(flags[k]) & bit) != 0U) {
      out[k] = std::numeric_limits<double>::quiet_NaN();
    }
  }
  return out;
}

void put(std::ostream& o, double v) {
  if (std::isfinite(v)) {
    o << ' ' << v;
  } else {
    o << " NaN";
  }
}

// plot.dat: t u y yr y_model error_min error_max, every bin-th sample (at most kMaxPoints rows);
// the error against yr where the log has a reference, else against y_model.
void write_plot_data(const fs::path& dat, const DataTable& table, const std::vector<double>* yr,
                     const std::vector<double>* ym) {
  const std::vector<double>& t = table.column("t");
  const std::vector<double>& u = table.column("u");
  const std::vector<double>& y = table.column("y");
  const std::size_t n = table.rows();
  std::ofstream d(dat, std::ios::trunc);
  if (!d) throw std::runtime_error(dat.string() + ": cannot write");
  d.precision(9);
  d << "# t u y yr y_model error_min error_max (every " << std::max<std::size_t>(1, n / kMaxPoints)
    << "th sample; the error's min and max over each bin)\n";
  const std::size_t bin = std::max<std::size_t>(1, (n + kMaxPoints - 1) / kMaxPoints);
  for (std::size_t b = 0; b < n; b += bin) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t k = b; k < std::min(n, b + bin); ++k) {
      const double target = yr ? (*yr)[k] : (ym ? (*ym)[k] : NAN);
      const double e = y[k] - target;
      if (std::isfinite(e)) lo = std::min(lo, e), hi = std::max(hi, e);
    }
    d << t[b];
    put(d, u[b]);
    put(d, y[b]);
    put(d, yr ? (*yr)[b] : NAN);
    put(d, ym ? (*ym)[b] : NAN);
    put(d, lo);
    put(d, hi);
    d << '\n';
  }
}

}  // namespace

fs::path default_plot_dir(const std::string& log_path) {
  fs::path p(log_path);
  return p.parent_path() / (p.stem().string() + "-plots");
}

std::vector<fs::path> plot_run_log(const std::string& log_path, const fs::path& dir) {
  const DataTable table = DataTable::read_csv(log_path);
  for (const char* name : {"t", "u", "y"}) {
    if (!table.has(name)) {
      throw std::runtime_error(log_path + ": no '" + name +
                               "' column (a run log or a CSV with t, u, y is needed)");
    }
  }
  const std::vector<double>* logged_yr = drawn_column(table, "yr");
  const std::vector<double> followed =
      logged_yr ? followed_reference(table, *logged_yr) : std::vector<double>();
  const std::vector<double>* yr = logged_yr && any_finite(followed) ? &followed : nullptr;
  const std::vector<double>* ym = drawn_column(table, "y_model");
  if (table.rows() == 0 || !any_finite(table.column("y"))) {
    throw std::runtime_error(log_path + ": no finite sample of y");
  }

  fs::create_directories(dir);
  const fs::path dat = dir / "plot.dat";
  write_plot_data(dat, table, yr, ym);

  const std::string data = details::gnuplot_quoted(dat);
  const std::string name = fs::path(log_path).filename().string();
  std::vector<fs::path> pngs = {dir / "time.png", dir / "error.png", dir / "loop.png"};
  const fs::path script = dir / "plot.gp";
  std::ofstream gp(script, std::ios::trunc);
  if (!gp) throw std::runtime_error(script.string() + ": cannot write");
  gp << "# hystbench plot of " << log_path << ": gnuplot " << details::gnuplot_quoted(script)
     << "\nset terminal pngcairo size 1000,600\nset grid\nset key top left\n"
     << "set datafile missing 'NaN'\n";
  gp << "set output " << details::gnuplot_quoted(pngs[0]) << "\n"
     << "set title '" << name << ": reference, measurement and model'\n"
     << "set xlabel 't [s]'\nset ylabel 'displacement [um]'\n"
     << "plot " << data << " using 1:3 with lines lw 1 lc 1 title 'y (measured)'";
  if (yr) gp << ", " << data << " using 1:4 with lines lw 2 lc 2 title 'yr (reference)'";
  if (ym) gp << ", " << data << " using 1:5 with lines dt 2 lc 3 title 'y\\_model (model)'";
  gp << "\n";
  gp << "set output " << details::gnuplot_quoted(pngs[1]) << "\n"
     << "set title '" << name << ": "
     << (yr ? "tracking error y - yr" : "model error y - y\\_model")
     << " (min and max per bin)'\nset ylabel 'error [um]'\n";
  if (yr || ym) {
    gp << "plot " << data << " using 1:6:7 with filledcurves lc 1 fs transparent solid 0.4 "
       << "title 'error range', " << data << " using 1:7 with lines lc 1 notitle, " << data
       << " using 1:6 with lines lc 1 notitle\n";
  } else {
    gp << "set label 1 'no reference and no model in this log: no error to draw' at graph 0.1,"
       << " graph 0.5\nplot 0 notitle\nunset label 1\n";
  }
  gp << "set output " << details::gnuplot_quoted(pngs[2]) << "\n"
     << "set title '" << name << ": output against input'\n"
     << "set xlabel 'u [V]'\nset ylabel 'y [um]'\n"
     << "plot " << data << " using 2:3 with lines lc 1 title 'measured'";
  if (ym) gp << ", " << data << " using 2:5 with lines dt 2 lw 2 lc 3 title 'model'";
  gp << "\n";
  gp.close();
  details::run_gnuplot(script, dir / "gnuplot.log");
  return pngs;
}

fs::path plot_learning(const nlohmann::json& learning, const std::string& log_path,
                       const fs::path& dir) {
  const nlohmann::json& trials = learning.at("trials");
  if (trials.empty()) throw std::runtime_error("learning.png: the run played no trial");
  const auto period = learning.at("period_samples").get<std::size_t>();
  const DataTable table = DataTable::read_csv(log_path);
  for (const char* name : {"t", "y", "yr"}) {
    if (!table.has(name)) throw std::runtime_error(log_path + ": no '" + name + "' column");
  }
  const std::size_t n = table.rows();
  if (n < period) throw std::runtime_error(log_path + ": shorter than one trial");
  fs::create_directories(dir);
  const fs::path dat = dir / "learning.dat";
  std::ofstream d(dat, std::ios::trunc);
  if (!d) throw std::runtime_error(dat.string() + ": cannot write");
  d.precision(9);
  d << "# trial rms_percent max_percent\n";
  for (const auto& t : trials) {
    d << t.at("trial").get<int>();
    put(d, t.at("rms_error_percent").get<double>());
    put(d, t.at("max_error_percent").get<double>());
    d << '\n';
  }
  // A second block (gnuplot's index 1): the last trial, the log's last period.
  d << "\n\n# t_ms error_um (the last trial: y - yr)\n";
  const std::vector<double>&t = table.column("t"), &y = table.column("y"), &yr = table.column("yr");
  for (std::size_t k = n - period; k < n; ++k) {
    d << 1e3 * (t[k] - t[n - period]);
    put(d, y[k] - yr[k]);
    d << '\n';
  }
  d.close();
  const std::string data = details::gnuplot_quoted(dat);
  fs::path png = dir / "learning.png";
  const fs::path script = dir / "learning.gp";
  std::ofstream gp(script, std::ios::trunc);
  if (!gp) throw std::runtime_error(script.string() + ": cannot write");
  gp << "# hystbench learning plot of " << log_path << ": gnuplot "
     << details::gnuplot_quoted(script) << "\nset terminal pngcairo size 1000,800\n"
     << "set output " << details::gnuplot_quoted(png) << "\nset grid\nset key top right\n"
     << "set datafile missing 'NaN'\nset multiplot layout 2,1\n"
     << "set title 'learning: error per trial (trial 0: the drive it started from)'\n"
     << "set logscale y\nset xlabel 'trial'\nset ylabel 'error [% of range]'\n"
     << "plot " << data << " index 0 using 1:2 with linespoints lw 2 lc 1 title 'rms', " << data
     << " index 0 using 1:3 with linespoints dt 2 lc 2 title 'max'\n"
     << "unset logscale y\nset title 'the last trial: y - yr'\nset xlabel 't [ms]'\n"
     << "set ylabel 'error [um]'\nplot " << data
     << " index 1 using 1:2 with lines lc 1 title 'error'\nunset multiplot\n";
  gp.close();
  details::run_gnuplot(script, dir / "gnuplot-learning.log");
  return png;
}

int run_plot(const PlotCommand& cmd, std::ostream& out, std::ostream& err) {
  try {
    const fs::path dir =
        cmd.out_dir.empty() ? default_plot_dir(cmd.log_path) : fs::path(cmd.out_dir);
    const std::vector<fs::path> pngs = plot_run_log(cmd.log_path, dir);
    if (cmd.json_output) {
      nlohmann::json files = nlohmann::json::array();
      for (const auto& p : pngs) files.push_back(p.string());
      out << nlohmann::json{{"log", cmd.log_path}, {"plots", files}}.dump() << "\n";
    } else {
      for (const auto& p : pngs) out << "wrote     " << p.string() << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    err << "hystbench: error: plot: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace hystbench::cli
