#include "hystbench/daemon/bench.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>

#include "command_table.hpp"
#include "details/fit_families.hpp"
#include "details/request_params.hpp"
#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/pid_tuning.hpp"
#include "hystbench/compensation/tracking_metrics.hpp"
#include "hystbench/daemon/identification_fit.hpp"
#include "hystbench/daemon/inverse_track_program.hpp"
#include "hystbench/daemon/model_file_io.hpp"
#include "hystbench/sim/identification_excitation.hpp"
#include "identify_session.hpp"
#include "track_reference.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

constexpr std::uint64_t kMaxRecordedSamples = 2'000'000;
/// Largest measurement delay identify looks for [ticks].
constexpr int kMaxDelayTicks = 4;

const char* state_name(BenchLoop::State s) {
  switch (s) {
    case BenchLoop::State::kStopped:
      return "stopped";
    case BenchLoop::State::kIdle:
      return "idle";
    case BenchLoop::State::kRunning:
      return "running";
    case BenchLoop::State::kFault:
      return "fault";
  }
  return "unknown";
}

// What identify did so that the model does not depend on earlier runs (for the result).
json identify_history_json(const json& fit_options) {
  return {{"precondition_sweep_s", fit_options.value("precondition_s", 0.0)},
          {"settle_s", fit_options.value("settle_s", 0.0)},
          {"unscored_samples", fit_options.value("skip_samples", 0)},
          {"note",
           "hold at mid-range (creep), sweep to u_max and u_min (hysteresis memory) before the "
           "excitation; the fit simulates both from the output's last value and scores from "
           "the first major loop on"}};
}

// Ramps linearly from a to b over n samples (b reached on the last one).
void append_ramp(std::vector<double>& out, double a, double b, std::size_t n) {
  for (std::size_t k = 1; k <= n; ++k) out.push_back(a + (b - a) * static_cast<double>(k) / n);
}

}  // namespace

