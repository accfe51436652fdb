// diagnose of a record of several inputs (run_diagnose_mimo, offline/details/mimo_commands.hpp):
// cross-coupling per output, in words, as JSON and as a report folder plotted by gnuplot.
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/amplitude_dependence.hpp"
#include "hystbench/compensation/mimo_diagnosis.hpp"
#include "offline/details/mimo_commands.hpp"
#include "offline/details/progress_line.hpp"
#include "report/details/gnuplot.hpp"

namespace hystbench::cli::details {

namespace hc = compensation;
using nlohmann::json;
using cd = std::complex<double>;

namespace {

// frf.dat: per excited bin, the frequency-response matrix measured (least squares over the
// realizations, where there are as many as inputs; else nan) and modelled (every input).
void write_frequency_responses(std::ostream& f, const hc::PeriodicSpectra& s,
                               const hc::CouplingDiagnosis& d) {
  const std::size_t m = s.inputs(), p = s.outputs(), nr = s.u.size();
  const bool measured = nr >= m;
  const double df = 1.0 / (static_cast<double>(s.period) * s.dt);
  f << "# f_Hz, then per output i and input j: measured |G_ij| (nan: fewer realizations than "
       "inputs), model |G_ij|\n";
  for (std::size_t k = 0; k < s.bins.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    Eigen::MatrixXcd gm = Eigen::MatrixXcd::Constant(static_cast<Eigen::Index>(p),
                                                     static_cast<Eigen::Index>(m), std::nan(""));
    if (measured) {
      Eigen::MatrixXcd u(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(nr)),
          y(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(nr));
      for (std::size_t r = 0; r < nr; ++r) {
        u.col(static_cast<Eigen::Index>(r)) = s.u[r].col(kk);
        y.col(static_cast<Eigen::Index>(r)) = s.y[r].col(kk);
      }
      gm = (u * u.adjoint()).ldlt().solve(u * y.adjoint()).adjoint();
    }
    const Eigen::MatrixXcd g = d.extended.response(s.z(k));
    f << static_cast<double>(s.bins[k]) * df;
    for (std::size_t i = 0; i < p; ++i) {
      for (std::size_t j = 0; j < m; ++j) {
        const auto ii = static_cast<Eigen::Index>(i), jj = static_cast<Eigen::Index>(j);
        f << " " << std::abs(gm(ii, jj)) << " " << std::abs(g(ii, jj));
      }
    }
    f << "\n";
  }
}

// residual.dat: per excited bin, each output's residual amplitude from its own input alone and
// from every input.
void write_residual_spectra(std::ostream& f, const hc::PeriodicSpectra& s,
                            const hc::CouplingDiagnosis& d) {
  const std::size_t p = s.outputs(), nr = s.u.size();
  const double df = 1.0 / (static_cast<double>(s.period) * s.dt);
  // Amplitude of a bin's sinusoid from the unnormalised DFT of one period: 2 |X| / N.
  const double amplitude = 2.0 / static_cast<double>(s.period);
  f << "# f_Hz, then per output: residual amplitude from its own input alone, from every "
       "input (rms over the realizations, output unit)\n";
  for (std::size_t k = 0; k < s.bins.size(); ++k) {
    const auto kk = static_cast<Eigen::Index>(k);
    const Eigen::MatrixXcd g = d.extended.response(s.z(k));
    f << static_cast<double>(s.bins[k]) * df;
    for (std::size_t i = 0; i < p; ++i) {
      const auto& c = d.outputs[i];
      const cd gb = c.baseline.response(s.z(k))(0, 0);
      double before = 0.0, after = 0.0;
      for (std::size_t r = 0; r < nr; ++r) {
        const cd y = s.y[r](static_cast<Eigen::Index>(i), kk);
        before += std::norm(y - gb * s.u[r](static_cast<Eigen::Index>(c.own_input), kk));
        after += std::norm(y - (g.row(static_cast<Eigen::Index>(i)) * s.u[r].col(kk))(0, 0));
      }
      f << " " << amplitude * std::sqrt(before / static_cast<double>(nr)) << " "
        << amplitude * std::sqrt(after / static_cast<double>(nr));
    }
    f << "\n";
  }
}

// report.gp: the frequency-response matrix, a panel per output and input, and each output's
// residual spectrum.
void write_coupling_script(std::ostream& gp, const std::filesystem::path& dir,
                           const hc::PeriodicSpectra& s, const hc::CouplingDiagnosis& d,
                           const MultiRecord& data) {
  const std::size_t m = s.inputs(), p = s.outputs();
  const std::string unit = data.y_units.front().value_or("um");
  gp << "# hystbench diagnose report (several inputs): gnuplot "
     << details::gnuplot_quoted(dir / "report.gp") << "\n"
     << "set terminal pngcairo size 1200,900 font ',9' noenhanced\nset grid\n"
     << "set logscale xy\nset format y '%g'\n"
     << "set output " << details::gnuplot_quoted(dir / "frf.png") << "\n"
     << "set multiplot layout " << p << "," << m << " title 'frequency response |G| [" << unit
     << "/input unit]: measured per bin (points), the model of every input (line)'\n";
  for (std::size_t i = 0; i < p; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t col = 2 + 2 * (i * m + j);
      gp << "set title '" << data.y_names[i] << " from " << data.u_names[j] << "'\n"
         << "plot " << details::gnuplot_quoted(dir / "frf.dat") << " using 1:" << col
         << " with points pt 7 ps 0.2 notitle, '' using 1:" << col + 1
         << " with lines lw 1.5 notitle\n";
    }
  }
  gp << "unset multiplot\n"
     << "set output " << details::gnuplot_quoted(dir / "residual_spectrum.png") << "\n"
     << "set multiplot layout " << p << ",1 title 'residual amplitude per bin [" << unit
     << "]: from the own input alone, from every input'\n";
  for (std::size_t i = 0; i < p; ++i) {
    gp << "set title '" << data.y_names[i] << "'\nset key top right\n"
       << "plot " << details::gnuplot_quoted(dir / "residual.dat") << " using 1:" << 2 + 2 * i
       << " with lines title 'own input (" << data.u_names[d.outputs[i].own_input]
       << ")', '' using 1:" << 3 + 2 * i << " with lines title 'every input'\n";
  }
  gp << "unset multiplot\n";
}

// The report folder of a coupling diagnosis: the text and JSON, the frequency-response matrix
// measured (per bin, least squares over the realizations, where there are as many as inputs)
// and modelled (every input), and each output's residual spectrum from its own input alone and
// from every input, plotted by gnuplot.
void write_coupling_report(const std::string& dir_name, const hc::PeriodicSpectra& s,
                           const hc::CouplingDiagnosis& d, const MultiRecord& data,
                           const std::string& text, const json& result) {
  const std::filesystem::path dir(dir_name);
  std::filesystem::create_directories(dir);
  const auto open = [&](const char* name) {
    std::ofstream f(dir / name);
    if (!f) throw std::runtime_error((dir / name).string() + ": cannot write");
    f.precision(8);
    return f;
  };
  open("report.txt") << text;
  open("diagnosis.json") << result.dump(2) << "\n";
  {
    auto f = open("frf.dat");
    write_frequency_responses(f, s, d);
  }
  {
    auto f = open("residual.dat");
    write_residual_spectra(f, s, d);
  }
  auto gp = open("report.gp");
  write_coupling_script(gp, dir, s, d, data);
  gp.close();
  details::run_gnuplot(dir / "report.gp", dir / "gnuplot.log");
}

// An output's cross-coupling diagnosis: each input's share of its power, the inputs named, the
// held-out errors from its own input and from every input.
json output_coupling_json(const hc::OutputCoupling& c, const MultiRecord& data) {
  json shares = json::object(), named = json::array();
  for (std::size_t j = 0; j < data.u.size(); ++j) shares[data.u_names[j]] = c.shares[j];
  for (const auto j : c.named_inputs) named.push_back(data.u_names[j]);
  return {{"output", data.y_names[c.output]},
          {"own_input", data.u_names[c.own_input]},
          {"cause", c.named ? "cross_coupling" : "none"},
          {"cross_coupling",
           {{"named", c.named},
            {"inputs", named},
            {"shares", shares},
            {"gain", c.gain},
            {"baseline_heldout_rms", c.baseline_heldout_rms},
            {"baseline_order", c.baseline_order},
            {"extended_heldout_rms", c.extended_heldout_rms},
            {"left_out_gains", c.left_out_gains},
            {"naming_gain", hc::kCouplingNamingGain}}}};
}

// Saves the model of every input (--save-extended): the diagnosis's linear block, no operators.
void save_every_input_model(const std::string& file_path, const hc::CouplingDiagnosis& d,
                            const MultiRecord& data, const hc::PeriodicRecord& rec,
                            const std::string& path) {
  hc::MimoModelFile file;
  file.model = hc::HammersteinMimoModel(
      std::vector<std::optional<hc::ActuatorModel>>(data.u.size()), d.extended, rec.dt);
  file.sample_period_s = rec.dt;
  file.inputs = channels(data.u_names, data.u_units, "V");
  file.outputs = channels(data.y_names, data.y_units, "um");
  file.identification = {
      {"data_file", path}, {"from", "diagnose: every input"}, {"order", d.extended_order}};
  common::save_mimo_model_file(file_path, file);
}

// The diagnosis as text: the record, then per output its errors from its own input and from
// every input, each input's share of its power and the cause named.
void print_coupling_diagnosis(std::ostream& text, const std::string& path,
                              const hc::PeriodicRecord& rec, const hc::PeriodicSpectra& spectra,
                              const hc::CouplingDiagnosis& d, const MultiRecord& data,
                              const std::string& unit) {
  const std::size_t m = data.u.size();
  text << "record    " << path << ": " << rec.u.size() << " realization(s) x " << rec.periods
       << " period(s) of " << rec.period << " samples; " << spectra.bins.size()
       << " excited bins; held out: " << d.heldout << "\n"
       << std::fixed;
  for (const auto& c : d.outputs) {
    const std::string& y = data.y_names[c.output];
    text << std::setprecision(4) << y << ": from " << data.u_names[c.own_input] << " alone "
         << c.baseline_heldout_rms << " " << unit << " held-out rms (order " << c.baseline_order
         << "); from every input " << c.extended_heldout_rms << " (order " << d.extended_order
         << "): " << std::setprecision(2) << c.gain << "x";
    if (!c.left_out_gains.empty()) {
      text << "; each realization left out:";
      for (const double g : c.left_out_gains) text << " " << g << "x";
    }
    text << "\n  power per input:";
    text << std::setprecision(1);
    for (std::size_t j = 0; j < m; ++j)
      text << " " << data.u_names[j] << " " << 100.0 * c.shares[j] << " %";
    text << "\n  cause: ";
    if (c.named) {
      text << "cross_coupling from";
      for (const auto j : c.named_inputs) text << " " << data.u_names[j];
    } else {
      text << "none named (cross-coupling needs " << std::setprecision(1) << hc::kCouplingNamingGain
           << "x on the held-out part and on every realization left out, from an input carrying "
           << 100.0 * hc::kCouplingNamedShare << " % of the power)";
    }
    text << "\n";
  }
}

}  // namespace

