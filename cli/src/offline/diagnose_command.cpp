#include "hystbench/cli/offline/diagnose_command.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <ostream>
#include <sstream>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/offline/offline_commands.hpp"
#include "hystbench/common/step_timed_model.hpp"
#include "hystbench/compensation/model_check.hpp"
#include "hystbench/compensation/model_file.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "offline/details/mimo_commands.hpp"
#include "report/details/gnuplot.hpp"

namespace hystbench::cli {

namespace hc = compensation;
using nlohmann::json;

namespace {

constexpr std::size_t kMaxPlotPoints = 20000;

std::string fmt(double v, int digits = 4) { return hc::significant(v, digits); }

std::string pct(double fraction) { return hc::fixed(100.0 * fraction, 0) + " %"; }

// A column must hold finite numbers only: name the file, column and data row.
// The variable that explains the named cause, for its residual plot.
const char* explanatory_variable(hc::Cause c) {
  switch (c) {
    case hc::Cause::kAsymmetry:
    case hc::Cause::kLoopShape:
      return "input";
    case hc::Cause::kRateDependence:
    case hc::Cause::kDelay:
      return "rate";
    case hc::Cause::kCreep:
      return "since_event";
    case hc::Cause::kDynamics:
      return "frequency";
    case hc::Cause::kDrift:
    case hc::Cause::kNone:
      break;
  }
  return "time";
}

json model_json(const hc::ActuatorModel& m, const json& identification) {
  return hc::to_json(hc::ModelFile{m, identification});
}

json identification_of(const hc::Diagnosis& d, const std::string& data_path, bool extended) {
  json j = {{"data_file", data_path},
            {"source", "hystbench diagnose"},
            {"role", extended ? "extended" : "baseline"},
            {"cause", std::string(hc::to_string(d.cause))},
            {"description", extended ? d.extended_description : d.baseline_description},
            {"heldout", d.split.describe(d.sample_period_s)},
            {"samples", d.samples},
            {"sample_period_s", d.sample_period_s},
            {"fit", to_json(extended ? d.extended_fit : d.baseline_fit)},
            {"heldout_error", to_json(extended ? d.extended_heldout : d.baseline_heldout)}};
  return j;
}

// The baseline and the extended model scored on a record neither was fitted on.
struct Validation {
  std::string path;
  hc::ValidationScore baseline, extended;
  double gain() const { return extended.rmse > 0.0 ? baseline.rmse / extended.rmse : 1.0; }
};

json to_json(const Validation& v) {
  return {{"data", v.path},
          {"baseline_rms", v.baseline.rmse},
          {"extended_rms", v.extended.rmse},
          {"gain", v.gain()},
          {"baseline_offset", v.baseline.offset},
          {"extended_offset", v.extended.offset},
          {"baseline_max_abs", v.baseline.max_abs},
          {"extended_max_abs", v.extended.max_abs},
          {"samples", v.extended.samples},
          {"skipped_samples", v.extended.skipped}};
}

void print_validation(std::ostream& out, const Validation& v, const std::string& unit) {
  out << "validate  " << v.path << " (never fitted; " << v.extended.samples
      << " samples after the start-up, mean error removed): baseline rms " << fmt(v.baseline.rmse)
      << " " << unit << ", extended " << fmt(v.extended.rmse) << " " << unit << " (gain "
      << fmt(v.gain(), 3) << ")\n";
}

std::ofstream open_for_writing(const std::filesystem::path& p) {
  std::ofstream out(p, std::ios::trunc);
  if (!out) throw std::runtime_error(p.string() + ": cannot write");
  out << std::setprecision(10);
  return out;
}

// A candidate cause's test, its held-out score and what it would add.
json candidate_json(const hc::CandidateReport& c) {
  json left_out = json::array();
  for (const hc::LeftOutScore& l : c.left_out) {
    left_out.push_back(
        {{"record", l.record}, {"baseline_rms", l.baseline_rms}, {"rms", l.rms}, {"gain", l.gain}});
  }
  return {{"cause", std::string(hc::to_string(c.cause))},
          {"statistic", c.statistic},
          {"threshold", c.threshold},
          {"significant", c.significant},
          {"rmse_heldout", c.heldout.rmse},
          {"rmse_fit", c.fit.rmse},
          {"gain", c.gain},
          {"evidence", c.evidence},
          {"extension", c.extension},
          {"carries_over", c.carries_over},
          {"left_out_gain", c.left_out_gain},
          {"left_out", left_out},
          {"named", c.named},
          {"not_named", c.not_named}};
}

// The records diagnosed end to end: each one's first sample, length and output offset.
json records_json(const hc::Diagnosis& d) {
  json records = json::array();
  for (std::size_t i = 0; i < d.records.size(); ++i) {
    const std::size_t start = i < d.record_starts.size() ? d.record_starts[i] : 0;
    const std::size_t end = i + 1 < d.record_starts.size() ? d.record_starts[i + 1] : d.samples;
    const double offset = i < d.record_offsets.size() ? d.record_offsets[i] : 0.0;
    records.push_back({{"data", d.records[i]},
                       {"start", start},
                       {"samples", end - start},
                       {"output_offset", offset}});
  }
  return records;
}

}  // namespace

json diagnosis_to_json(const hc::Diagnosis& d, const std::string& data_path) {
  json candidates = json::array();
  for (const hc::CandidateReport& c : d.candidates) candidates.push_back(candidate_json(c));
  json causes = json::array();
  for (const hc::NamedCause& n : d.causes) {
    causes.push_back({{"cause", std::string(hc::to_string(n.cause))},
                      {"gain", n.gain},
                      {"against", n.against},
                      {"heldout_rms", n.heldout_rms},
                      {"added_gain", n.added_gain},
                      {"added_rms", n.added_rms},
                      {"evidence", n.evidence},
                      {"extension", n.extension}});
  }
  const json records = records_json(d);
  json structure = json::object();
  for (const hc::ResidualProfile& p : d.profiles) structure[p.variable] = p.explained;
  json baseline = {{"model", model_json(d.baseline, identification_of(d, data_path, false))},
                   {"description", d.baseline_description},
                   {"given", d.baseline_given},
                   {"rmse", d.baseline_heldout.rmse},
                   {"max_abs", d.baseline_heldout.max_abs},
                   {"rmse_fit", d.baseline_fit.rmse}};
  if (d.refit_heldout) baseline["rmse_refit"] = d.refit_heldout->rmse;
  const double gain =
      d.extended_heldout.rmse > 0.0 ? d.baseline_heldout.rmse / d.extended_heldout.rmse : 1.0;
  return {{"data", data_path},
          {"cause", std::string(hc::to_string(d.cause))},
          {"causes", causes},
          {"units", hc::to_json(d.baseline.units)},
          {"verdict", d.verdict},
          {"notes", d.notes},
          {"records", records},
          {"samples", d.samples},
          {"sample_period_s", d.sample_period_s},
          {"heldout", d.split.describe(d.sample_period_s)},
          {"noise_rms", d.noise_rms},
          {"noise_source", d.noise_source},
          {"noise_allowance_rms", d.noise_allowance_rms},
          {"coherent_share", d.coherent_share},
          {"input_period_samples", d.input_period},
          {"baseline", baseline},
          {"extended",
           {{"model", model_json(d.extended, identification_of(d, data_path, true))},
            {"description", d.extended_description},
            {"parts", d.extended_parts},
            {"rmse", d.extended_heldout.rmse},
            {"max_abs", d.extended_heldout.max_abs},
            {"rmse_fit", d.extended_fit.rmse},
            {"gain", gain}}},
          {"candidates", candidates},
          {"residual_structure", structure}};
}

void print_diagnosis(std::ostream& out, const hc::Diagnosis& d, const std::string& data_path) {
  const std::string unit = d.baseline.units.output;
  const double seconds = d.sample_period_s * static_cast<double>(d.samples - 1);
  out << "data      " << data_path << ": " << d.samples << " samples"
      << (d.records.size() > 1 ? " in " + std::to_string(d.records.size()) + " records" : "")
      << ", " << fmt(1.0 / d.sample_period_s) << " Hz, " << fmt(seconds) << " s; u in "
      << d.baseline.units.input << ", y in " << unit << "\n";
  out << "held out  " << d.split.describe(d.sample_period_s) << "\n";
  out << "baseline  " << d.baseline_description << "\n"
      << "          held-out rms " << fmt(d.baseline_heldout.rmse) << " " << unit << " ("
      << fmt(d.baseline_heldout.rmse_percent(), 3) << " % of range), max "
      << fmt(d.baseline_heldout.max_abs) << " " << unit << "; noise rms about "
      << fmt(d.noise_rms, 3) << " " << unit << " (" << d.noise_source << ")\n";
  if (d.refit_heldout) {
    out << "          same structure refitted here: held-out rms " << fmt(d.refit_heldout->rmse)
        << " " << unit << "\n";
  }
  out << "residual  share of the baseline residual variance explained by:";
  for (const hc::ResidualProfile& p : d.profiles)
    out << "  " << p.variable << " " << pct(p.explained);
  out << "\n";
  const hc::FrequencyResponse& fr = d.frequency_response;
  std::optional<std::size_t> peak;
  for (std::size_t i = 0; i < fr.gain.size(); ++i) {
    if (fr.informative[i] && (!peak || fr.gain[i] > fr.gain[*peak])) peak = i;
  }
  if (peak) {
    out << "          measured / predicted: largest gain " << fmt(fr.gain[*peak], 3) << " at "
        << fmt(fr.frequency_hz[*peak], 3) << " Hz (phase "
        << fmt(fr.phase_rad[*peak] * 180.0 / M_PI, 3)
        << " deg), over the coherent bins above the noise\n";
  } else {
    out << "          measured / predicted: no coherent frequency bin above the noise\n";
  }
  out << "candidates (held-out rms; gain = baseline / candidate):\n";
  for (const hc::CandidateReport& c : d.candidates) {
    out << "  " << std::left << std::setw(16) << hc::to_string(c.cause) << std::right
        << " statistic " << std::setw(8) << fmt(c.statistic, 3) << (c.significant ? " >= " : " <  ")
        << std::setw(5) << fmt(c.threshold, 2) << "  rms " << std::setw(9) << fmt(c.heldout.rmse)
        << "  gain " << std::setw(7) << fmt(c.gain, 3) << "  " << c.extension << "\n"
        << "  " << std::string(16, ' ') << " " << c.evidence << "\n";
    if (!c.left_out.empty()) {
      out << "  " << std::string(16, ' ') << " records left out whole: gain";
      for (const hc::LeftOutScore& l : c.left_out) out << " " << fmt(l.gain, 3);
      out << " (geometric mean " << fmt(c.left_out_gain, 3) << ", "
          << (c.carries_over ? "carries over" : "does not carry over") << ")\n";
    }
    if (c.significant && !c.named) {
      out << "  " << std::string(16, ' ') << " not named: " << c.not_named << "\n";
    }
  }
  out << "cause     " << hc::to_string(d.cause) << "\n          " << d.verdict << "\n";
  // The named causes, largest gain first; each adds to those before it more than the noise
  // allows.
  for (std::size_t i = 0; i < d.causes.size(); ++i) {
    const hc::NamedCause& n = d.causes[i];
    out << "named     " << i + 1 << ". " << std::left << std::setw(16) << hc::to_string(n.cause)
        << std::right << " gain " << fmt(n.gain, 3) << " over " << n.against << ", held-out rms "
        << fmt(n.heldout_rms) << " " << unit;
    if (i > 0) {
      out << "; added to the causes before it: gain " << fmt(n.added_gain, 3) << ", "
          << fmt(n.added_rms, 3) << " " << unit << " rms (the noise allows "
          << fmt(d.noise_allowance_rms, 3) << " " << unit << ")";
    }
    out << "\n          " << n.extension << "\n          " << n.evidence << "\n";
  }
  for (const std::string& n : d.notes) out << "note      " << n << "\n";
  out << "extended  " << d.extended_description << ": held-out rms " << fmt(d.extended_heldout.rmse)
      << " " << unit << "\n";
}

namespace {

// record.dat: the whole record with both models' predictions and residuals, thinned to at most
// kMaxPlotPoints rows.
void write_record_series(const std::filesystem::path& file, const hc::Diagnosis& d,
                         std::span<const double> t, std::span<const double> u,
                         std::span<const double> y) {
  const std::size_t n = u.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + kMaxPlotPoints - 1) / kMaxPlotPoints);
  auto f = open_for_writing(file);
  f << "# t u y y_baseline y_extended residual_baseline residual_extended part "
       "(0 fit, 1 held out, 2 start-up: neither)\n";
  for (std::size_t k = 0; k < n; k += stride) {
    const double yb = d.baseline_prediction[k], ye = d.extended_prediction[k];
    const int part = d.split.is_skipped(k) ? 2 : d.split.is_heldout(k) ? 1 : 0;
    f << t[k] << ' ' << u[k] << ' ' << y[k] << ' ' << yb << ' ' << ye << ' ' << y[k] - yb << ' '
      << y[k] - ye << ' ' << part << '\n';
  }
}