Bench::Bench(BenchSettings settings) : settings_(std::move(settings)) {
  dt_ = 1.0 / settings_.loop.rate_hz;
  try {
    driver_ = drivers::make_driver(settings_.driver_type);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  if (auto r = driver_->configure(settings_.driver_params, settings_.loop.rate_hz); !r) {
    throw std::runtime_error(r.message);
  }
  auto& lim = settings_.loop.limits;
  if (lim.u_min < driver_->output_min_v() || lim.u_max > driver_->output_max_v()) {
    throw std::runtime_error("limits.u_min/u_max [" + std::to_string(lim.u_min) + ", " +
                             std::to_string(lim.u_max) + "] V exceed the driver's output range [" +
                             std::to_string(driver_->output_min_v()) + ", " +
                             std::to_string(driver_->output_max_v()) + "] V");
  }
  if (auto r = driver_->activate(); !r) throw std::runtime_error(r.message);
  loop_ = std::make_unique<BenchLoop>(*driver_, settings_.loop);
}

Bench::~Bench() {
  // A run that cannot be written out at exit (full disk) is logged, not rethrown from here.
  try {
    shutdown();
  } catch (const std::exception& e) {
    spdlog::error("bench shutdown: {}", e.what());
  }
}

RealtimeReport Bench::start() {
  realtime_ = loop_->start();
  supervisor_ = std::thread([this] { supervise(); });
  return realtime_;
}

void Bench::shutdown() {
  if (quit_.exchange(true)) return;
  if (loop_) {
    loop_->request_abort();
    // Give the loop a few ticks to end the run cleanly, then stop it.
    for (int i = 0; i < 200 && loop_->state() == BenchLoop::State::kRunning; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    loop_->shutdown();
  }
  if (supervisor_.joinable()) supervisor_.join();
  if (loop_) {
    if (auto finished = loop_->take_finished()) finalize(std::move(finished));
  }
  if (driver_) {
    driver_->safe_state();
    driver_->deactivate();
  }
}

void Bench::set_event_sink(EventSink sink) {
  std::lock_guard lock(mutex_);
  sink_ = std::move(sink);
}

void Bench::emit(const json& event) {
  EventSink sink;
  {
    std::lock_guard lock(mutex_);
    sink = sink_;
  }
  if (sink) sink(event);
}

bool Bench::loop_advanced() {
  const std::uint64_t t = loop_->ticks();
  const bool advanced = t != watchdog_ticks_;
  watchdog_ticks_ = t;
  return advanced;
}

bool Bench::wait_idle(std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < until) {
    {
      std::lock_guard lock(mutex_);
      if (loop_->state() != BenchLoop::State::kRunning && !finalizing_ && !delivering_result_ &&
          active_run_.is_null()) {
        return true;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

std::string Bench::new_run_id(const char* kind) {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &tm);
  return std::string(stamp) + "-" + kind + "-" + std::to_string(++run_counter_);
}

std::unique_ptr<SampleLogWriter> Bench::open_log(const std::string& run_id, json header) {
  SampleLogOptions opt;
  opt.log_dir = settings_.log_dir;
  opt.run_id = run_id;
  opt.header = std::move(header);
  opt.ring_capacity = settings_.log_ring_capacity;
  try {
    return std::make_unique<SampleLogWriter>(std::move(opt));
  } catch (const std::exception& e) {
    throw CommandError("log_error", std::string("cannot open the run log: ") + e.what());
  }
}

std::uint64_t Bench::model_exchange_ticks() const {
  if (!model_ || !model_->identification.is_object()) return 0;
  return static_cast<std::uint64_t>(
      std::max<std::int64_t>(0, model_->identification.value("exchange_ticks", 0)));
}

std::uint64_t Bench::model_delay_ticks() const {
  if (!model_) return 0;
  const auto total = static_cast<std::int64_t>(std::ceil(model_->model.delay_s() / dt_ - 1e-9));
  // The driver's exchange latency is part of the identified delay, and each reading reports it.
  const auto exchange = static_cast<std::int64_t>(model_exchange_ticks());
  return static_cast<std::uint64_t>(std::max<std::int64_t>(0, total - exchange));
}

std::optional<Bench::ActuatorRange> Bench::actuator_range() const {
  // Caller holds mutex_.
  if (model_) {
    const auto& lim = settings_.loop.limits;
    const ModelOutputRange r = major_loop_range(model_->model, lim.u_min, lim.u_max, dt_);
    return ActuatorRange{r.y_bottom, r.y_top};
  }
  if (settings_.y_max > settings_.y_min) return ActuatorRange{settings_.y_min, settings_.y_max};
  return std::nullopt;
}

std::optional<hc::ActuatorModel> Bench::predictor(double u0) const {
  // Caller holds mutex_.
  std::optional<hc::ActuatorModel> m;
  const auto& lim = settings_.loop.limits;
  if (model_) {
    m = model_->model;
  } else if (settings_.y_max > settings_.y_min && lim.u_max > lim.u_min) {
    // No model yet: the configured range as a straight line, what `none` compensates with.
    const double gain = (settings_.y_max - settings_.y_min) / (lim.u_max - lim.u_min);
    m.emplace(std::make_unique<hc::PiModel>(
        hc::PiParameters{{0.0}, {gain}, settings_.y_min - gain * lim.u_min}));
  } else {
    return std::nullopt;
  }
  m->configure(dt_);
  m->reset(u0);
  return m;
}

const char* Bench::predictor_name() const {
  if (model_) return "the active model, stepped with u";
  if (settings_.y_max > settings_.y_min) return "linear map of limits.y_min..y_max, stepped with u";
  return "none (NaN): no model and no limits.y_min/y_max";
}

json Bench::handle(const std::string& cmd, const json& params, std::uint64_t client) {
  const details::Command& command = details::find_command(cmd, params);
  const details::Request request(params, command.params);
  return command.handle(*this, request, client);
}

json Bench::stop_run() {
  {
    std::lock_guard lock(mutex_);
    // A run submitted but not yet picked up by the loop counts as active.
    if (active_run_.is_null() || finalizing_) throw CommandError("no_run", "no run is active");
  }
  loop_->request_stop();
  return {{"stopping", true}};
}

json Bench::abort_run() {
  bool running = false;
  {
    std::lock_guard lock(mutex_);
    running = !active_run_.is_null() && !finalizing_;
  }
  loop_->request_abort();
  return {{"aborted", running}, {"output_v", driver_->safe_output_v()}};
}

json Bench::reset() {
  const bool was_fault = loop_->state() == BenchLoop::State::kFault;
  if (was_fault && !loop_->reset_fault()) {
    throw CommandError("reset_failed", "the loop did not leave FAULT");
  }
  return {{"was_fault", was_fault}, {"state", state_name(loop_->state())}};
}

json Bench::model_get() const {
  std::lock_guard lock(mutex_);
  if (!model_) throw CommandError("no_model", "no active model (identify or model.load first)");
  return {{"path", model_path_}, {"model", hc::to_json(*model_)}};
}

void Bench::client_closed(std::uint64_t client) { uploads_.drop_client(client); }

json Bench::status() const {
  json s;
  const auto state = loop_->state();
  std::lock_guard lock(mutex_);
  s["state"] = finalizing_ && state == BenchLoop::State::kIdle ? "finalizing" : state_name(state);
  if (state == BenchLoop::State::kFault) s["fault_reason"] = loop_->fault_reason();
  s["output_v"] = loop_->last_output();
  s["position_um"] = loop_->last_measurement();
  if (!active_run_.is_null()) {
    s["run"] = active_run_;
  } else {
    s["run"] = nullptr;
  }
  if (model_) {
    s["model"] = {{"type", std::string(hc::to_string(model_->model.hysteresis().kind()))},
                  {"path", model_path_},
                  {"operators", model_->model.hysteresis().operator_count()}};
  } else {
    s["model"] = nullptr;
  }
  s["loop"] = {{"rate_hz", settings_.loop.rate_hz},
               {"realtime", realtime_.summary(settings_.loop.realtime)},
               {"degraded", realtime_.degraded()},
               {"statistics", to_json(loop_->statistics())}};
  s["driver"] = driver_->diagnostics();
  s["uploads"] = {{"open", uploads_.open()},
                  {"staged_samples", uploads_.staged_samples()},
                  {"max_samples", uploads_.limits().max_samples}};
  s["last_result"] = last_result_;
  return s;
}

namespace {

// A model name in the daemon's model folder: letters, digits, '.', '_', '-', not starting with
// '.', at most 128 characters; ".json" appended when missing. Never a path.
std::string model_file_name(const std::string& key, const std::string& name) {
  const bool ok = !name.empty() && name.size() <= 128 && name.front() != '.' &&
                  std::all_of(name.begin(), name.end(), [](unsigned char c) {
                    return std::isalnum(c) || c == '.' || c == '_' || c == '-';
                  });
  if (!ok) {
    throw CommandError("bad_params", key +
                                         ": a model name (letters, digits, '.', '_', '-'; not a "
                                         "path), as `hystbench model list` shows");
  }
  const bool has_json = name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0;
  return has_json ? name : name + ".json";
}

}  // namespace

nlohmann::json Bench::load_model(const details::Request& request) {
  const bool stored = request.has("stored");
  const bool document = request.has("model");
  if (stored == document) {
    throw CommandError("bad_params",
                       "give either 'model' (the model document) or 'stored' (a name from "
                       "model.list)");
  }
  // Checked first: a refused request changes nothing (an upload is not kept either).
  std::lock_guard lock(mutex_);
  if (!active_run_.is_null())
    throw CommandError("busy", "a run is active; load the model after it");
  const std::filesystem::path dir(settings_.model_dir);
  hc::ModelFile file;
  std::filesystem::path path;
  if (stored) {
    const std::string name = model_file_name("stored", request.string("stored", ""));
    path = dir / name;
    if (!std::filesystem::is_regular_file(std::filesystem::symlink_status(path))) {
      throw CommandError("bad_params", "stored: no model '" + name +
                                           "' in the daemon's model folder (hystbench model list)");
    }
    try {
      file = load_model_file(path.string());
    } catch (const std::exception& e) {
      throw CommandError("bad_model", e.what());
    }
  } else {
    const std::string name = model_file_name("name", request.string("name", "uploaded"));
    try {
      file = hc::model_file_from_json(request.params()["model"]);
    } catch (const std::exception& e) {
      throw CommandError("bad_model", std::string("model: ") + e.what());
    }
    // Kept in the model folder: `model load --stored` after a restart, and `model list`.
    path = dir / name;
    try {
      std::filesystem::create_directories(dir);
      save_model_file(path.string(), file);
    } catch (const std::exception& e) {
      throw CommandError("io_error",
                         "cannot keep the model in the model folder: " + std::string(e.what()));
    }
  }
  const auto inv = file.model.hysteresis().invertibility();
  model_ = std::move(file);
  model_path_ = path.string();
  return {{"path", model_path_},
          {"name", path.filename().string()},
          {"type", std::string(hc::to_string(model_->model.hysteresis().kind()))},
          {"invertible", inv.invertible},
          {"reason", inv.reason}};
}

nlohmann::json Bench::list_models() const {
  std::lock_guard lock(mutex_);
  json models = json::array();
  std::error_code ec;
  const std::filesystem::path dir(settings_.model_dir);
  std::vector<std::filesystem::directory_entry> entries;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.is_regular_file() && e.path().extension() == ".json") entries.push_back(e);
  }
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.path().filename() < b.path().filename(); });
  for (const auto& e : entries) {
    json m = {{"name", e.path().filename().string()}, {"bytes", e.file_size()}};
    try {
      const hc::ModelFile f = load_model_file(e.path().string());
      m["type"] = std::string(hc::to_string(f.model.hysteresis().kind()));
      m["operators"] = f.model.hysteresis().operator_count();
    } catch (const std::exception&) {
      m["type"] = "unreadable";  // never the file's text
    }
    m["active"] = e.path().string() == model_path_;
    models.push_back(std::move(m));
  }
  return {{"folder", dir.string()}, {"models", models}};
}

