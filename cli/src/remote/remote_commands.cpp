#include "hystbench/cli/remote/remote_commands.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <ostream>

#include "hystbench/cli/offline/data_table.hpp"
#include "hystbench/cli/remote/bench_client.hpp"
#include "hystbench/cli/report/loop_plots.hpp"
#include "hystbench/cli/report/plot_command.hpp"
#include "hystbench/common/command_error.hpp"
#include "remote/details/feedback_text.hpp"
#include "remote/details/fixed_text.hpp"
#include "remote/details/identify_text.hpp"

namespace hystbench::cli {

using nlohmann::json;

std::string default_socket_path() {
  const char* env = std::getenv("HYSTBENCH_SOCKET");
  return env != nullptr && *env != '\0' ? env : "/run/hystbench/hystbench.sock";
}

namespace {

using details::fixed;
using details::fixed_or_dash;

std::string us(const json& ns) {
  return ns.is_number() ? fixed(ns.get<double>() / 1000.0, 1) : "?";
}

}  // namespace

void progress_bar(std::ostream& err, double fraction, const std::string& label) {
  const int width = 30;
  const int filled = static_cast<int>(std::lround(std::clamp(fraction, 0.0, 1.0) * width));
  err << "\r[" << std::string(filled, '#') << std::string(width - filled, '.') << "] "
      << std::setw(3) << static_cast<int>(100 * fraction) << " % " << label << "\x1b[K"
      << std::flush;
}

json wait_for_run(BenchClient& client, const std::string& run_id,
                  const std::function<void(double, const std::string&)>& progress) {
  for (;;) {
    auto event = client.next_event(std::chrono::seconds(3600));
    if (!event) continue;
    const std::string name = event->value("event", "");
    if (name == "run.finished" && (*event)["result"].value("run_id", "") == run_id) {
      return (*event)["result"];
    }
    if (!progress || event->value("run_id", "") != run_id) continue;
    if (name == "run.progress") {
      progress(event->value("fraction", 0.0), event->value("stage", std::string()));
    } else if (name == "fit.progress") {
      progress(event->value("fraction", 0.0), "fitting: " + event->value("stage", ""));
    }
  }
}

bool measure_response_if_missing(BenchClient& client, const std::string& compensator,
                                 std::ostream& err) {
  if (compensator != "inverse+pid" && compensator != "pid") return true;
  const json probe = client.request("tune", {{"compensator", compensator}});
  if (probe.value("ok", false) || probe["error"].value("code", "") != "no_frequency_response") {
    return true;  // designed, or refused for a cause the run will name itself
  }
  err << "hystbench: no frequency response is stored for the active model: measuring it first "
         "(hystbench frf)\n";
  const json started = client.request("frf", json::object());
  if (!started.value("ok", false)) {
    err << "hystbench: frf refused: " << started["error"].value("message", "?") << "\n";
    return false;
  }
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  std::function<void(double, const std::string&)> show;
  if (tty) show = [&](double f, const std::string&) { progress_bar(err, f, "frf"); };
  const json r = wait_for_run(client, started["result"].value("run_id", ""), show);
  if (tty) err << "\r\x1b[K" << std::flush;
  if (r.value("end", "") != "completed" || !r.contains("frequency_response")) {
    err << "hystbench: frf did not measure a response: "
        << r.value("frequency_response_error", r.value("reason", std::string("?"))) << "\n";
    return false;
  }
  return true;
}

namespace {

// Where a run's largest error fell: ", at index N" (the log's `index` column), or nothing for a
// result without the key.
std::string at_index(const json& r, const char* key) {
  if (!r.contains(key)) return {};
  return ", at index " + std::to_string(r[key].get<std::uint64_t>());
}

// A tracking run's error against its reference, and the hysteresis it leaves.
void print_tracking_error(std::ostream& out, const json& r) {
  out << "  tracking error  rms " << fixed(r["rms_error_um"], 4) << " um ("
      << fixed(r["rms_error_percent"], 3) << " % of " << fixed(r["range_um"], 2) << " um)   max "
      << fixed(r["max_error_um"], 4) << " um (" << fixed(r["max_error_percent"], 3) << " %"
      << at_index(r, "max_error_index") << ")\n";
  out << "  hysteresis      " << fixed(r["hysteresis_percent"], 3) << " % of the output range\n";
}

// A learning run: each trial's error, why it stopped, and the drive it saved.
void print_learning(std::ostream& out, const json& l) {
  const json& trials = l["trials"];
  const json from = l.value("started_from", json());
  out << "  learning        " << trials.size() << " trials of "
      << (l.value("reference", std::string()) == "upload"
              ? "a pass of " + std::to_string(l.value("period_samples", 0)) + " ticks"
              : fixed(l["frequency_hz"], 3) + " Hz")
      << " (the first with "
      << (from.is_string() ? "the drive " + from.get<std::string>() + " learned before"
                           : std::string("the compensator's drive"))
      << "): rms %";
  for (const json& t : trials) out << " " << fixed(t["rms_error_percent"], 3);
  out << "\n                  " << l.value("why", std::string()) << "; best trial "
      << l.value("best_trial", json()).dump() << ", cut-off " << fixed(l["cutoff_hz"], 0) << " Hz";
  const json above = l.value("above_cutoff", json::object());
  if (above.value("updates", 0) > 0) {
    out << ", above it through a " << fixed(above["mode_hz"], 0) << " Hz mode ("
        << above.value("mode_from", std::string()) << ") in " << above["updates"].get<int>()
        << " updates";
  }
  if (l.value("stale_periods", 0) > 0) {
    out << ", " << l["stale_periods"].get<int>()
        << " periods replayed while the update was computed";
  }
  out << "\n";
  // The bench's floor: what two plays of one drive differ by, and where it was measured again.
  if (const auto f = l.find("floor"); f != l.end() && f->is_object()) {
    const json pair = f->value("trials", json::array({0, 1}));
    out << "  floor           " << fixed((*f)["rms_error_percent"], 3) << " % rms (trials "
        << pair[0].dump() << " and " << pair[1].dump() << ", the same drive)";
    if (pair[0] != 0 && f->contains("first_rms_error_percent")) {
      out << "; " << fixed((*f)["first_rms_error_percent"], 3) << " % on trials 0 and 1";
    }
    out << "\n";
  }
  // The best trial's drive played again: said where its error did not repeat.
  if (const auto b = l.find("best_replayed");
      b != l.end() && b->is_object() && !b->value("held", true)) {
    out << "  best replayed   trial " << (*b)["trial"].dump() << "'s drive: rms %";
    for (const json& r : (*b)["replays_rms_percent"]) out << " " << fixed(r, 3);
    out << " (its own " << fixed((*b)["rms_error_percent"], 3)
        << "): " << b->value("meaning", std::string()) << "\n";
  }
  if (from.is_string() && l.value("lead_in_periods", 0) > 0) {
    const double period_s =
        l.value("frequency_hz", 0.0) > 0.0 ? 1.0 / l["frequency_hz"].get<double>() : 0.0;
    out << "  lead-in         " << l["lead_in_periods"].get<int>() << " periods";
    if (period_s > 0.0)
      out << " (" << fixed(l["lead_in_periods"].get<double>() * period_s, 2) << " s)";
    out << ", offset followed " << fixed(l.value("lead_in_followed_um", 0.0), 3)
        << " um: " << l.value("lead_in_end", std::string()) << "\n";
  }
  if (l.contains("drive_file")) {
    out << "  learned drive   " << l.value("drive", std::string()) << " ("
        << l["drive_file"].get<std::string>() << "): track --learned "
        << l.value("drive", std::string()) << " replays it\n";
  }
}

// The feedforward planned before the run: its size and error on the model, or why not.
void print_planned_feedforward(std::ostream& out, const json& p) {
  if (p.value("samples", 0) > 0) {
    out << "  feedforward     planned over " << p.value("samples", 0) << " samples in "
        << fixed(p["seconds"], 2) << " s: model rms " << fixed(p["model_rms_um"], 4)
        << " um (the previewed inverse's " << fixed(p["previewed_model_rms_um"], 4) << " um)\n";
  } else {
    out << "  feedforward     not planned: " << p.value("why_not", std::string("?")) << "\n";
  }
}

// Whether a model predicted y_model over the run, from the result's `y_model_from`: not where
// no model was active and the daemon stepped the straight line of limits.y_min..y_max
// ("limits") or nothing ("none"): y - y_model then measures the line, not a model. A result
// without the key (kept before the daemon wrote it) counts as a model's.
bool model_predicted(const json& r) { return r.value("y_model_from", "model") == "model"; }

// The bench's output against the model's prediction over the run; where the result gives the
// mean, the rms about it too (an offset apart: the creep since identify, say).
void print_model_error(std::ostream& out, const json& r) {
  out << "  model vs bench  rms " << fixed(r["model_rms_error_um"], 4) << " um ("
      << fixed(r["model_rms_error_percent"], 3) << " %)";
  if (r.contains("model_mean_error_um")) {
    const double rms = r["model_rms_error_um"].get<double>();
    const double mean = r["model_mean_error_um"].get<double>();
    out << ", mean " << fixed(mean, 4) << " um and "
        << fixed(std::sqrt(std::max(0.0, rms * rms - mean * mean)), 4) << " um about it";
  }
  out << "   max " << fixed(r["model_max_error_um"], 4) << " um ("
      << fixed(r["model_max_error_percent"], 3) << " %" << at_index(r, "model_max_error_index")
      << "): y - y_model (y_model: " << r.value("y_model", std::string("?")) << ")\n";
}

// The loop's timing over the run: wake latency, execution time, overruns.
void print_loop_timing(std::ostream& out, const json& r) {
  const json& l = r["loop"];
  const json w = l.value("wake_latency_ns", json::object());
  const json e = l.value("exec_ns", json::object());
  out << "  loop            wake latency p50 " << us(w.value("p50", json())) << " us, p99 "
      << us(w.value("p99", json())) << " us, max " << us(w.value("max", json()))
      << " us; execution p99 " << us(e.value("p99", json())) << " us; " << l.value("overruns", 0)
      << " overruns";
  // Virtual time: no wake-up to be late, no overrun; the execution time is measured.
  if (r.value("clock", "") == "simulated") out << " (simulated clock)";
  out << "\n";
}

}  // namespace

namespace {

// A stage's run: each axis's error, what the other axes left on it, and identify's coupling.
void print_stage(std::ostream& out, const json& r) {
  const json& axes = r["axes"];
  for (const auto& [name, a] : axes.items()) {
    // An axis's own y_model where the result gives one, else the run's (the first axis's).
    const bool model_error =
        a.contains("model_rms_error_um") && model_predicted(a.contains("y_model_from") ? a : r);
    if (!a.contains("rms_error_um") && !model_error) continue;
    out << "  axis " << name;
    for (std::size_t pad = name.size(); pad < 11; ++pad) out << ' ';
    if (a.contains("rms_error_um")) {
      out << "rms " << fixed(a["rms_error_percent"], 3) << " % (" << fixed(a["rms_error_um"], 4)
          << " um), max " << fixed(a["max_error_percent"], 3) << " % of "
          << fixed(a.value("range_um", 0.0), 2) << " um";
    } else if (model_error) {
      out << "model vs bench rms " << fixed(a["model_rms_error_um"], 3) << " um";
    }
    if (r.contains("coupling_error") && r["coupling_error"].contains(name)) {
      out << "; the other axes left " << fixed(r["coupling_error"][name]["rms_um"], 4) << " um";
    }
    out << "\n";
    if (const auto l = a.find("learning"); l != a.end() && l->is_object()) {
      out << "    learning      rms %";
      for (const json& t : (*l)["trials"]) out << " " << fixed(t["rms_error_percent"], 3);
      out << "\n                  " << l->value("why", std::string());
      if (l->value("lead_in_periods", 0) > 0) {
        out << "; lead-in " << (*l)["lead_in_periods"].get<int>() << " periods";
      }
      out << "\n";
    }
  }
  if (r.contains("learned_drive")) {
    const std::string run = r["learned_drive"].get<std::string>();
    out << "  learned drives  " << run << "-AXIS-learned: track --learned " << run
        << " replays every axis's\n";
  }
  if (const auto d = r.find("decoupling"); d != r.end() && d->is_object()) {
    out << "  decoupling      "
        << (d->value("static", false) ? "static, from " + d->value("from_run", std::string("?"))
                                      : "none: " + d->value("why_not", std::string("?")))
        << "\n";
  }
  const auto model = r.find("stage_model");
  if (model == r.end() || !model->is_object()) return;
  for (const auto& [name, fit] : (*model)["axes"].items()) {
    out << "  model " << name << "         " << fit.value("model", "?") << ", held-out rms "
        << fixed(fit["heldout_rms_error_um"], 4) << " um ("
        << fixed(fit["heldout_rms_error_percent"], 3) << " %)\n";
  }
  for (const auto& [pair, g] : (*model)["coupling"]["gains"].items()) {
    out << "  coupling " << pair << "    " << fixed(g["gain"], 4);
    if (g["db"].is_number()) out << " (" << fixed(g["db"], 1) << " dB)";
    out << "\n";
  }
}

}  // namespace

void print_run_result(const json& r, std::ostream& out) {
  out << "run " << r.value("run_id", "?") << " " << r.value("end", "?");
  // A completed run's reason ("every planned sample played") adds nothing to its end.
  if (r.value("end", "") != "completed" && !r.value("reason", std::string()).empty())
    out << " (" << r["reason"].get<std::string>() << ")";
  out << ": " << r.value("samples", 0) << " samples, " << r.value("dropped", 0) << " dropped\n";
  if (r.contains("rms_error_um")) print_tracking_error(out, r);
  if (r.contains("axes") && r["axes"].is_object()) print_stage(out, r);
  if (const auto l = r.find("learning"); l != r.end() && l->is_object()) print_learning(out, *l);
  if (r.contains("tare_um")) {
    out << "  tare            " << fixed(r["tare_um"], 4)
        << " um: the offset the model missed on the precondition sweep, taken off the "
           "feedforward\n";
  }
  if (r.contains("startup_offset_um")) {
    out << "  start-up        " << fixed(r["startup_offset_um"], 4)
        << " um: the mean error of the second, unscored period, taken off the feedforward "
           "from the first scored tick\n";
  }
  if (const auto ff = r.find("feedforward"); ff != r.end() && ff->contains("planned")) {
    print_planned_feedforward(out, (*ff)["planned"]);
  }
  if (r.contains("model_rms_error_um") && model_predicted(r)) print_model_error(out, r);
  details::print_identification(out, r);
  if (r.contains("fit_error"))
    out << "  fit failed      " << r["fit_error"].get<std::string>() << "\n";
  if (r.contains("frequency_response"))
    details::print_frequency_response(out, r["frequency_response"]);
  if (r.contains("frequency_response_error")) {
    out << "  response        not measured: " << r["frequency_response_error"].get<std::string>()
        << "\n";
  }
  if (r.contains("feedback")) details::print_feedback(out, r["feedback"]);
  if (r.contains("feedback_error")) {
    out << "  feedback        not designed: " << r["feedback_error"].get<std::string>() << "\n";
  }
  // An unplayed run has no timing.
  if (r.contains("loop") && r.value("samples", 0) > 0) print_loop_timing(out, r);
  if (r.contains("clamps")) {
    out << "  limits          " << r.value("clamps", 0) << " clamped, " << r.value("slew_limits", 0)
        << " slew-limited samples\n";
  }
  if (!r.value("log", std::string()).empty())
    out << "  log             " << r["log"].get<std::string>() << "\n";
}

RemoteUpload read_upload(const std::string& path, const std::string& kind,
                         const std::string& t_column, const std::string& value_column, double scale,
                         double rate_hz) {
  RecordColumns columns;
  columns.t = t_column;
  columns.u = value_column;
  columns.y.clear();  // no output column to read
  columns.u_scale = scale;
  columns.rate_hz = rate_hz;
  columns.read_units = false;  // a drive in V, a reference in um: what the daemon takes
  columns.u_role = kind;
  columns.u_option = kind == "drive" ? "--u-column" : "--yr-column";
  Record r = read_record(path, columns, false);
  RemoteUpload u;
  u.kind = kind;
  u.param = kind == "drive" ? "drive_upload" : "reference_upload";
  u.source = path;
  u.rate_hz = rate_hz;
  if (rate_hz <= 0.0) u.t = std::move(r.t);
  u.values = std::move(r.u);
  u.lines = std::move(r.lines);
  return u;
}

namespace {

/// The daemon's reply's result, or CommandError with its code, message and details.
json result_or_throw(const json& reply) {
  if (reply.value("ok", false)) return reply["result"];
  json e = reply.value("error", json::object());
  const std::string code = e.value("code", "error");
  const std::string message = e.value("message", "?");
  e.erase("code");
  e.erase("message");
  throw common::CommandError(code, message, e);
}

}  // namespace

std::string send_upload(BenchClient& client, const RemoteUpload& upload,
                        const std::function<void(double)>& progress) {
  const std::size_t n = upload.values.size();
  json begin = {{"kind", upload.kind},
                {"samples", n},
                {"source", std::filesystem::path(upload.source).filename().string()}};
  if (upload.rate_hz > 0.0) begin["rate_hz"] = upload.rate_hz;
  const json started = result_or_throw(client.request("upload.begin", begin));
  std::string name = started.value("upload", "");  // returned: not const, so it moves
  // Below the daemon's bound and well inside the 64 KiB request line with t and values.
  const std::size_t chunk =
      std::clamp<std::size_t>(started.value("max_chunk_samples", std::size_t{1000}), 1, 1000);
  for (std::size_t k = 0; k < n; k += chunk) {
    const std::size_t m = std::min(chunk, n - k);
    json params = {
        {"upload", name},
        {"offset", k},
        {"values", std::vector<double>(upload.values.begin() + k, upload.values.begin() + k + m)}};
    if (upload.rate_hz <= 0.0) {
      params["t"] = std::vector<double>(upload.t.begin() + k, upload.t.begin() + k + m);
    }
    (void)result_or_throw(client.request("upload.chunk", params));
    if (progress) progress(static_cast<double>(k + m) / static_cast<double>(n));
  }
  return name;
}

namespace {

/// Sends the command, after its upload, and returns the daemon's reply; CommandError when the
/// daemon refuses either.
/// A user's file the CLI could not read (a missing column, a bad row): no request was sent.
struct UnreadableInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The reference file's uploads: one for a one-axis bench (its value column), else one per axis
/// of the stage (the column named as the axis), keyed by axis ("" for one axis).
std::vector<std::pair<std::string, RemoteUpload>> reference_file_uploads(
    BenchClient& client, const RemoteCommand::ReferenceFile& file) {
  const json status = result_or_throw(client.request("status", json::object()));
  std::vector<std::pair<std::string, RemoteUpload>> out;
  try {
    if (!status.contains("axes") || !status["axes"].is_object()) {
      out.emplace_back("", read_upload(file.path, file.kind, file.t_column, file.value_column,
                                       file.scale, file.rate_hz));
      return out;
    }
    for (const auto& [axis, value] : status["axes"].items()) {
      (void)value;
      out.emplace_back(
          axis, read_upload(file.path, file.kind, file.t_column, axis, file.scale, file.rate_hz));
    }
  } catch (const std::exception& e) {
    std::string why = e.what();
    if (status.contains("axes")) {
      why += " (the bench is a stage: the file needs a column per axis, named ";
      std::string names;
      for (const auto& item : status["axes"].items())
        names += (names.empty() ? "" : ", ") + item.key();
      why += names + ")";
    }
    throw UnreadableInput(why);
  }
  return out;
}

json request_command(BenchClient& client, const RemoteCommand& cmd, bool tty, std::ostream& err) {
  json params = cmd.params;
  std::vector<std::pair<std::string, RemoteUpload>> uploads;
  if (cmd.upload) uploads.emplace_back("", *cmd.upload);
  if (cmd.reference_file) uploads = reference_file_uploads(client, *cmd.reference_file);
  for (const auto& entry : uploads) {
    // Named, not a structured binding: clang (clang-tidy) refuses a lambda capturing one.
    const std::string& axis = entry.first;
    const RemoteUpload& upload = entry.second;
    std::function<void(double)> shown;
    if (tty && !cmd.json_output && upload.values.size() > 100'000) {
      shown = [&](double f) { progress_bar(err, f, "uploading " + upload.source); };
    }
    const std::string name = send_upload(client, upload, shown);
    if (axis.empty()) {
      params[upload.param] = name;
    } else {
      params[upload.kind == "drive" ? "drive_uploads" : "reference_uploads"][axis] = name;
    }
    if (shown) err << "\r\x1b[K" << std::flush;
  }
  json reply = client.request(cmd.cmd, params);
  (void)result_or_throw(reply);
  return reply;
}

/// The daemon's refusal: as JSON, or as a message naming the first offending row of an upload.
void report_refusal(const RemoteCommand& cmd, const common::CommandError& e, std::ostream& out,
                    std::ostream& err) {
  if (cmd.json_output) {
    json error = e.detail();
    error["code"] = e.code();
    error["message"] = e.what();
    out << json{{"ok", false}, {"error", error}}.dump() << "\n";
    return;
  }
  err << "hystbench: " << cmd.cmd << " refused: " << e.what() << " [" << e.code() << "]\n";
  // The first offending sample, as the line of the user's file.
  if (cmd.upload && e.detail().contains("sample") && e.detail()["sample"].is_number()) {
    const auto k = e.detail()["sample"].get<std::size_t>();
    if (k < cmd.upload->lines.size()) {
      err << "hystbench: " << cmd.upload->source << ":" << cmd.upload->lines[k]
          << ": the first offending row (data row " << k + 1 << ")\n";
    }
  }
}

/// Plots the finished run's log into --plot's folder and lists the images in r["plots"]; false
/// when plotting failed. An frf run: its measured responses.
bool plot_run(const RemoteCommand& cmd, json& r, std::ostream& err) {
  try {
    json files = json::array();
    if (cmd.cmd == "frf") {
      if (!r.contains("frequency_response")) throw std::runtime_error("nothing was measured");
      for (const auto& png : plot_responses(r["frequency_response"]["measured"], cmd.plot_dir)) {
        files.push_back(png.string());
      }
      r["plots"] = files;
      return true;
    }
    for (const auto& png : plot_run_log(r["log"].get<std::string>(), cmd.plot_dir)) {
      files.push_back(png.string());
    }
    if (r.contains("learning")) {
      files.push_back(plot_learning(r["learning"], r["log"], cmd.plot_dir).string());
    }
    r["plots"] = files;
    return true;
  } catch (const std::exception& e) {
    err << "hystbench: error: --plot: " << e.what() << "\n";
    return false;
  }
}

/// tune's reply: the design in words (or as JSON), its plots with --plot. 0, or 1 when the
/// plots failed.
// One loop's design as tune prints it (one axis's on a stage).
void print_loop_design(std::ostream& out, const json& result) {
  details::print_feedback(out, result);
  for (const json& m : result.value("margins", json::array())) {
    out << "  on " << m.value("response", std::string("?")) << ": crossover "
        << fixed_or_dash(m.value("crossover_hz", json()), 0) << " Hz, gain margin "
        << fixed_or_dash(m.value("gain_margin_db", json()), 1) << " dB at "
        << fixed_or_dash(m.value("gain_margin_hz", json()), 0) << " Hz, phase margin "
        << fixed_or_dash(m.value("phase_margin_deg", json()), 1) << " deg, peak |S| "
        << fixed_or_dash(m.value("peak_sensitivity_db", json()), 1) << " dB at "
        << fixed_or_dash(m.value("peak_sensitivity_hz", json()), 0) << " Hz"
        << (m.value("stable", false) ? "" : ", UNSTABLE") << "\n";
  }
  for (const auto& png : result.value("plots", json::array())) {
    out << "  plot            " << png.get<std::string>() << "\n";
  }
}

// --plot: a loop's pictures in dir (on a stage, each axis's in dir/AXIS); false on failure.
bool plot_tune(json& design, const std::filesystem::path& dir, std::ostream& err) {
  try {
    json files = json::array();
    for (const auto& png : plot_loop(design, dir)) files.push_back(png.string());
    design["plots"] = files;
    return true;
  } catch (const std::exception& e) {
    err << "hystbench: error: --plot: " << e.what() << "\n";
    return false;
  }
}

int print_tune(const RemoteCommand& cmd, json& result, std::ostream& out, std::ostream& err) {
  int status = 0;
  const bool stage = result.contains("axes") && result["axes"].is_object();
  if (!cmd.plot_dir.empty()) {
    if (stage) {
      for (auto& [axis, design] : result["axes"].items()) {
        if (!plot_tune(design, std::filesystem::path(cmd.plot_dir) / axis, err)) status = 1;
      }
    } else if (!plot_tune(result, cmd.plot_dir, err)) {
      status = 1;
    }
  }
  if (cmd.json_output) {
    out << result.dump() << "\n";
  } else {
    print_tune_result(result, out);
  }
  return status;
}

}  // namespace

void print_tune_result(const json& result, std::ostream& out) {
  if (!result.contains("axes") || !result["axes"].is_object()) {
    out << "tune " << result.value("compensator", std::string("?")) << " on the responses of "
        << result.value("responses_from", std::string("?")) << "\n";
    print_loop_design(out, result);
    return;
  }
  out << "tune " << result.value("compensator", std::string("?")) << " on each axis of the stage\n";
  for (const auto& [axis, design] : result["axes"].items()) {
    out << "axis " << axis << " (responses of " << design.value("responses_from", std::string("?"))
        << ")\n";
    print_loop_design(out, design);
  }
  const json& together = result.value("feedback_interaction", json());
  if (together.is_object()) {
    out << "the loops together through the coupling: " << fixed(together.value("peak", 0.0), 2)
        << " at " << fixed(together.value("peak_hz", 0.0), 0) << " Hz ("
        << (together.value("dominant", false) ? "below 1: stable together" : "NOT below 1") << ")";
    const json& designed = together.value("designed_together", json());
    if (designed.is_object() && designed.value("lowered_by", 1.0) < 1.0) {
      out << "; each loop lowered by " << fixed(designed.value("lowered_by", 1.0), 2) << " from "
          << fixed(designed.value("peak_alone", 0.0), 2);
    }
    out << "\n";
  }
}

int run_remote(const RemoteCommand& cmd, std::ostream& out, std::ostream& err) {
  try {
    BenchClient client(cmd.socket_path);
    const bool tty = ::isatty(STDERR_FILENO) == 1;
    if (cmd.cmd == "track" && cmd.wait && !cmd.params.contains("kp") &&
        !cmd.params.contains("ki") && !cmd.params.contains("kd") &&
        !measure_response_if_missing(client, cmd.params.value("compensator", ""), err)) {
      return 1;
    }
    json reply;
    try {
      reply = request_command(client, cmd, tty, err);
    } catch (const common::CommandError& e) {
      report_refusal(cmd, e, out, err);
      return 1;
    } catch (const UnreadableInput& e) {
      err << "hystbench: error: " << e.what() << "\n";
      return 1;
    }
    json result = reply["result"];
    const bool is_run =
        cmd.cmd == "identify" || cmd.cmd == "track" || cmd.cmd == "excite" || cmd.cmd == "frf";
    if (cmd.cmd == "tune") return print_tune(cmd, result, out, err);
    if (!(is_run && cmd.wait)) {
      if (cmd.json_output || !is_run) {
        out << (cmd.json_output ? result.dump() : result.dump(2)) << "\n";
      } else {
        out << "started " << result.value("run_id", "?") << " ("
            << fixed(result.value("duration_s", 0.0), 1) << " s), log " << result.value("log", "?")
            << "\n";
      }
      return 0;
    }
    const std::string run_id = result.value("run_id", "");
    std::function<void(double, const std::string&)> show;
    if (tty && !cmd.json_output) {
      show = [&](double f, const std::string& what) {
        progress_bar(err, f, what.empty() ? cmd.cmd + " " + run_id : what);
      };
    }
    json r = wait_for_run(client, run_id, show);
    if (show) err << "\r\x1b[K" << std::flush;
    int status = r.value("end", "") == "completed" && !r.contains("fit_error") ? 0 : 1;
    if (!cmd.plot_dir.empty() && !r.value("log", std::string()).empty() && !plot_run(cmd, r, err)) {
      status = 1;
    }
    if (cmd.json_output) {
      out << r.dump() << "\n";
    } else {
      print_run_result(r, out);
      for (const auto& png : r.value("plots", json::array())) {
        out << "  plot            " << png.get<std::string>() << "\n";
      }
    }
    return status;
  } catch (const ClientError& e) {
    err << "hystbench: " << e.what() << "\n";
    return 2;
  }
}

}  // namespace hystbench::cli
