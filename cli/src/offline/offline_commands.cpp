#include "hystbench/cli/offline/offline_commands.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/common/fit_families.hpp"
#include "hystbench/compensation/drive_planner.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "offline/details/mimo_commands.hpp"
#include "offline/details/progress_line.hpp"

namespace hystbench::cli {

namespace hc = compensation;
using nlohmann::json;

namespace {

void print_stats(std::ostream& out, const char* label, const hc::ErrorStats& s,
                 const std::string& unit) {
  out << std::left << std::setw(10) << label << std::right << std::fixed << std::setprecision(4)
      << "rms " << s.rmse << " " << unit << " (" << std::setprecision(2) << s.rmse_percent()
      << " % of range)   max " << std::setprecision(4) << s.max_abs << " " << unit << " ("
      << std::setprecision(2) << s.max_percent() << " %)   over " << s.samples << " samples\n";
}

// Runs a command body, turning exceptions into a clear message and exit code 1 (2 for usage).
template <typename F>
int guarded(std::ostream& err, F&& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    err << "hystbench: error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace

int run_fit(const FitCommand& cmd, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (cmd.model_name == "hammerstein" || names_several(cmd.columns)) {
      if (cmd.model_name != "hammerstein" && cmd.model_name != FitCommand{}.model_name) {
        throw std::invalid_argument("--model " + cmd.model_name +
                                    " takes one input and one output column; several are fitted "
                                    "as --model hammerstein");
      }
      return details::run_fit_mimo(cmd, out, err);
    }
    if (!cmd.more_data_paths.empty()) {
      throw std::invalid_argument(
          "several records are fitted as one model of several inputs (comma lists in --u-column "
          "and --y-column); a model of one input takes one record");
    }
    const Record data = read_record(cmd.data_path, cmd.columns, true);
    hc::FitOptions opt;
    try {
      opt.kind = common::parse_fit_family(cmd.model_name);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--model: ") + e.what());
    }
    opt.operators = cmd.operators;
    opt.dead_zones = cmd.dead_zones;
    opt.heldout_fraction = cmd.heldout_fraction;
    opt.refine_thresholds = cmd.refine;
    // A file's history is unknown: by default its start is left out until the input has
    // reached both extremes.
    opt.skip_samples = std::nullopt;
    if (cmd.skip_s) {
      opt.skip_samples = static_cast<std::size_t>(std::lround(*cmd.skip_s / data.sample_period_s));
    }
    opt.creep = cmd.creep.value_or(true);  // unset: tried, kept when it lowers held-out error
    opt.creep_always = cmd.creep.value_or(false);
    opt.drift = cmd.drift;
    opt.preisach_rate_law = cmd.plane_rate_law;
    opt.units = data.units();
    if (!cmd.json_output) {
      opt.progress = [&err](double fraction, const std::string& what) {
        details::progress_line(err, fraction, what);
      };
    }
    const hc::FitResult r = hc::fit_model(data.t, data.u, data.y, opt);
    if (!cmd.json_output) err << "\n";
    // What the fit chose: kept in the model file and printed by --json alike.
    const json fitted = {{"method", r.method},
                         {"operators", r.operators},
                         {"dead_zones", r.dead_zones},
                         {"delay_samples", r.delay_samples},
                         {"creep", r.creep},
                         {"skipped_samples", r.skipped_samples},
                         {"drift_per_s", r.drift_per_s},
                         {"notes", r.notes},
                         {"fit", to_json(r.fit)},
                         {"heldout", to_json(r.heldout)}};
    hc::ModelFile file{r.model, fitted};
    file.identification.update({{"data_file", cmd.data_path},
                                {"samples", data.t.size()},
                                {"fit_samples", r.fit_samples},
                                {"heldout_samples", r.heldout_samples},
                                {"sample_period_s", data.sample_period_s}});
    common::save_model_file(cmd.output_path, file);
    const std::string type(hc::to_string(r.model.hysteresis().kind()));
    if (cmd.json_output) {
      json result = fitted;
      result.update(
          {{"model", cmd.output_path}, {"type", type}, {"units", hc::to_json(r.model.units)}});
      out << result.dump() << "\n";
    } else {
      out << "model     " << type << " with " << r.operators
          << (type == "preisach" ? " cells per side, " : " plays, ") << r.dead_zones
          << " dead zones per side, delay " << r.delay_samples << " samples, "
          << (r.creep ? "with" : "no") << " creep lags (" << r.method << ")\n";
      for (const std::string& note : r.notes) out << "note      " << note << "\n";
      print_stats(out, "fit", r.fit, r.model.units.output);
      print_stats(out, "held-out", r.heldout, r.model.units.output);
      out << "saved     " << cmd.output_path << "\n";
    }
    return 0;
  });
}

int run_simulate(const SimulateCommand& cmd, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    if (const auto mimo = common::load_mimo_model_file(cmd.model_path)) {
      return details::run_simulate_mimo(cmd, *mimo, out, err);
    }
    if (cmd.skip_s) {
      throw std::invalid_argument("--skip: only for a model of several inputs (mimo_hammerstein)");
    }
    hc::ModelFile file = common::load_model_file(cmd.model_path);
    const Record data = read_record(cmd.data_path, cmd.columns, false);
    // The record's units, where it names them, must be the model's.
    const hc::Units units =
        common_units(std::span(&data, 1), std::span(&cmd.data_path, 1), file.model.units);
    const auto& t = data.t;
    const auto& u = data.u;
    const std::vector<double> y_model = file.model.simulate(u, data.sample_period_s);
    std::vector<std::string> names{"t", "u", "y_model"};
    std::vector<const std::vector<double>*> cols{&t, &u, &y_model};
    std::vector<double> residual;
    json result = {
        {"samples", u.size()}, {"output", cmd.output_path}, {"units", hc::to_json(units)}};
    if (!data.y.empty()) {
      const auto& y = data.y;
      residual.resize(y.size());
      for (std::size_t k = 0; k < y.size(); ++k) residual[k] = y[k] - y_model[k];
      names.insert(names.end(), {"y", "residual"});
      cols.insert(cols.end(), {&y, &residual});
      const hc::ErrorStats s = hc::error_stats(y, y_model);
      result.update(to_json(s));
      if (!cmd.json_output) print_stats(out, "error", s, units.output);
    }
    write_csv(cmd.output_path, names, cols,
              {"hystbench simulate model=" + cmd.model_path + " data=" + cmd.data_path,
               "units: t s, u " + units.input + ", y " + units.output});
    if (cmd.json_output) {
      out << result.dump() << "\n";
    } else {
      out << "wrote " << cmd.output_path << " (" << u.size() << " samples)\n";
    }
    return 0;
  });
}