// explanatory.dat: the frequency response, or the baseline residual binned against the variable
// that explains the cause (empty when there is no such profile).
void write_explanatory(const std::filesystem::path& file, const hc::Diagnosis& d,
                       const std::string& variable, const hc::ResidualProfile* profile) {
  auto f = open_for_writing(file);
  if (variable == "frequency") {
    f << "# frequency_hz gain phase_deg coherence informative (measured / baseline "
         "prediction)\n";
    const auto& fr = d.frequency_response;
    for (std::size_t i = 0; i < fr.frequency_hz.size(); ++i) {
      f << fr.frequency_hz[i] << ' ' << fr.gain[i] << ' ' << fr.phase_rad[i] * 180.0 / M_PI << ' '
        << fr.coherence[i] << ' ' << int{fr.informative[i]} << '\n';
    }
  } else if (profile != nullptr) {
    f << "# " << profile->label << " | mean baseline residual | samples\n";
    for (std::size_t i = 0; i < profile->centers.size(); ++i) {
      f << profile->centers[i] << ' ' << profile->means[i] << ' ' << profile->counts[i] << '\n';
    }
  }
}

// candidates.dat: the baseline's and each candidate's held-out rms and gain.
void write_candidates(const std::filesystem::path& file, const hc::Diagnosis& d) {
  auto f = open_for_writing(file);
  f << "# index name heldout_rms gain\n0 baseline " << d.baseline_heldout.rmse << " 1\n";
  int i = 1;
  for (const hc::CandidateReport& c : d.candidates) {
    f << i++ << ' ' << hc::to_string(c.cause) << ' ' << c.heldout.rmse << ' ' << c.gain << '\n';
  }
}