void Bench::require_idle() const {
  if (loop_->state() == BenchLoop::State::kFault) {
    throw CommandError("fault", std::string("the bench is in FAULT (") + loop_->fault_reason() +
                                    "); send reset first");
  }
  if (!active_run_.is_null() || finalizing_) throw CommandError("busy", "a run is active");
}

Bench::SubmittedRun Bench::submit_run(std::unique_ptr<RunProgram> p, const json& header) {
  p->log = open_log(p->run_id, header);
  SubmittedRun s{p->run_id, p->log->path().string(), p->total_samples};
  if (auto refused = loop_->submit(std::move(p))) {
    refused->log->close();
    throw CommandError("busy", "the loop did not accept the run");
  }
  return s;
}

json Bench::start_identify(const details::Request& request) {
  const auto& lim = settings_.loop.limits;
  const std::string model = request.string("model", settings_.identify_model);
  if (!details::is_fit_family(model)) {
    throw CommandError("bad_params",
                       "model: unknown '" + model + "' (" + details::fit_family_names() + ")");
  }
  const int operators = request.integer("operators", settings_.identify_operators);
  const int dead_zones = request.integer("dead_zones", settings_.identify_dead_zones);
  const double u_lo = request.number(
      "u_min", std::isnan(settings_.identify_u_min) ? lim.u_min : settings_.identify_u_min,
      lim.u_min, lim.u_max);
  const double u_hi = request.number(
      "u_max", std::isnan(settings_.identify_u_max) ? lim.u_max : settings_.identify_u_max,
      lim.u_min, lim.u_max);
  if (!(u_hi > u_lo)) throw CommandError("bad_params", "u_max must be greater than u_min");

  std::lock_guard lock(mutex_);
  require_idle();

  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kIdentify;
  p->response_delay_ticks = model_delay_ticks();
  p->run_id = new_run_id("identify");
  sim::Excitation exc;
  try {
    sim::IdentificationExcitationOptions options = settings_.identify_excitation;
    options.major_loop_frequency_hz = settings_.identify_major_loop_hz;
    options.major_loop_cycles = settings_.identify_major_loop_cycles;
    options.precondition_s = settings_.identify_precondition_s;
    options.settle_s = settings_.identify_settle_s;
    options.reversals_last = true;  // the held-out end of the record: loop shape, not creep
    exc = sim::identification_excitation(u_lo, u_hi, dt_, options);
  } catch (const std::exception& e) {
    throw CommandError("bad_params", e.what());
  }
  // Start from where the output is: a short ramp to the excitation's first value.
  const double u_now = loop_->last_output();
  append_ramp(p->excitation, u_now, exc.samples.front(),
              static_cast<std::size_t>(std::ceil(0.1 / dt_)));
  p->model = predictor(u_now);
  const std::size_t offset = p->excitation.size();
  p->excitation.insert(p->excitation.end(), exc.samples.begin(), exc.samples.end());
  p->total_samples = p->excitation.size();
  // Recorded from the first sample: the fit simulates the ramp, settle and sweep from
  // where the output was, so its model enters the scored part in the actuator's state.
  p->metrics_from = 0;
  p->record_capacity = std::min<std::uint64_t>(p->total_samples, kMaxRecordedSamples);
  p->rec_u.resize(p->record_capacity);
  p->rec_y.resize(p->record_capacity);
  p->rec_yr.resize(p->record_capacity);
  p->rec_response.resize(p->record_capacity);
  json segments = json::array();
  for (const auto& s : exc.segments) {
    segments.push_back({{"name", s.name}, {"begin", s.begin + offset}, {"end", s.end + offset}});
  }
  json header = {{"run",
                  {{"kind", "identify"},
                   {"model", model},
                   {"operators", operators},
                   {"dead_zones", dead_zones},
                   {"u_min", u_lo},
                   {"u_max", u_hi},
                   {"rate_hz", settings_.loop.rate_hz},
                   {"segments", segments}}},
                 {"driver", settings_.driver_type},
                 {"y_model", predictor_name()}};
  const auto [run_id, log_path, total] = submit_run(std::move(p), header);
  active_run_ = {{"run_id", run_id}, {"kind", "identify"}, {"total", total}, {"log", log_path}};
  pending_identify_model_ = model;
  const sim::ExcitationSegment* first_scored = exc.find("major_loop");
  pending_identify_options_ = {
      {"operators", operators},
      {"dead_zones", dead_zones},
      {"skip_samples", offset + (first_scored != nullptr ? first_scored->begin : 0)},
      {"precondition_s", settings_.identify_precondition_s},
      {"settle_s", settings_.identify_settle_s}};
  return {{"run_id", run_id},
          {"samples", total},
          {"duration_s", static_cast<double>(total) * dt_},
          {"log", log_path}};
}

