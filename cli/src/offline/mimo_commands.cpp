#include "offline/details/mimo_commands.hpp"

#include <chrono>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/amplitude_dependence.hpp"
#include "offline/details/progress_line.hpp"

namespace hystbench::cli::details {

namespace hc = compensation;
using nlohmann::json;

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

// The measured outputs, each followed by its residual y - y_model, as columns (the residuals
// kept in `owned`, reserved ahead so that the pointers into it stay valid), and each output's
// error over the scored samples in `result`: outputs, rmse over them, scored_samples.
void add_measured_outputs(const MultiRecord& data, const hc::MimoModelFile& file,
                          const MimoSimulation& sim, std::vector<std::string>& names,
                          std::vector<const std::vector<double>*>& cols,
                          std::vector<std::vector<double>>& owned, json& result) {
  const std::size_t p = file.outputs.size();
  json outputs = json::array();
  double total2 = 0.0;
  for (std::size_t i = 0; i < p; ++i) {
    owned.emplace_back(data.rows);
    for (std::size_t k = 0; k < data.rows; ++k) owned.back()[k] = data.y[i][k] - sim.y_model[i][k];
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
    add_measured_outputs(data, file, sim, names, cols, owned, result);
    if (!cmd.json_output) {
      out << std::fixed << std::setprecision(4) << "error     rms over outputs "
          << result["rmse"].get<double>() << " " << file.outputs.front().unit << " (";
      for (const auto& o : result["outputs"]) {
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

int print_result(std::ostream& out, bool json_output, const json& result, const std::string& text) {
  if (json_output) {
    out << result.dump() << "\n";
  } else {
    out << text;
  }
  return 0;
}

}  // namespace hystbench::cli::details
