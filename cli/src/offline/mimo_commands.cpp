#include "offline/details/mimo_commands.hpp"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/amplitude_dependence.hpp"
#include "hystbench/compensation/mimo_diagnosis.hpp"
#include "offline/details/progress_line.hpp"
#include "report/details/gnuplot.hpp"

namespace hystbench::cli::details {

namespace hc = compensation;
using nlohmann::json;
using cd = std::complex<double>;

namespace {

// Contiguous runs of equal values: their starts, and the end as the last entry.
std::vector<std::size_t> runs(const std::vector<double>& ids, std::size_t from, std::size_t to) {
  std::vector<std::size_t> starts{from};
  for (std::size_t k = from + 1; k < to; ++k) {
    if (ids[k] != ids[k - 1]) starts.push_back(k);
  }
  starts.push_back(to);
  return starts;
}

std::vector<double> to_vector(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

}  // namespace

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::vector<hc::MimoChannel> channels(const std::vector<std::string>& names,
                                      const std::vector<std::optional<std::string>>& units,
                                      const char* fallback) {
  std::vector<hc::MimoChannel> out;
  for (std::size_t i = 0; i < names.size(); ++i)
    out.push_back({names[i], units[i].value_or(fallback)});
  return out;
}

hc::PeriodicRecord periodic_record(const MultiRecord& data, const std::string& path) {
  const std::size_t rows = data.rows;
  const std::vector<double> none(rows, 0.0);
  const auto& realization = data.realization.empty() ? none : data.realization;
  const auto& period = data.period.empty() ? none : data.period;
  hc::PeriodicRecord rec;
  rec.dt = data.sample_period_s;
  const std::vector<std::size_t> r_runs = runs(realization, 0, rows);
  for (std::size_t r = 0; r + 1 < r_runs.size(); ++r) {
    const std::size_t from = r_runs[r], to = r_runs[r + 1];
    for (std::size_t q = 0; q < r; ++q) {
      if (realization[r_runs[q]] == realization[from]) {
        throw DataFileError(path + ": data row " + std::to_string(from + 1) + ": realization " +
                            std::to_string(static_cast<long>(realization[from])) +
                            " starts again after another; a realization's rows must be together");
      }
    }
    const std::vector<std::size_t> p_runs = runs(period, from, to);
    const std::size_t periods = p_runs.size() - 1, n = p_runs[1] - p_runs[0];
    for (std::size_t q = 0; q < periods; ++q) {
      if (p_runs[q + 1] - p_runs[q] != n) {
        throw DataFileError(path + ": data row " + std::to_string(p_runs[q] + 1) +
                            ": a period of " + std::to_string(p_runs[q + 1] - p_runs[q]) +
                            " rows where the first has " + std::to_string(n) +
                            "; every period needs the same length");
      }
    }
    if (r == 0) {
      rec.period = n;
      rec.periods = periods;
    } else if (n != rec.period || periods != rec.periods) {
      throw DataFileError(path + ": realization " +
                          std::to_string(static_cast<long>(realization[from])) + " has " +
                          std::to_string(periods) + " periods of " + std::to_string(n) +
                          " rows, the first " + std::to_string(rec.periods) + " of " +
                          std::to_string(rec.period) + "; realizations need the same layout");
    }
    const auto block = [&](const std::vector<std::vector<double>>& cols) {
      Eigen::MatrixXd m(static_cast<Eigen::Index>(cols.size()),
                        static_cast<Eigen::Index>(to - from));
      for (std::size_t c = 0; c < cols.size(); ++c) {
        for (std::size_t k = from; k < to; ++k) {
          m(static_cast<Eigen::Index>(c), static_cast<Eigen::Index>(k - from)) = cols[c][k];
        }
      }
      return m;
    };
    rec.u.push_back(block(data.u));
    rec.y.push_back(block(data.y));
  }
  return rec;
}

hc::PeriodicRecord dynamic_record(const MultiRecord& data, const std::string& path) {
  hc::PeriodicRecord rec = periodic_record(data, path);
  if (rec.period < 16) {
    throw DataFileError(path + ": periods of " + std::to_string(rec.period) +
                        " samples: a dynamic fit needs at least 16 per period");
  }
  return rec;
}

namespace {

// The noise on the averaged period, from the differences between periods (Parseval).
struct PeriodNoise {
  Eigen::VectorXd rms;  ///< per output [output unit]
  bool known = false;   ///< two periods or more
  std::string from;     ///< how it was measured
};

PeriodNoise period_noise(const hc::PeriodicRecord& rec, const hc::PeriodicSpectra& spectra) {
  const double n2 = static_cast<double>(rec.period) * static_cast<double>(rec.period);
  PeriodNoise noise;
  noise.rms = (spectra.noise_var.rowwise().sum() * 2.0 / n2).cwiseSqrt();
  noise.known = rec.periods >= 2;
  noise.from =
      !noise.known ? "unknown: one period"
      : spectra.periods_used >= 2
          ? "the differences between the periods after the first"
          : "the differences between both periods, the first's transient included: an upper "
            "bound";
  return noise;
}

// What fit found on a record of several columns: the model file's identification and the
// --json result's figures.
json mimo_fit_json(const hc::HammersteinFitResult& r, const hc::PeriodicRecord& rec,
                   const hc::PeriodicSpectra& spectra, const Eigen::MatrixXd& shares,
                   const PeriodNoise& noise, double seconds) {
  json orders = json::array();
  for (const auto& s : r.linear.scores) {
    orders.push_back({{"order", s.order}, {"heldout_rms", s.heldout_rms}});
  }
  json coupling = json::array();
  for (Eigen::Index i = 0; i < shares.rows(); ++i) coupling.push_back(to_vector(shares.row(i)));
  return {{"method", "frequency-domain Sanathanan-Koerner, poles shared; residues least squares"},
          {"order", r.linear.order},
          {"orders", orders},
          {"heldout", r.heldout},
          {"heldout_rms", {{"linear", r.heldout_linear}, {"hammerstein", r.heldout_hammerstein}}},
          {"hysteresis_kept", r.hysteresis_kept},
          {"fit_rms", to_vector(r.fit_rms)},
          {"noise_rms", noise.known ? json(to_vector(noise.rms)) : json(nullptr)},
          {"noise_from", noise.from},
          {"coupling", coupling},
          {"realizations", rec.u.size()},
          {"periods", rec.periods},
          {"period_samples", rec.period},
          {"transient_periods", spectra.transient_periods},
          {"excited_bins", spectra.bins.size()},
          {"fit_s", seconds}};
}

// The fit's and the noise's rms per output (the stream's precision and format apply).
void print_output_errors(std::ostream& out, const MultiRecord& data,
                         const hc::HammersteinFitResult& r, const PeriodNoise& noise,
                         const std::string& y_unit) {
  out << "fit       rms";
  for (Eigen::Index i = 0; i < r.fit_rms.size(); ++i) {
    out << " " << data.y_names[static_cast<std::size_t>(i)] << " " << r.fit_rms(i) << " " << y_unit
        << ";";
  }
  out << "\n";
  if (noise.known) {
    out << "noise     rms";
    for (Eigen::Index i = 0; i < noise.rms.size(); ++i) {
      out << " " << data.y_names[static_cast<std::size_t>(i)] << " " << noise.rms(i) << " "
          << y_unit << ";";
    }
    out << " from " << noise.from << "\n";
  }
}

// Each output's power by input [%] (the stream's precision and format apply).
void print_coupling_shares(std::ostream& out, const MultiRecord& data,
                           const Eigen::MatrixXd& shares) {
  for (Eigen::Index i = 0; i < shares.rows(); ++i) {
    out << "coupling  " << data.y_names[static_cast<std::size_t>(i)] << ":";
    for (Eigen::Index j = 0; j < shares.cols(); ++j) {
      out << " " << data.u_names[static_cast<std::size_t>(j)] << " " << 100.0 * shares(i, j)
          << " %";
    }
    out << " of its power\n";
  }
}

}  // namespace

int run_fit_mimo(const FitCommand& cmd, std::ostream& out, std::ostream& err) {
  if (!cmd.more_data_paths.empty()) {
    std::vector<std::string> paths{cmd.data_path};
    paths.insert(paths.end(), cmd.more_data_paths.begin(), cmd.more_data_paths.end());
    return run_fit_scheduled(cmd, amplitude_records(paths, cmd.columns), out, err);
  }
  const auto started = std::chrono::steady_clock::now();
  const MultiRecord data = read_multi_record(cmd.data_path, cmd.columns, true);
  const hc::PeriodicRecord rec = dynamic_record(data, cmd.data_path);
  const auto groups = hc::amplitude_groups(rec);
  if (groups.size() > 1) {
    return run_fit_scheduled(cmd, amplitude_records(cmd.data_path, data, rec, groups), out, err);
  }
  hc::HammersteinFitOptions options;
  if (cmd.operators > 0) options.operators = static_cast<std::size_t>(cmd.operators);
  if (!cmd.json_output) {
    options.linear.progress = [&err](double f, const std::string& what) {
      details::progress_line(err, f, what);
    };
  }
  const hc::HammersteinFitResult r = hc::identify_mimo_hammerstein(rec, options);
  const Eigen::MatrixXd shares = hc::coupling_shares(r.model, rec);
  if (!cmd.json_output) err << "\n";
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const hc::PeriodicSpectra spectra = hc::periodic_spectra(rec);
  const PeriodNoise noise = period_noise(rec, spectra);
  const json fitted = mimo_fit_json(r, rec, spectra, shares, noise, seconds);
  hc::MimoModelFile file;
  file.model = r.model;
  file.sample_period_s = rec.dt;
  file.inputs = channels(data.u_names, data.u_units, "V");
  file.outputs = channels(data.y_names, data.y_units, "um");
  file.identification = fitted;
  file.identification.update({{"data_file", cmd.data_path}, {"samples", data.rows}});
  common::save_mimo_model_file(cmd.output_path, file);
  const std::string y_unit = file.outputs.front().unit;
  if (cmd.json_output) {
    json result = fitted;
    result.update({{"model", cmd.output_path},
                   {"type", hc::kMimoModelType},
                   {"inputs", data.u_names},
                   {"outputs", data.y_names}});
    out << result.dump() << "\n";
    return 0;
  }
  out << "model     " << hc::kMimoModelType << ": " << data.u_names.size() << " input(s) ("
      << joined(data.u_names) << ") -> " << data.y_names.size() << " output(s) ("
      << joined(data.y_names) << "), linear dynamics of order " << r.linear.order << "\n";
  out << "record    " << rec.u.size() << " realization(s) x " << rec.periods << " period(s) of "
      << rec.period << " samples at " << std::setprecision(6) << 1.0 / rec.dt << " Hz; "
      << (spectra.transient_periods > 0 ? "the first period of each dropped (transient); " : "")
      << spectra.bins.size() << " excited bins\n";
  out << "order     held-out rms [" << y_unit << "] on " << r.heldout << ":";
  out << std::fixed << std::setprecision(4);
  for (const auto& s : r.linear.scores) {
    out << " " << s.order << ": " << s.heldout_rms << (s.order == r.linear.order ? " (chosen)" : "")
        << ";";
  }
  out << "\n";
  out << "operators one play model per input: held-out " << r.heldout_hammerstein << " " << y_unit
      << " against " << r.heldout_linear
      << " without: " << (r.hysteresis_kept ? "kept" : "left out (not 2 % better)") << "\n";
  print_output_errors(out, data, r, noise, y_unit);
  out << std::setprecision(1);
  print_coupling_shares(out, data, shares);
  out << "saved     " << cmd.output_path << " (" << std::setprecision(1) << seconds << " s)\n";
  return 0;
}

namespace {

// The record against the model: as many input and output columns, in its units, at its rate.
void check_against_model(const SimulateCommand& cmd, const hc::MimoModelFile& file,
                         const MultiRecord& data) {
  if (data.u.size() != file.inputs.size() ||
      (!data.y.empty() && data.y.size() != file.outputs.size())) {
    throw DataFileError(cmd.data_path + ": " + std::to_string(data.u.size()) + " input and " +
                        std::to_string(data.y.size()) + " output columns for a model of " +
                        std::to_string(file.inputs.size()) + " and " +
                        std::to_string(file.outputs.size()));
  }
  const auto check_units = [&](const std::vector<std::optional<std::string>>& units,
                               const std::vector<hc::MimoChannel>& model, const char* option) {
    for (std::size_t i = 0; i < units.size(); ++i) {
      if (units[i] && *units[i] != model[i].unit) {
        throw DataFileError(cmd.data_path + ": column " + std::to_string(i + 1) + " is in " +
                            *units[i] + ", the model's " + model[i].name + " in " + model[i].unit +
                            "; scale it with " + option);
      }
    }
  };
  check_units(data.u_units, file.inputs, "--u-scale");
  check_units(data.y_units, file.outputs, "--y-scale");
  if (std::abs(data.sample_period_s - file.sample_period_s) > 1e-6 * file.sample_period_s) {
    std::ostringstream msg;
    msg << cmd.data_path << ": sampled at " << 1.0 / data.sample_period_s
        << " Hz; the model's dynamics hold at " << 1.0 / file.sample_period_s << " Hz only";
    throw DataFileError(msg.str());
  }
}

// The model's outputs over the record, and with measured outputs their errors after the first
// `skip` samples of each realization.
struct MimoSimulation {
  std::vector<std::vector<double>> y_model;  ///< per output, a value per row
  std::size_t scored = 0;                    ///< samples scored per output
  Eigen::VectorXd sum2, max_abs;             ///< per output: squared errors' sum, largest error
};

// Each realization from rest: an experiment of its own.
MimoSimulation simulate_realizations(const hc::MimoModelFile& file, const hc::PeriodicRecord& rec,
                                     const MultiRecord& data, std::size_t skip) {
  const std::size_t p = file.outputs.size();
  MimoSimulation sim;
  sim.y_model.assign(p, std::vector<double>(data.rows));
  std::size_t row = 0;
  sim.sum2 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(p));
  sim.max_abs = sim.sum2;
  for (const auto& u : rec.u) {
    const Eigen::MatrixXd y = file.simulate(u);
    for (Eigen::Index t = 0; t < y.cols(); ++t, ++row) {
      for (std::size_t i = 0; i < p; ++i) {
        sim.y_model[i][row] = y(static_cast<Eigen::Index>(i), t);
        if (data.y.empty() || static_cast<std::size_t>(t) < skip) continue;
        const double e = data.y[i][row] - sim.y_model[i][row];
        sim.sum2(static_cast<Eigen::Index>(i)) += e * e;
        sim.max_abs(static_cast<Eigen::Index>(i)) =
            std::max(sim.max_abs(static_cast<Eigen::Index>(i)), std::abs(e));
      }
      if (!data.y.empty() && static_cast<std::size_t>(t) >= skip) ++sim.scored;
    }
  }
  return sim;
}

// What a schedule saw: the drive's amplitude estimate, each realization from its start.
std::vector<double> schedule_amplitudes(const hc::AmplitudeScheduledMimoModel& model,
                                        const hc::PeriodicRecord& rec) {
  std::vector<double> out;
  for (const auto& u : rec.u) {
    const Eigen::VectorXd a = hc::amplitude_estimate(u, model.window_samples());
    out.insert(out.end(), a.data(), a.data() + a.size());
  }
  return out;
}

}  // namespace

int run_simulate_mimo(const SimulateCommand& cmd, const hc::MimoModelFile& file, std::ostream& out,
                      std::ostream& /*err*/) {
  RecordColumns columns = cmd.columns;
  // Unnamed columns: the model's own.
  std::vector<std::string> u_names, y_names;
  for (const auto& c : file.inputs) u_names.push_back(c.name);
  for (const auto& c : file.outputs) y_names.push_back(c.name);
  if (columns.u == RecordColumns{}.u) columns.u = joined(u_names);
  if (columns.y == RecordColumns{}.y) columns.y = joined(y_names);
  const MultiRecord data = read_multi_record(cmd.data_path, columns, false);
  check_against_model(cmd, file, data);
  const double skip_s = cmd.skip_s.value_or(0.0);
  if (!(skip_s >= 0.0)) throw std::invalid_argument("--skip: seconds >= 0");
  const auto skip = static_cast<std::size_t>(std::llround(skip_s / file.sample_period_s));
  MultiRecord layout_only = data;
  if (layout_only.y.empty()) layout_only.y = layout_only.u;  // the layout needs some output
  const hc::PeriodicRecord rec = periodic_record(layout_only, cmd.data_path);
  const std::size_t p = file.outputs.size();
  const MimoSimulation sim = simulate_realizations(file, rec, data, skip);
  std::vector<std::string> names{"t"};
  std::vector<std::vector<double>> owned;
  owned.reserve(3 * p + 2);
  owned.emplace_back(data.rows);
  for (std::size_t k = 0; k < data.rows; ++k)
    owned[0][k] = static_cast<double>(k % (rec.period * rec.periods)) * data.sample_period_s;
  std::vector<const std::vector<double>*> cols{&owned[0]};
  if (!data.realization.empty()) names.push_back("realization"), cols.push_back(&data.realization);
  for (std::size_t j = 0; j < data.u.size(); ++j)
    names.push_back(data.u_names[j]), cols.push_back(&data.u[j]);
  for (std::size_t i = 0; i < p; ++i)
    names.push_back(y_names[i] + "_model"), cols.push_back(&sim.y_model[i]);
  if (file.scheduled) {
    owned.push_back(schedule_amplitudes(*file.scheduled, rec));
    names.push_back("amplitude_" + file.inputs.front().unit), cols.push_back(&owned.back());
  }
  json result = {{"samples", data.rows},
                 {"output", cmd.output_path},
                 {"realizations", rec.u.size()},
                 {"skip_samples", skip}};
  if (!data.y.empty()) {
    json outputs = json::array();
    double total2 = 0.0;
    for (std::size_t i = 0; i < p; ++i) {
      owned.emplace_back(data.rows);
      for (std::size_t k = 0; k < data.rows; ++k)
        owned.back()[k] = data.y[i][k] - sim.y_model[i][k];
      names.push_back(data.y_names[i]), cols.push_back(&data.y[i]);
      names.push_back(data.y_names[i] + "_residual"), cols.push_back(&owned.back());
      const double rms =
          sim.scored > 0
              ? std::sqrt(sim.sum2(static_cast<Eigen::Index>(i)) / static_cast<double>(sim.scored))
              : 0.0;
      total2 += rms * rms;
      outputs.push_back({{"name", data.y_names[i]},
                         {"unit", file.outputs[i].unit},
                         {"rmse", rms},
                         {"max_abs", sim.max_abs(static_cast<Eigen::Index>(i))}});
    }
    result["outputs"] = outputs;
    result["rmse"] = std::sqrt(total2 / static_cast<double>(p));
    result["scored_samples"] = sim.scored;
    if (!cmd.json_output) {
      out << std::fixed << std::setprecision(4) << "error     rms over outputs "
          << result["rmse"].get<double>() << " " << file.outputs.front().unit << " (";
      for (const auto& o : outputs) {
        out << o["name"].get<std::string>() << " " << o["rmse"].get<double>() << "; ";
      }
      out << "each realization from rest, the first " << skip << " samples of each not scored)\n";
    }
  }
  write_csv(cmd.output_path, names, cols,
            {"hystbench simulate model=" + cmd.model_path + " data=" + cmd.data_path});
  if (cmd.json_output) {
    out << result.dump() << "\n";
  } else {
    out << "wrote " << cmd.output_path << " (" << data.rows << " samples)\n";
  }
  return 0;
}

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

int print_result(std::ostream& out, bool json_output, const json& result, const std::string& text) {
  if (json_output) {
    out << result.dump() << "\n";
  } else {
    out << text;
  }
  return 0;
}

}  // namespace hystbench::cli::details