json Bench::start_excite(const details::Request& request, std::uint64_t client) {
  const auto& lim = settings_.loop.limits;
  if (!request.has("drive_upload")) {
    throw CommandError("bad_params", "drive_upload: missing (the name of a complete drive upload)");
  }
  const std::string upload_name = request.string("drive_upload", "");

  std::lock_guard lock(mutex_);
  require_idle();
  const auto upload = uploads_.complete(upload_name, client, UploadKind::kDrive);
  const std::vector<double> drive =
      details::checked_drive(*upload, lim.u_min, lim.u_max, lim.slew_v_per_s, dt_);

  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kExcite;
  p->response_delay_ticks = model_delay_ticks();
  p->run_id = new_run_id("excite");
  // From where the output is to the drive's first value within the slew limit (at least 0.1 s),
  // logged like the rest: the record starts from a known output.
  const double u_now = loop_->last_output();
  const double ramp_s = std::max(0.1, 2.0 * std::abs(drive.front() - u_now) / lim.slew_v_per_s);
  append_ramp(p->excitation, u_now, drive.front(),
              static_cast<std::size_t>(std::ceil(ramp_s / dt_)));
  const std::size_t offset = p->excitation.size();
  p->excitation.insert(p->excitation.end(), drive.begin(), drive.end());
  p->model = predictor(u_now);
  p->total_samples = p->excitation.size();
  p->metrics_from = offset;
  p->record_capacity =
      std::min<std::uint64_t>(p->total_samples - p->metrics_from, kMaxRecordedSamples);
  p->rec_u.resize(p->record_capacity);
  p->rec_y.resize(p->record_capacity);
  p->rec_yr.resize(p->record_capacity);
  json header = {{"run",
                  {{"kind", "excite"},
                   {"source", upload->source},
                   {"upload_samples", upload->values.size()},
                   {"ramp_samples", offset},
                   {"metrics_from", p->metrics_from},
                   {"u_min", *std::min_element(drive.begin(), drive.end())},
                   {"u_max", *std::max_element(drive.begin(), drive.end())},
                   {"rate_hz", settings_.loop.rate_hz}}},
                 {"driver", settings_.driver_type},
                 {"y_model", predictor_name()},
                 {"model", model_ ? hc::to_json(*model_) : json(nullptr)}};
  const auto [run_id, log_path, total] = submit_run(std::move(p), header);
  uploads_.erase(upload_name, client);  // the run has it now
  active_run_ = {{"run_id", run_id}, {"kind", "excite"}, {"total", total}, {"log", log_path}};
  return {{"run_id", run_id},
          {"samples", total},
          {"drive_samples", drive.size()},
          {"ramp_samples", offset},
          {"duration_s", static_cast<double>(total) * dt_},
          {"log", log_path}};
}

