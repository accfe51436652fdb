#include "hystbench/cli/remote/sweep_command.hpp"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <ostream>

#include "hystbench/cli/remote/bench_client.hpp"
#include "hystbench/cli/remote/remote_commands.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "report/details/gnuplot.hpp"

namespace hystbench::cli {

using nlohmann::json;

namespace {

constexpr const char* kLearned = "learned";

using compensation::fixed;

double number_or_nan(const json& r, const char* key) {
  return r.contains(key) && r[key].is_number() ? r[key].get<double>() : std::nan("");
}

// The sweep's columns: each compensator by its name, then "learned" with --learn N.
std::vector<std::string> columns(const SweepCommand& cmd) {
  std::vector<std::string> out = cmd.compensators;
  if (cmd.learn_trials > 0) out.emplace_back(kLearned);
  return out;
}

// The track request of column c at frequency f: a compensator's run over max(periods,
// min_duration_s x f) periods, or a learning run over learn_trials trials.
json track_params(const SweepCommand& cmd, const std::string& c, double f) {
  json p = {
      {"reference", cmd.reference}, {"frequency_hz", f}, {"range_fraction", cmd.range_fraction}};
  if (c == kLearned) {
    p["learn_trials"] = cmd.learn_trials;
  } else {
    p["compensator"] = c;
    p["periods"] = std::max(cmd.periods, std::ceil(cmd.min_duration_s * f));
  }
  return p;
}

// The row of frequency f and compensator c, or null.
const json* find_row(const json& rows, double f, const std::string& c) {
  for (const auto& r : rows) {
    if (r["frequency_hz"].get<double>() == f && r["compensator"] == c) return &r;
  }
  return nullptr;
}

void print_table(const SweepCommand& cmd, const json& rows, std::ostream& out) {
  out << "sweep: " << cmd.reference << " over " << fixed(100 * cmd.range_fraction, 0)
      << " % of range; tracking error rms / max, % of range\n";
  const std::vector<std::string> cols = columns(cmd);
  out << std::setw(12) << "f [Hz]";
  for (const auto& c : cols) {
    out << std::setw(24)
        << (c == kLearned ? "learned (" + std::to_string(cmd.learn_trials) + ")" : c);
  }
  out << "\n";
  for (const double f : cmd.frequencies_hz) {
    out << std::setw(12) << fixed(f, 3);
    for (const auto& c : cols) {
      std::string cell = "-";
      if (const json* r = find_row(rows, f, c)) {
        cell = r->contains("rms_error_percent") ? fixed((*r)["rms_error_percent"], 3) + " / " +
                                                      fixed((*r)["max_error_percent"], 3)
                                                : r->value("end", std::string("?"));
      }
      out << std::setw(24) << cell;
    }
    out << "\n";
  }
}

void write_plot(const SweepCommand& cmd, const json& rows) {
  namespace fs = std::filesystem;
  const fs::path dir = cmd.plot_dir;
  fs::create_directories(dir);
  std::ofstream dat(dir / "sweep.dat", std::ios::trunc);
  if (!dat) throw std::runtime_error((dir / "sweep.dat").string() + ": cannot write");
  const std::vector<std::string> cols = columns(cmd);
  dat << "# frequency_hz";
  for (const auto& c : cols) dat << " rms_percent_" << c << " max_percent_" << c;
  dat << "\n";
  for (const double f : cmd.frequencies_hz) {
    dat << f;
    for (const auto& c : cols) {
      const json* r = find_row(rows, f, c);
      const double rms = r != nullptr ? number_or_nan(*r, "rms_error_percent") : std::nan("");
      const double mx = r != nullptr ? number_or_nan(*r, "max_error_percent") : std::nan("");
      dat << " " << (std::isnan(rms) ? std::string("NaN") : std::to_string(rms)) << " "
          << (std::isnan(mx) ? std::string("NaN") : std::to_string(mx));
    }
    dat << "\n";
  }
  dat.close();
  std::ofstream gp(dir / "sweep.gp", std::ios::trunc);
  gp << "set terminal pngcairo size 900,600\n"
     << "set output " << details::gnuplot_quoted(dir / "sweep.png") << "\n"
     << "set logscale xy\nset grid\nset key top left\n"
     << "set xlabel 'reference frequency [Hz]'\nset ylabel 'tracking error [% of range]'\n"
     << "set title 'hystbench sweep: " << cmd.reference << ", rms (solid) and max (dashed)'\n"
     << "plot ";
  for (std::size_t i = 0; i < cols.size(); ++i) {
    const auto col = 2 + 2 * i;
    gp << (i ? ", " : "") << details::gnuplot_quoted(dir / "sweep.dat") << " using 1:" << col
       << " with linespoints lw 2 lc " << i + 1 << " title '" << cols[i] << " rms', "
       << details::gnuplot_quoted(dir / "sweep.dat") << " using 1:" << col + 1
       << " with linespoints dt 2 lc " << i + 1 << " title '" << cols[i] << " max'";
  }
  gp << "\n";
  gp.close();
  details::run_gnuplot(dir / "sweep.gp", dir / "gnuplot.log");
}

// The finished run's figures in its row: its end, errors and log, and a learning run's trials.
void add_run_figures(json& row, const json& r) {
  for (const char* key :
       {"run_id", "end", "reason", "rms_error_percent", "max_error_percent", "rms_error_um",
        "max_error_um", "range_um", "model_rms_error_percent", "log"}) {
    if (r.contains(key)) row[key] = r[key];
  }
  if (const auto l = r.find("learning"); l != r.end() && l->is_object()) {
    json trials = json::array();
    for (const json& t : (*l)["trials"]) trials.push_back(t["rms_error_percent"]);
    row["learning"] = {{"frequency_hz", (*l)["frequency_hz"]},
                       {"trials_rms_percent", trials},
                       {"stopped", (*l)["stopped"]},
                       {"drive", l->value("drive", json())}};
  }
}

}  // namespace

int run_sweep(const SweepCommand& cmd, std::ostream& out, std::ostream& err) {
  json rows = json::array();
  int status = 0;
  const bool tty = ::isatty(STDERR_FILENO) == 1 && !cmd.json_output;
  const std::vector<std::string> cols = columns(cmd);
  const std::size_t total = cmd.frequencies_hz.size() * cols.size();
  std::size_t done = 0;
  try {
    BenchClient client(cmd.socket_path);
    for (const auto& comp : cols) {
      if (!measure_response_if_missing(client, comp, err)) return 1;
    }
    for (const auto& comp : cols) {
      for (const double f : cmd.frequencies_hz) {
        const json params = track_params(cmd, comp, f);
        const json reply = client.request("track", params);
        json row = {{"frequency_hz", f}, {"compensator", comp}};
        for (const char* key : {"periods", "learn_trials"}) {
          if (params.contains(key)) row[key] = params[key];
        }
        if (!reply.value("ok", false)) {
          const json& e = reply["error"];
          row["end"] = "refused";
          row["error"] = e;
          rows.push_back(row);
          err << "hystbench: sweep: track " << comp << " at " << f
              << " Hz refused: " << e.value("message", "?") << " [" << e.value("code", "?")
              << "]\n";
          status = 1;
          break;
        }
        const std::string label = comp + " " + fixed(f, 3) + " Hz (" + std::to_string(done + 1) +
                                  "/" + std::to_string(total) + ")";
        std::function<void(double, const std::string&)> show;
        if (tty) {
          // A stage before the run (the planned feedforward) names itself and holds the bar.
          show = [&](double frac, const std::string& stage) {
            const double run_part = stage.empty() ? frac : 0.0;
            progress_bar(err, (static_cast<double>(done) + run_part) / static_cast<double>(total),
                         "sweep " + label + (stage.empty() ? "" : ": " + stage));
          };
        }
        const json r = wait_for_run(client, reply["result"].value("run_id", ""), show);
        ++done;
        add_run_figures(row, r);
        rows.push_back(row);
        if (r.value("end", "") != "completed") {
          err << (tty ? "\r\x1b[K" : "") << "hystbench: sweep: " << label << " ended "
              << r.value("end", "?") << " (" << r.value("reason", "") << "); sweep stopped\n";
          status = 1;
          break;
        }
      }
      if (status != 0) break;
    }
    if (tty) err << "\r\x1b[K" << std::flush;
  } catch (const ClientError& e) {
    err << "hystbench: " << e.what() << "\n";
    return 2;
  }
  if (cmd.json_output) {
    out << json{{"reference", cmd.reference},           {"range_fraction", cmd.range_fraction},
                {"frequencies_hz", cmd.frequencies_hz}, {"compensators", cmd.compensators},
                {"learn_trials", cmd.learn_trials},     {"rows", rows}}
               .dump()
        << "\n";
  } else {
    print_table(cmd, rows, out);
  }
  if (!cmd.plot_dir.empty()) {
    try {
      write_plot(cmd, rows);
      if (!cmd.json_output)
        out << "plot: " << (std::filesystem::path(cmd.plot_dir) / "sweep.png").string() << "\n";
    } catch (const std::exception& e) {
      err << "hystbench: sweep: " << e.what() << "\n";
      return 2;
    }
  }
  return status;
}

}  // namespace hystbench::cli