int run_diagnose_mimo(const DiagnoseCommand& cmd, std::ostream& out, std::ostream& err) {
  const bool alone =
      cmd.validate_paths.empty() && cmd.model_path.empty() && cmd.save_baseline.empty();
  if (cmd.data_paths.size() > 1 && alone) {
    return run_diagnose_amplitude(cmd, amplitude_records(cmd.data_paths, cmd.columns), out, err);
  }
  if (cmd.data_paths.size() != 1 || !alone) {
    throw std::invalid_argument(
        "a record of several columns is diagnosed alone (its realizations are the held-out "
        "checks), or with records of the same device at other amplitudes (each left out in "
        "turn), without --validate, --model or --save-baseline");
  }
  const std::string& path = cmd.data_paths.front();
  const MultiRecord data = read_multi_record(path, cmd.columns, true);
  const std::size_t m = data.u.size(), p = data.y.size();
  if (m < 2) {
    throw std::invalid_argument("--u-column names one input: cross-coupling needs several");
  }
  if (p != 1 && p != m) {
    throw std::invalid_argument(
        "--y-column names " + std::to_string(p) + " outputs for " + std::to_string(m) +
        " inputs: give one output (its own input the first), or one per input in their order");
  }
  std::vector<std::size_t> own(p);
  for (std::size_t i = 0; i < p; ++i) own[i] = p == 1 ? 0 : i;
  const hc::PeriodicRecord rec = periodic_record(data, path);
  const auto groups = hc::amplitude_groups(rec);
  if (groups.size() > 1) {
    return run_diagnose_amplitude(cmd, amplitude_records(path, data, rec, groups), out, err);
  }
  const hc::PeriodicSpectra spectra = hc::periodic_spectra(rec);
  std::function<void(double, const std::string&)> progress;
  if (!cmd.json_output)
    progress = [&err](double f, const std::string& w) { details::progress_line(err, f, w); };
  const hc::CouplingDiagnosis d = hc::diagnose_cross_coupling(spectra, own, progress);
  if (!cmd.json_output) err << "\n";
  const std::string unit = data.y_units.front().value_or("um");
  json outputs = json::array();
  bool any = false;
  for (const auto& c : d.outputs) {
    any = any || c.named;
    outputs.push_back(output_coupling_json(c, data));
  }
  const json result = {{"cause", any ? "cross_coupling" : "none"},
                       {"data", path},
                       {"heldout", d.heldout},
                       {"extended_order", d.extended_order},
                       {"unit", unit},
                       {"realizations", rec.u.size()},
                       {"periods", rec.periods},
                       {"excited_bins", spectra.bins.size()},
                       {"outputs", outputs}};
  if (!cmd.save_extended.empty()) save_every_input_model(cmd.save_extended, d, data, rec, path);
  std::ostringstream text;
  print_coupling_diagnosis(text, path, rec, spectra, d, data, unit);
  if (!cmd.save_extended.empty()) text << "saved     " << cmd.save_extended << " (every input)\n";
  if (!cmd.report_dir.empty()) {
    write_coupling_report(cmd.report_dir, spectra, d, data, text.str(), result);
    text << "report    " << cmd.report_dir
         << " (report.txt, diagnosis.json, frf.png, residual_spectrum.png)\n";
  }
  return print_result(out, cmd.json_output, result, text.str());
}

}  // namespace hystbench::cli::details