json Bench::start_track(const details::Request& request, std::uint64_t client) {
  const bool uploaded = request.has("reference_upload");
  const auto& lim = settings_.loop.limits;
  const double precondition = request.number("precondition_s", settings_.precondition_s);
  const double approach = uploaded ? request.number("approach_s", 0.2) : 0.2;

  std::lock_guard lock(mutex_);
  require_idle();
  const std::string comp_name = request.string("compensator", model_ ? "inverse" : "none");
  const auto kind = hc::compensator_kind_from_string(comp_name);
  if (!kind) {
    throw CommandError("bad_params",
                       "compensator: unknown '" + comp_name +
                           "' (none, inverse, inverse_multiplicative, inverse+pid, pid)");
  }
  if (hc::needs_model(*kind) && !model_) {
    throw CommandError("no_model", "compensator '" + comp_name +
                                       "' needs a model: run identify or model.load first");
  }
  const auto range = actuator_range();
  if (!range) {
    throw CommandError("no_range",
                       "the actuator range is unknown: identify or load a model, or set "
                       "limits.y_min and limits.y_max");
  }
  const double span = range->y_top - range->y_bottom;
  const details::ReferenceLimits ref_limits{range->y_bottom, range->y_top,
                                            lim.slew_v_per_s * span / (lim.u_max - lim.u_min),
                                            settings_.loop.rate_hz};
  std::string upload_name;
  details::TrackReference ref;
  if (uploaded) {
    upload_name = request.string("reference_upload", "");
    const auto upload = uploads_.complete(upload_name, client, UploadKind::kReference);
    // The precondition sweep leaves the output at the bottom of its range.
    ref = details::uploaded_reference(*upload, ref_limits, range->y_bottom, approach);
  } else {
    ref = details::builtin_reference(request, ref_limits);
  }

  auto p = std::make_unique<RunProgram>();
  p->kind = RunKind::kTrack;
  p->response_delay_ticks = model_delay_ticks();
  p->run_id = new_run_id("track");
  p->reference = std::move(ref.signal);
  // Pre-conditioning: current output -> u_max -> u_min, open loop.
  p->excitation = precondition_sweep(loop_->last_output(), lim.u_min, lim.u_max, precondition, dt_);
  std::unique_ptr<hc::InverseModel> inverse;
  hc::LinearMap linear{span / (lim.u_max - lim.u_min),
                       range->y_bottom - span / (lim.u_max - lim.u_min) * lim.u_min};
  if (model_) {
    const hc::ActuatorModel m =
        model_after(model_->model, p->excitation, loop_->last_output(), lim.u_min, lim.u_max, dt_);
    if (hc::needs_model(*kind)) {
      try {
        inverse = hc::make_inverse(m, *kind == hc::CompensatorKind::kInverseMultiplicative
                                          ? hc::InverseKind::kMultiplicative
                                          : hc::InverseKind::kAuto);
      } catch (const hc::NotInvertibleError& e) {
        throw CommandError("not_invertible", e.what());
      } catch (const std::exception& e) {
        throw CommandError("bad_model", e.what());
      }
    }
  }
  std::optional<hc::PidController> pid;
  json feedback = nullptr;
  if (hc::uses_feedback(*kind)) {
    hc::PidParameters pp = settings_.pid;
    const bool given = request.has("kp") || request.has("ki") || request.has("kd");
    if (settings_.pid_derived && !given) {
      const hc::ActuatorModel* m = model_ ? &model_->model : nullptr;
      const hc::PidTuning t =
          hc::tune_pid(linear.gain, settings_.loop.rate_hz, settings_.pid_bandwidth_hz, m);
      pp.kp = t.kp;
      pp.ki = t.ki;
      pp.kd = t.kd;
      pp.output_filter_hz = settings_.pid_output_filter_hz.value_or(t.output_filter_hz);
      feedback = {{"gains", "derived"}, {"basis", t.basis}};
    } else {
      pp.kp = request.number("kp", pp.kp);
      pp.ki = request.number("ki", pp.ki);
      pp.kd = request.number("kd", pp.kd);
      feedback = {{"gains", given ? "request" : "config"}};
    }
    if (*kind == hc::CompensatorKind::kPid) {
      pp.output_min = lim.u_min;
      pp.output_max = lim.u_max;
    }
    try {
      pid.emplace(pp, dt_);
    } catch (const std::exception& e) {
      throw CommandError("bad_params", e.what());
    }
    feedback.update({{"kp", pp.kp},
                     {"ki", pp.ki},
                     {"kd", pp.kd},
                     {"output_filter_hz", pp.output_filter_hz},
                     {"u_fb_min", pp.output_min},
                     {"u_fb_max", pp.output_max}});
  }
  try {
    p->compensator.emplace(*kind, std::move(inverse), pid, linear);
  } catch (const std::exception& e) {
    throw CommandError("bad_params", e.what());
  }
  if (*kind == hc::CompensatorKind::kPid) {
    p->compensator->reset(p->excitation.empty() ? loop_->last_output() : p->excitation.back());
  }
  p->model = predictor(p->excitation.empty() ? loop_->last_output() : p->excitation.front());
  p->summary = {{"compensator", comp_name}};
  if (model_ && hc::needs_model(*kind)) {
    // The feedforward inverts the whole model: hysteresis, creep and rate in the static inverse,
    // the delay and dynamics from the previewed reference.
    const hc::DynamicsInversion inversion(model_->model, dt_, settings_.feedforward_bandwidth_hz);
    json inverted = json::array({"hysteresis"});
    if (model_->model.creep()) inverted.push_back("creep");
    if (model_->model.hysteresis().kind() == hc::ModelKind::kRateDependentPi) {
      inverted.push_back("rate");
    }
    if (model_->model.delay_samples() > 0 || model_->model.delay_s() > 0.0)
      inverted.push_back("delay");
    if (model_->model.dynamics()) inverted.push_back("dynamics");
    p->summary["feedforward"] = {{"inverted", inverted},
                                 {"preview_samples", inversion.preview_samples()},
                                 {"bandwidth_hz", inversion.bandwidth_hz()},
                                 {"how", inversion.describe()}};
    if (inversion.active()) p->preview = inversion;
    arm_tare(*p, model_exchange_ticks());
  }
  if (!feedback.is_null()) p->summary["feedback"] = feedback;
  const std::uint64_t prefix = p->excitation.size();
  p->total_samples = prefix + ref.samples;
  p->metrics_from = prefix + ref.unscored;
  p->y_ref_min = range->y_bottom;
  p->y_ref_max = range->y_top;
  p->record_capacity =
      std::min<std::uint64_t>(p->total_samples - p->metrics_from, kMaxRecordedSamples);
  p->rec_u.resize(p->record_capacity);
  p->rec_y.resize(p->record_capacity);
  p->rec_yr.resize(p->record_capacity);
  json run_header = {{"kind", "track"}};
  run_header.update(ref.header);
  run_header.update({{"compensator", comp_name},
                     {"precondition_samples", prefix},
                     {"metrics_from", p->metrics_from},
                     {"rate_hz", settings_.loop.rate_hz},
                     {"feedback", feedback}});
  json header = {{"run", run_header},
                 {"driver", settings_.driver_type},
                 {"y_model", predictor_name()},
                 {"model", model_ ? hc::to_json(*model_) : json(nullptr)}};
  const json p_summary_feedforward = p->summary.value("feedforward", json(nullptr));
  const auto [run_id, log_path, total] = submit_run(std::move(p), header);
  if (uploaded) uploads_.erase(upload_name, client);  // the run has it now
  active_run_ = {{"run_id", run_id},
                 {"kind", "track"},
                 {"total", total},
                 {"log", log_path},
                 {"compensator", comp_name}};
  return {{"run_id", run_id},
          {"samples", total},
          {"duration_s", static_cast<double>(total) * dt_},
          {"reference", ref.reply},
          {"compensator", comp_name},
          {"feedback", feedback},
          {"feedforward", p_summary_feedforward},
          {"log", log_path}};
}