// The cause's plot: explanatory.dat against its variable.
void plot_cause(std::ostream& gp, const std::filesystem::path& dir, const std::string& variable,
                const hc::ResidualProfile* profile, const std::string& out) {
  const std::filesystem::path expl = dir / "explanatory.dat";
  gp << "set output " << details::gnuplot_quoted(dir / ("cause_" + variable + ".png")) << "\n";
  if (variable == "frequency") {
    gp << "set title 'measured / baseline prediction against frequency (Welch)'\n"
       << "set logscale x\nset xlabel 'f [Hz]'\nset ylabel 'gain'\nset y2label 'phase [deg]'\n"
       << "set ytics nomirror\nset y2tics\n"
       << "plot " << details::gnuplot_quoted(expl)
       << " using 1:($5 > 0 ? $2 : 1/0) with lines lw 2 title "
          "'gain (informative bins)', \\\n"
       << "     '' using 1:($5 > 0 ? $3 : 1/0) axes x1y2 with lines title 'phase'\n"
       << "unset logscale x\nunset y2tics\nunset y2label\nset ytics mirror\n";
  } else {
    const std::string label = profile != nullptr ? profile->label : variable;
    gp << "set title 'baseline residual against " << label << " (binned mean)'\nset xlabel '"
       << label << "'\nset ylabel 'mean residual [" << out << "]'\n";
    if (variable == "since_event") gp << "set logscale x\n";
    gp << "plot " << details::gnuplot_quoted(expl)
       << " using 1:2 with linespoints lw 2 title 'mean residual'\n";
    if (variable == "since_event") gp << "unset logscale x\n";
  }
}

