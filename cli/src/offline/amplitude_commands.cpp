// fit and diagnose of records of several inputs taken at several amplitudes: one local model per
// record, blended by the drive's amplitude (compensation/amplitude_dependence.hpp).
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "hystbench/common/model_file_io.hpp"
#include "hystbench/compensation/amplitude_dependence.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "offline/details/mimo_commands.hpp"
#include "offline/details/progress_line.hpp"

namespace hystbench::cli::details {

namespace hc = compensation;
using nlohmann::json;

namespace {

hc::FitProgress progress_to(std::ostream& err, bool quiet) {
  if (quiet) return {};
  return [&err](double f, const std::string& what) { details::progress_line(err, f, what); };
}

// Each local model's figures: its record, amplitude, order, held-out error, and the schedule's.
json local_json(const hc::AmplitudeFit& fit, std::size_t k, const AmplitudeRecords& r) {
  const hc::HammersteinFitResult& l = fit.local[k];
  const hc::PeriodicRecord& rec = r.records[fit.order[k]];
  return {{"data", r.labels[fit.order[k]]},
          {"amplitude", fit.amplitudes[k]},
          {"order", l.linear.order},
          {"heldout", l.heldout},
          {"heldout_rms", {{"linear", l.heldout_linear}, {"hammerstein", l.heldout_hammerstein}}},
          {"hysteresis_kept", l.hysteresis_kept},
          {"schedule_rms", fit.schedule_rms[k]},
          {"left_out_rms", fit.left_out_rms[k]},
          {"realizations", rec.u.size()},
          {"periods", rec.periods},
          {"period_samples", rec.period}};
}

hc::HammersteinFitOptions local_options(int operators) {
  hc::HammersteinFitOptions o;
  if (operators > 0) o.operators = static_cast<std::size_t>(operators);
  return o;
}

hc::MimoModelFile scheduled_file(const hc::AmplitudeFit& fit, const AmplitudeRecords& r) {
  hc::MimoModelFile file;
  file.scheduled = fit.model;
  file.model = fit.model->local_models().back();
  file.sample_period_s = r.records.front().dt;
  file.inputs = channels(r.u_names, r.u_units, "V");
  file.outputs = channels(r.y_names, r.y_units, "um");
  return file;
}

}  // namespace

AmplitudeRecords amplitude_records(const std::vector<std::string>& paths,
                                   const RecordColumns& columns) {
  AmplitudeRecords r;
  r.labels = paths;
  for (const auto& path : paths) {
    const MultiRecord d = read_multi_record(path, columns, true);
    if (r.records.empty()) {
      r.u_names = d.u_names;
      r.y_names = d.y_names;
      r.u_units = d.u_units;
      r.y_units = d.y_units;
    } else if (d.u_units != r.u_units || d.y_units != r.y_units) {
      throw DataFileError(path + ": its columns' units differ from " + paths.front() + "'s");
    } else if (const double dt = r.records.front().dt;
               std::abs(d.sample_period_s - dt) > 1e-9 * dt) {
      throw DataFileError(path + ": sampled at " + hc::significant(1.0 / d.sample_period_s, 6) +
                          " Hz, " + paths.front() + " at " + hc::significant(1.0 / dt, 6) + " Hz");
    }
    r.records.push_back(dynamic_record(d, path));
  }
  return r;
}

AmplitudeRecords amplitude_records(const std::string& path, const MultiRecord& data,
                                   const hc::PeriodicRecord& record,
                                   const std::vector<std::vector<std::size_t>>& groups) {
  AmplitudeRecords r;
  r.u_names = data.u_names;
  r.y_names = data.y_names;
  r.u_units = data.u_units;
  r.y_units = data.y_units;
  for (const auto& g : groups) {
    std::string label = path + " (realization" + (g.size() > 1 ? "s" : "");
    for (std::size_t k = 0; k < g.size(); ++k) label += (k > 0 ? ", " : " ") + std::to_string(g[k]);
    r.labels.push_back(label + ")");
    r.records.push_back(hc::realizations_of(record, g));
  }
  return r;
}

int run_fit_scheduled(const FitCommand& cmd, const AmplitudeRecords& r, std::ostream& out,
                      std::ostream& err) {
  const auto started = std::chrono::steady_clock::now();
  hc::AmplitudeFitOptions options;
  options.local = local_options(cmd.operators);
  options.progress = progress_to(err, cmd.json_output);
  const hc::AmplitudeFit fit = hc::fit_amplitude_schedule(r.records, options);
  if (!cmd.json_output) err << "\n";
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  json locals = json::array();
  for (std::size_t k = 0; k < fit.local.size(); ++k) locals.push_back(local_json(fit, k, r));
  hc::MimoModelFile file = scheduled_file(fit, r);
  const std::string estimate =
      "the rms over the inputs of each one's standard deviation over the last window";
  file.identification = {{"method",
                          "a Hammerstein model fitted on each record (frequency-domain "
                          "Sanathanan-Koerner, poles shared), blended linearly by the amplitude"},
                         {"amplitude_estimate", estimate},
                         {"data", r.labels},
                         {"fit_s", seconds}};
  for (const auto& l : locals) file.local_identification.push_back(l);
  common::save_mimo_model_file(cmd.output_path, file);
  const std::string u_unit = file.inputs.front().unit, y_unit = file.outputs.front().unit;
  if (cmd.json_output) {
    out << json{{"model", cmd.output_path},
                {"type", hc::kScheduledMimoModelType},
                {"inputs", r.u_names},
                {"outputs", r.y_names},
                {"window_s", fit.model->window_s()},
                {"amplitude_estimate", estimate},
                {"amplitudes", locals},
                {"fit_s", seconds}}
               .dump()
        << "\n";
    return 0;
  }
  out << "model     " << hc::kScheduledMimoModelType << ": " << r.u_names.size() << " input(s) ("
      << joined(r.u_names) << ") -> " << r.y_names.size() << " output(s) (" << joined(r.y_names)
      << "), " << fit.local.size() << " local models blended by the drive's amplitude (" << estimate
      << ", " << fit.model->window_s() << " s)\n";
  out << std::fixed;
  for (const auto& l : locals) {
    out << "amplitude " << std::setprecision(4) << l["amplitude"].get<double>() << " " << u_unit
        << "  " << l["data"].get<std::string>() << ": order " << l["order"].get<std::size_t>()
        << ", held-out " << l["heldout_rms"]["hammerstein"].get<double>() << " " << y_unit << " on "
        << l["heldout"].get<std::string>() << "; the schedule on the record "
        << l["schedule_rms"].get<double>() << "; left out, the others predict it at "
        << l["left_out_rms"].get<double>() << "\n";
  }
  out << "          (errors: each realization simulated from rest, scored after its first "
         "period)\n";
  out << "saved     " << cmd.output_path << " (" << std::setprecision(1) << seconds << " s)\n";
  return 0;
}

namespace {

json diagnosis_json(const hc::AmplitudeDiagnosis& d, const AmplitudeRecords& r,
                    const hc::AmplitudeFit& fit) {
  json left = json::array(), modes = json::array(), entries = json::array();
  for (std::size_t k = 0; k < d.left_out.size(); ++k) {
    const auto& l = d.left_out[k];
    left.push_back({{"data", r.labels[fit.order[k]]},
                    {"amplitude", l.amplitude},
                    {"baseline_rms", l.baseline_rms},
                    {"baseline_order", l.baseline_order},
                    {"extended_rms", l.extended_rms},
                    {"gain", l.gain}});
  }
  for (const auto& m : d.modes) {
    modes.push_back({{"frequency_hz", m.frequency_hz},
                     {"damping", m.damping},
                     {"peak", m.peak},
                     {"shift_percent", m.shift_percent},
                     {"peak_ratio", m.peak_ratio}});
  }
  for (const auto& e : d.entries) {
    entries.push_back({{"output", r.y_names[e.output]},
                       {"input", r.u_names[e.input]},
                       {"change", e.change},
                       {"at_hz", e.at_hz}});
  }
  return {{"cause", d.named ? "amplitude_dependence" : "none"},
          {"data", r.labels},
          {"unit", r.y_units.front().value_or("um")},
          {"amplitude_dependence",
           {{"named", d.named},
            {"amplitudes", d.amplitudes},
            {"gain", d.gain},
            {"naming_gain", hc::kAmplitudeNamingGain},
            {"left_out", left},
            {"modes", modes},
            {"entries", entries}}}};
}

void print_amplitude_diagnosis(std::ostream& text, const hc::AmplitudeDiagnosis& d,
                               const AmplitudeRecords& r, const hc::AmplitudeFit& fit) {
  const std::string u_unit = r.u_units.front().value_or("V");
  const std::string y_unit = r.y_units.front().value_or("um");
  text << std::fixed << "records   " << r.labels.size()
       << " at the amplitudes (rms over the inputs) ";
  for (std::size_t k = 0; k < d.amplitudes.size(); ++k) {
    text << (k > 0 ? ", " : "") << std::setprecision(4) << d.amplitudes[k] << " " << u_unit;
  }
  text << "\neach amplitude left out: one model fitted on the others pooled -> the schedule of "
          "the others' models (simulated from rest, "
       << y_unit << " rms)\n";
  for (std::size_t k = 0; k < d.left_out.size(); ++k) {
    const auto& l = d.left_out[k];
    text << "  " << std::setprecision(4) << l.amplitude << " " << u_unit << " ("
         << r.labels[fit.order[k]] << "): " << l.baseline_rms << " (order " << l.baseline_order
         << ") -> " << l.extended_rms << ": " << std::setprecision(2) << l.gain << "x\n";
  }
  text << "modes     lowest -> highest amplitude (the highest's strongest first):\n";
  for (const auto& m : d.modes) {
    text << "  " << std::setprecision(1) << m.frequency_hz.front() << " -> "
         << m.frequency_hz.back() << " Hz (" << std::showpos << m.shift_percent << std::noshowpos
         << " %), peak x" << std::setprecision(2) << m.peak_ratio << ", damping "
         << std::setprecision(3) << m.damping.front() << " -> " << m.damping.back() << "\n";
  }
  text << "entries   |G_high - G_low| over |G_high|, largest first:";
  for (std::size_t k = 0; k < d.entries.size(); ++k) {
    const auto& e = d.entries[k];
    text << (k > 0 ? ";" : "") << " " << r.u_names[e.input] << "->" << r.y_names[e.output] << " "
         << std::setprecision(0) << 100.0 * e.change << " % (most at " << e.at_hz << " Hz)";
  }
  text << "\ncause:    ";
  if (d.named) {
    text << "amplitude_dependence: the schedule predicts an amplitude it did not fit "
         << std::setprecision(2) << d.gain << "x better than one model (geometric mean)\n";
  } else {
    text << "none named (amplitude dependence needs " << std::setprecision(1)
         << hc::kAmplitudeNamingGain << "x on the amplitudes left out; here "
         << std::setprecision(2) << d.gain << "x)\n";
  }
}

}  // namespace

int run_diagnose_amplitude(const DiagnoseCommand& cmd, const AmplitudeRecords& r, std::ostream& out,
                           std::ostream& err) {
  const hc::FitProgress progress = progress_to(err, cmd.json_output);
  hc::AmplitudeFitOptions options;
  options.progress = [&](double f, const std::string& what) {
    if (progress) progress(0.4 * f, what);
  };
  const hc::AmplitudeFit fit = hc::fit_amplitude_schedule(r.records, options);
  const hc::AmplitudeDiagnosis d = hc::diagnose_amplitude_dependence(
      r.records, fit, options.local, [&](double f, const std::string& what) {
        if (progress) progress(0.4 + 0.6 * f, what);
      });
  if (!cmd.json_output) err << "\n";
  const json result = diagnosis_json(d, r, fit);
  std::ostringstream text;
  print_amplitude_diagnosis(text, d, r, fit);
  if (!cmd.save_extended.empty()) {
    hc::MimoModelFile file = scheduled_file(fit, r);
    file.identification = {{"from", "diagnose: amplitude dependence"}, {"data", r.labels}};
    common::save_mimo_model_file(cmd.save_extended, file);
    text << "saved     " << cmd.save_extended << " (the schedule of every amplitude)\n";
  }
  if (!cmd.report_dir.empty()) {
    std::filesystem::create_directories(cmd.report_dir);
    std::ofstream(std::filesystem::path(cmd.report_dir) / "report.txt") << text.str();
    std::ofstream(std::filesystem::path(cmd.report_dir) / "diagnosis.json")
        << result.dump(2) << "\n";
    text << "report    " << cmd.report_dir << " (report.txt, diagnosis.json)\n";
  }
  return print_result(out, cmd.json_output, result, text.str());
}

}  // namespace hystbench::cli::details