void Bench::supervise() {
  auto last_progress = std::chrono::steady_clock::now();
  while (!quit_.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (auto finished = loop_->take_finished()) {
      finalize(std::move(finished));
      continue;
    }
    const auto now = std::chrono::steady_clock::now();
    if (now - last_progress >= std::chrono::milliseconds(500)) {
      last_progress = now;
      json run;
      {
        std::lock_guard lock(mutex_);
        run = active_run_;
      }
      const RunProgram* p = loop_->active();
      if (!run.is_null() && p != nullptr) {
        const auto done = p->done.load(std::memory_order_acquire);
        const auto total = run["total"].get<std::uint64_t>();
        json event = {{"event", "run.progress"},
                      {"run_id", run["run_id"]},
                      {"kind", run["kind"]},
                      {"done", done},
                      {"total", total},
                      {"fraction", total ? static_cast<double>(done) / total : 0.0}};
        if (run.contains("stage")) event["stage"] = run["stage"];  // identify's verification
        emit(event);
      }
    }
  }
}

void Bench::finalize(std::unique_ptr<RunProgram> run) {
  if (session_ && run->run_id == session_->program_id) {
    verification_finished(std::move(run));
    return;
  }
  {
    std::lock_guard lock(mutex_);
    finalizing_ = true;
  }
  SampleLogCounts counts;
  std::string log_path;
  if (run->log) {
    log_path = run->log->path().string();
    counts = run->log->close();
  }
  json result = {{"run_id", run->run_id},
                 {"kind", to_string(run->kind)},
                 {"end", to_string(run->end)},
                 {"reason", run->end_reason},
                 {"samples", run->done.load()},
                 {"planned_samples", run->total_samples},
                 {"logged", counts.written},
                 {"dropped", counts.dropped + run->log_drops},
                 {"log", log_path},
                 {"loop", to_json(run->stats.snapshot())},
                 {"overruns", run->overruns},
                 {"clamps", run->clamps},
                 {"slew_limits", run->slew_limits},
                 {"reference_clips", run->reference_clips},
                 {"stale_reads", run->stale_reads},
                 {"output_v_after", loop_->last_output()}};
  if (!counts.error.empty()) result["log_error"] = counts.error;
  result.update(run->summary);
  const std::size_t n = run->recorded;
  if (run->kind == RunKind::kTrack) result.update(tracking_error_json(*run));
  if (run->model_error_samples > 0 && n > 2) {
    // The simulation's error on the bench: y - y_model over the scored samples, in µm and in %
    // of the output range the run covered (the reference's for a tracking run).
    const auto [lo, hi] = std::minmax_element(run->rec_y.begin(), run->rec_y.begin() + n);
    const double range = result.contains("range_um") ? result["range_um"].get<double>() : *hi - *lo;
    const double rms = std::sqrt(run->model_error_sum2 / run->model_error_samples);
    result["model_rms_error_um"] = rms;
    result["model_max_error_um"] = run->model_error_max;
    result["model_rms_error_percent"] = range > 0 ? 100.0 * rms / range : 0.0;
    result["model_max_error_percent"] = range > 0 ? 100.0 * run->model_error_max / range : 0.0;
  }
  std::string fit_model_name;
  json fit_options;
  {
    std::lock_guard lock(mutex_);
    fit_model_name = pending_identify_model_;
    fit_options = pending_identify_options_;
  }
  if (run->kind == RunKind::kIdentify && run->end == RunEnd::kCompleted && n > 100) {
    try {
      // Block-average down to the fit rate: the hysteresis is rate independent and the fit's
      // cost grows with the sample count. The input delay is chosen in ticks before averaging.
      const std::size_t block = std::max<std::size_t>(
          1, static_cast<std::size_t>(
                 std::floor(settings_.loop.rate_hz / settings_.identify_fit_rate_hz)));
      hc::FitOptions opt;
      opt.kind = details::parse_fit_family(fit_model_name);
      opt.operators = fit_options.value("operators", 0);
      opt.dead_zones = fit_options.value("dead_zones", -1);
      opt.heldout_fraction = settings_.identify_heldout_fraction;
      // A bench has a history: the creep of earlier runs still settles during the record (tens of
      // seconds), as a slow drift the fit would otherwise bend the hysteresis to.
      opt.drift = true;
      // The ramp, the settle hold and the precondition sweep are simulated, not scored.
      const std::size_t skip = fit_options.value("skip_samples", std::size_t{0});
      opt.skip_samples = (skip + block - 1) / block;
      const std::string run_id = run->run_id;
      opt.progress = [this, run_id](double f, const std::string& what) {
        emit({{"event", "fit.progress"}, {"run_id", run_id}, {"fraction", f}, {"stage", what}});
      };
      // The measurement delay in whole ticks: the driver's exchange latency from the readings,
      // then any further delay by held-out error, chosen with the requested family (mpi for
      // auto). The model keeps it; the feedforward previews the reference by it.
      const std::span<const double> u_rec(run->rec_u.data(), n), y_rec(run->rec_y.data(), n);
      const std::span<const std::uint32_t> response(run->rec_response.data(),
                                                    std::min(n, run->rec_response.size()));
      hc::FitOptions delay_opt = opt;
      if (!delay_opt.kind) {
        delay_opt.kind = hc::ModelKind::kModifiedPi;
        delay_opt.progress = nullptr;  // auto: the candidates' fits report progress
      }
      const IdentificationFit id =
          fit_identification_record(u_rec, y_rec, response, dt_, block, delay_opt, kMaxDelayTicks);
      const std::vector<double> aligned = response.empty()
                                              ? std::vector<double>(y_rec.begin(), y_rec.end())
                                              : align_to_outputs(u_rec, y_rec, response);
      const AveragedRecord rec = block_average(
          u_rec, aligned, dt_, block, static_cast<std::size_t>(id.delay_ticks - id.exchange_ticks));
      // Each candidate (one family, or every family for auto) is verified on the loop by a
      // tracking segment through its inverse before one is adopted and run.finished goes out.
      auto session = std::make_unique<IdentifySession>();
      if (opt.kind) {
        // One family: the delay search's fit at the chosen delay is that family's fit.
        session->candidates.push_back(family_candidate(id.fit));
        add_dead_zone_neighbour(session->candidates, rec.t, rec.u, rec.y, opt);
      } else {
        session->candidates = fit_identify_candidates(rec.t, rec.u, rec.y, opt);
      }
      for (IdentifyCandidate& c : session->candidates) {
        c.fit.delay_samples = id.delay_ticks;
        c.fit.model.set_delay(static_cast<double>(id.delay_ticks) * dt_);
      }
      session->log_path = log_path;
      session->samples = n;
      session->fit_sample_period_s = static_cast<double>(block) * dt_;
      session->history = identify_history_json(fit_options);
      session->history["delay_ticks"] = id.delay_ticks;
      session->history["exchange_ticks"] = id.exchange_ticks;
      session->history["delay_note"] = id.delay_note;
      session->result = result;
      session_ = std::move(session);
      if (!verify_next_candidate()) finish_identify();
      return;
    } catch (const std::exception& e) {
      result["fit_error"] = e.what();
    }
  }
  deliver_result(std::move(result));
}

void Bench::deliver_result(json result) {
  {
    std::lock_guard lock(mutex_);
    last_result_ = result;
    active_run_ = nullptr;
    finalizing_ = false;
    delivering_result_ = true;
  }
  // Clients may start the next run as soon as they see this event, so the bench is idle before
  // it goes out; wait_idle() still waits for it, or a caller could read the previous result.
  emit({{"event", "run.finished"}, {"result", result}});
  std::lock_guard lock(mutex_);
  delivering_result_ = false;
}

}  // namespace hystbench::daemon