// report.gp: the loops, the residual against time, the cause's plot and the held-out errors.
std::string report_script(const std::filesystem::path& dir, const hc::Diagnosis& d,
                          const std::string& variable, const hc::ResidualProfile* profile) {
  const std::string in = d.baseline.units.input, out = d.baseline.units.output;
  const std::string cause(hc::to_string(d.cause));
  const std::filesystem::path record = dir / "record.dat";
  std::ostringstream gp;
  gp << "# hystbench diagnose report: gnuplot " << details::gnuplot_quoted(dir / "report.gp")
     << "\n"
     << "set terminal pngcairo size 1000,650 font ',10' noenhanced\nset grid\nset key top left\n"
     << "set datafile commentschars '#'\n";
  gp << "set output " << details::gnuplot_quoted(dir / "loops.png") << "\n"
     << "set title 'y against u: measured and both models (cause: " << cause << ")'\n"
     << "set xlabel 'u [" << in << "]'\nset ylabel 'y [" << out << "]'\n"
     << "plot " << details::gnuplot_quoted(record)
     << " using 2:3 with points pt 7 ps 0.25 lc rgb '#999999' title 'measured', \\\n"
     << "     '' using 2:4 with lines lw 1 lc rgb '#d62728' title 'baseline', \\\n"
     << "     '' using 2:5 with lines lw 1 lc rgb '#1f77b4' title 'extended'\n";
  gp << "set output " << details::gnuplot_quoted(dir / "residual_time.png") << "\n"
     << "set title 'residual against time, before (baseline) and after (extended); grey: held "
        "out'\n"
     << "set xlabel 't [s]'\nset ylabel 'y - model [" << out << "]'\n"
     << "plot " << details::gnuplot_quoted(record)
     << " using 1:($8 == 1 ? $6 : 1/0) with impulses lc rgb '#dddddd' notitle, \\\n"
     << "     '' using 1:($8 < 2 ? $6 : 1/0) with lines lc rgb '#d62728' title 'baseline', \\\n"
     << "     '' using 1:($8 < 2 ? $7 : 1/0) with lines lc rgb '#1f77b4' title 'extended'\n";
  plot_cause(gp, dir, variable, profile, out);
  gp << "set output " << details::gnuplot_quoted(dir / "heldout_errors.png") << "\n"
     << "set title 'held-out rms error: baseline and each candidate (gain above the bars)'\n"
     << "set style fill solid 0.6\nset boxwidth 0.6\nset xlabel ''\nset ylabel 'rms [" << out
     << "]'\nset yrange [0:*]\nset xtics rotate by -30\n"
     << "plot " << details::gnuplot_quoted(dir / "candidates.dat")
     << " using 1:3:xtic(2) with boxes lc rgb '#1f77b4' notitle, \\\n"
     << "     '' using 1:3:(sprintf('%.2fx', $4)) with labels offset 0,1 notitle\n";
  return gp.str();
}

}  // namespace