int run_invert(const InvertCommand& cmd, std::ostream& out, std::ostream& err) {
  return guarded(err, [&] {
    hc::ModelFile file = common::load_model_file(cmd.model_path);
    // The reference goes through the record reader as its input column: same checks (finite,
    // t increasing, scale and rate valid), same messages naming file, column and line.
    if (!std::isfinite(cmd.yr_scale) || cmd.yr_scale == 0.0) {
      throw DataFileError("--yr-scale must be a finite, non-zero number");
    }
    RecordColumns columns;
    columns.t = cmd.t_column;
    columns.u = cmd.yr_column;
    columns.y.clear();  // no output column to read
    columns.u_scale = cmd.yr_scale;
    columns.rate_hz = cmd.rate_hz;
    columns.read_units = false;  // the reference is in the model's output unit
    columns.u_role = "reference";
    columns.u_option = "--yr-column";
    const Record reference = read_record(cmd.reference_path, columns, false);
    const auto& t = reference.t;
    const auto& yr = reference.u;
    file.model.configure(reference.sample_period_s);
    hc::InverseKind kind = hc::InverseKind::kAuto;
    if (cmd.inverse == "analytic")
      kind = hc::InverseKind::kAnalytic;
    else if (cmd.inverse == "numeric")
      kind = hc::InverseKind::kNumeric;
    else if (cmd.inverse == "multiplicative")
      kind = hc::InverseKind::kMultiplicative;
    else if (cmd.inverse != "auto") {
      throw std::invalid_argument("--inverse: unknown '" + cmd.inverse +
                                  "' (auto, analytic, numeric, multiplicative)");
    }
    auto inverse = hc::make_inverse(file.model, kind);
    const double u0 = file.model.input_min < file.model.input_max ? file.model.input_min : 0.0;
    inverse->reset(u0);
    std::vector<double> u;
    json result = {{"samples", yr.size()}, {"output", cmd.output_path}};
    if (kind == hc::InverseKind::kAuto && hc::can_plan_drive(file.model)) {
      // The whole reference is known: plan the drive of a rate-dependent model over it.
      hc::DrivePlanOptions options;
      if (!cmd.json_output) {
        options.progress = [&err](double fraction) {
          details::progress_line(err, fraction, "planning the drive");
        };
      }
      hc::DrivePlan plan = hc::plan_drive(file.model, u0, {}, yr, options);
      if (!cmd.json_output) err << "\n";
      u = std::move(plan.u);
      result["planned"] = {{"model_rms", plan.rms}, {"previewed_model_rms", plan.start_rms}};
      if (!cmd.json_output) {
        out << "planned   model rms " << std::fixed << std::setprecision(4) << plan.rms << " "
            << file.model.units.output << " (the previewed inverse's " << plan.start_rms << ")\n";
      }
    } else {
      // An inverse that looks ahead (a rate-dependent numeric one) sees the reference ahead.
      u = hc::invert_sequence(*inverse, yr);
    }
    write_csv(cmd.output_path, {"t", "yr", "u"}, {&t, &yr, &u},
              {"hystbench invert model=" + cmd.model_path + " reference=" + cmd.reference_path});
    if (cmd.json_output) {
      out << result.dump() << "\n";
    } else {
      out << "wrote " << cmd.output_path << " (" << u.size() << " samples)\n";
    }
    return 0;
  });
}

}  // namespace hystbench::cli