void write_diagnosis_report(const std::string& dir_name, const hc::Diagnosis& d,
                            const std::string& data_path, std::span<const double> t,
                            std::span<const double> u, std::span<const double> y) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::absolute(dir_name);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    throw std::runtime_error(dir.string() + ": cannot create the report folder");
  }
  {
    auto f = open_for_writing(dir / "report.txt");
    print_diagnosis(f, d, data_path);
  }
  {
    auto f = open_for_writing(dir / "diagnosis.json");
    f << std::setw(2) << diagnosis_to_json(d, data_path) << "\n";
  }
  write_record_series(dir / "record.dat", d, t, u, y);
  const std::string variable = explanatory_variable(d.cause);
  const hc::ResidualProfile* profile = d.profile(variable);
  write_explanatory(dir / "explanatory.dat", d, variable, profile);
  write_candidates(dir / "candidates.dat", d);
  const std::string script = report_script(dir, d, variable, profile);
  {
    auto f = open_for_writing(dir / "report.gp");
    f << script;
  }
  details::run_gnuplot(dir / "report.gp", dir / "gnuplot.log");
}

// What --save-baseline and --save-extended did: each model checked before it is written
// (model_check.hpp), and the extended model's dynamics and delay timed on the first record's step
// responses, as identify times its extension.
struct SavedModels {
  std::optional<json> timing;  ///< the extended model's timing (none: not saved, or no steps)
  std::vector<std::pair<std::string, hc::ModelCheck>> checks;  ///< "baseline", "extended"
  std::string refused;  ///< "extended model not saved to F: its check failed: ..."
};

// Writes `model` to `path` when it passes its check; else says why in saved.refused.
void save_checked(const std::string& path, const std::string& which, const hc::ModelFile& file,
                  double dt_s, SavedModels& saved) {
  const hc::ModelCheck check = hc::check_model(file.model, dt_s);
  saved.checks.emplace_back(which, check);
  if (check.passed) {
    common::save_model_file(path, file);
    return;
  }
  if (!saved.refused.empty()) saved.refused += "; ";
  saved.refused += which + " model not saved to " + path + ": its check " + describe(check);
}

SavedModels save_models(const DiagnoseCommand& cmd, const hc::Diagnosis& d,
                        const std::string& label, const Record& first) {
  SavedModels saved;
  if (!cmd.save_baseline.empty()) {
    save_checked(cmd.save_baseline, "baseline",
                 hc::ModelFile{d.baseline, identification_of(d, label, false)}, d.sample_period_s,
                 saved);
  }
  if (cmd.save_extended.empty()) return saved;
  hc::ActuatorModel model = d.extended;
  json timing = common::time_on_steps(model, first.u, first.y, first.sample_period_s, 0.0);
  json identification = identification_of(d, label, true);
  if (!timing.is_null()) {
    identification["timing"] = timing;
    saved.timing = std::move(timing);
  }
  save_checked(cmd.save_extended, "extended", hc::ModelFile{model, identification},
               d.sample_period_s, saved);
  return saved;
}

// The models written, each with its check (or why it was not written: the error says so too).
void print_saved(std::ostream& out, const DiagnoseCommand& cmd, const SavedModels& saved) {
  for (const auto& entry :
       {std::pair{"baseline", &cmd.save_baseline}, std::pair{"extended", &cmd.save_extended}}) {
    // Named, not a structured binding: clang (clang-tidy) refuses a lambda capturing one.
    const char* const which = entry.first;
    const std::string* const path = entry.second;
    const auto check = std::find_if(saved.checks.begin(), saved.checks.end(),
                                    [&which](const auto& c) { return c.first == which; });
    if (path->empty() || check == saved.checks.end()) continue;
    if (!check->second.passed) {
      out << "not saved " << which << " " << *path << ": its check " << describe(check->second)
          << "\n";
      continue;
    }
    out << "saved     " << which << " " << *path;
    if (std::string(which) == "extended" && saved.timing) {
      out << " (its dynamics and delay " << common::timing_text(*saved.timing) << ")";
    }
    out << "; its check " << describe(check->second) << "\n";
  }
}

int run_diagnose(const DiagnoseCommand& cmd, std::ostream& out, std::ostream& err) {
  try {
    if (cmd.data_paths.empty()) throw std::invalid_argument("no record to diagnose");
    if (names_several(cmd.columns)) return details::run_diagnose_mimo(cmd, out, err);
    // The records diagnosed, then those only validated: every unit they name must agree.
    std::vector<Record> records;
    std::vector<std::string> paths = cmd.data_paths;
    paths.insert(paths.end(), cmd.validate_paths.begin(), cmd.validate_paths.end());
    records.reserve(paths.size());
    for (const std::string& path : paths) records.push_back(read_record(path, cmd.columns, true));
    std::string label;
    for (const std::string& path : cmd.data_paths) label += (label.empty() ? "" : " + ") + path;
    hc::DiagnosisOptions opt;
    if (!cmd.model_path.empty()) opt.baseline = common::load_model_file(cmd.model_path).model;
    opt.units = common_units(records, paths,
                             opt.baseline ? std::optional(opt.baseline->units) : std::nullopt);
    if (!cmd.json_output) {
      opt.progress = [&err](double fraction, const std::string& what) {
        err << "\r[" << std::setw(3) << static_cast<int>(100.0 * fraction) << " %] " << what
            << "\x1b[K" << std::flush;
      };
    }
    std::vector<hc::RecordView> views;
    for (std::size_t i = 0; i < cmd.data_paths.size(); ++i) {
      views.push_back({records[i].t, records[i].u, records[i].y, cmd.data_paths[i]});
    }
    const hc::Diagnosis d = hc::diagnose(views, opt);  // errors name the record
    if (!cmd.json_output) err << "\n";
    std::vector<Validation> validations;
    for (std::size_t i = cmd.data_paths.size(); i < records.size(); ++i) {
      const Record& v = records[i];
      try {
        validations.push_back({paths[i],
                               hc::validate_model(d.baseline, v.u, v.y, v.sample_period_s),
                               hc::validate_model(d.extended, v.u, v.y, v.sample_period_s)});
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(paths[i] + ": " + e.what());
      }
    }
    const SavedModels saved = save_models(cmd, d, label, records[0]);
    if (!cmd.report_dir.empty()) {
      // The records end to end, as the diagnosis saw them.
      std::vector<double> t, u, y;
      for (std::size_t i = 0; i < cmd.data_paths.size(); ++i) {
        const Record& r = records[i];
        const double offset = i < d.record_offsets.size() ? d.record_offsets[i] : 0.0;
        u.insert(u.end(), r.u.begin(), r.u.end());
        for (const double v : r.y) y.push_back(v - offset);
      }
      for (std::size_t k = 0; k < u.size(); ++k) {
        t.push_back(cmd.data_paths.size() == 1 ? records[0].t[k]
                                               : static_cast<double>(k) * d.sample_period_s);
      }
      write_diagnosis_report(cmd.report_dir, d, label, t, u, y);
    }
    if (cmd.json_output) {
      json j = diagnosis_to_json(d, label);
      json v = json::array();
      for (const Validation& x : validations) v.push_back(to_json(x));
      j["validation"] = v;
      for (const auto& [which, check] : saved.checks) j["model_checks"][which] = to_json(check);
      out << j.dump() << "\n";
    } else {
      print_diagnosis(out, d, label);
      for (const Validation& x : validations) print_validation(out, x, d.baseline.units.output);
      print_saved(out, cmd, saved);
      if (!cmd.report_dir.empty()) out << "report    " << cmd.report_dir << "\n";
    }
    if (!saved.refused.empty()) {
      err << "hystbench: error: " << saved.refused << "\n";
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    err << "hystbench: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace hystbench::cli
