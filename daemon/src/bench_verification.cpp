// identify's second half: candidates fitted per family, each verified on the loop by one
// tracking segment through its inverse, the model chosen and reported (Bench members, run on
// the supervisor thread; see identify_session.hpp).
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "details/fit_families.hpp"
#include "hystbench/daemon/inverse_track_program.hpp"
#include "hystbench/daemon/offline_commands.hpp"
#include "identify_session.hpp"

namespace hystbench::daemon {

namespace hc = compensation;
using nlohmann::json;

namespace {

std::string type_name(const hc::FitResult& f) {
  return std::string(hc::to_string(f.model.hysteresis().kind()));
}

// Verified max error [% of the reference span]; +inf when not verified to the end.
double verified_max(const IdentifyCandidate& c) {
  if (c.verification.is_null() || c.verification.value("end", "") != "completed" ||
      !c.verification.contains("max_error_percent")) {
    return INFINITY;
  }
  return c.verification["max_error_percent"].get<double>();
}

json candidate_summary(const IdentifyCandidate& c) {
  return {{"type", type_name(c.fit)},
          {"operators", c.fit.operators},
          {"dead_zones", c.fit.dead_zones},
          {"heldout", to_json(c.fit.heldout)},
          {"verification", c.verification}};
}

}  // namespace

IdentifyCandidate family_candidate(hc::FitResult fit) {
  std::string label = type_name(fit);
  return {std::move(fit), json(), std::move(label)};
}

std::vector<IdentifyCandidate> fit_identify_candidates(std::span<const double> t,
                                                       std::span<const double> u,
                                                       std::span<const double> y,
                                                       const hc::FitOptions& options) {
  std::vector<hc::ModelKind> kinds;
  if (options.kind) {
    kinds = {*options.kind};
  } else {
    kinds.assign(details::fit_families().begin(), details::fit_families().end());
  }
  std::vector<IdentifyCandidate> out;
  std::string errors;
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    hc::FitOptions o = options;
    o.kind = kinds[i];
    o.delay_samples = 0;  // the record is already shifted by the delay chosen in ticks
    if (options.progress) {
      const double begin = static_cast<double>(i) / kinds.size(), span = 1.0 / kinds.size();
      o.progress = [&options, begin, span, kind = kinds[i]](double f, const std::string& what) {
        options.progress(begin + span * f, std::string(hc::to_string(kind)) + ": " + what);
      };
    }
    try {
      out.push_back(family_candidate(hc::fit_model(t, u, y, o)));
    } catch (const std::exception& e) {
      if (kinds.size() == 1) throw;
      errors += std::string(errors.empty() ? "" : "; ") + std::string(hc::to_string(kinds[i])) +
                ": " + e.what();
    }
  }
  if (out.empty()) throw std::runtime_error("no family could be fitted: " + errors);
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.fit.heldout.rmse < b.fit.heldout.rmse;
  });
  return out;
}

void add_dead_zone_neighbour(std::vector<IdentifyCandidate>& candidates, std::span<const double> t,
                             std::span<const double> u, std::span<const double> y,
                             const hc::FitOptions& options) {
  if (!options.kind || options.dead_zones >= 0 || candidates.size() != 1) return;
  const hc::FitResult& chosen = candidates.front().fit;
  if (chosen.dead_zones < 1) return;
  hc::FitOptions o = options;
  o.dead_zones = chosen.dead_zones - 1;
  o.delay_samples = 0;  // the record is already shifted by the delay chosen in ticks
  if (options.progress) {
    o.progress = [&options, m = o.dead_zones](double f, const std::string& what) {
      options.progress(f, std::to_string(m) + " dead zones: " + what);
    };
  }
  try {
    hc::FitResult fit = hc::fit_model(t, u, y, o);
    if (fit.dead_zones != o.dead_zones) return;  // e.g. a fall-back to the classical PI
    const std::string label = type_name(fit) + "-" + std::to_string(fit.dead_zones) + "dz";
    candidates.push_back({std::move(fit), json(), label});
  } catch (const std::exception&) {
    // The chosen order stands alone; its own fit succeeded.
  }
}

bool Bench::verify_next_candidate() {
  IdentifySession& s = *session_;
  const auto& lim = settings_.loop.limits;
  while (s.next < s.candidates.size()) {
    IdentifyCandidate& c = s.candidates[s.next];
    std::unique_ptr<RunProgram> p;
    try {
      VerificationSpec spec;
      spec.precondition_s = settings_.precondition_s;
      spec.feedforward_bandwidth_hz = settings_.feedforward_bandwidth_hz;
      spec.model_exchange_ticks =
          static_cast<std::uint64_t>(std::max(0, s.history.value("exchange_ticks", 0)));
      p = make_verification_program(c.fit.model, spec, loop_->last_output(), lim, dt_);
    } catch (const std::exception& e) {
      c.verification = {{"end", "not_run"}, {"reason", e.what()}};
      ++s.next;
      continue;
    }
    p->run_id = s.result["run_id"].get<std::string>() + "-verify-" + c.label;
    json header = {{"run",
                    {{"kind", "verify"},
                     {"identify_run", s.result["run_id"]},
                     {"reference", "triangle"},
                     {"frequency_hz", 1.0},
                     {"compensator", "inverse"},
                     {"precondition_samples", p->excitation.size()},
                     {"metrics_from", p->metrics_from},
                     {"rate_hz", settings_.loop.rate_hz}}},
                   {"driver", settings_.driver_type},
                   {"model", hc::to_json(hc::ModelFile{c.fit.model, json::object()})}};
    try {
      p->log = open_log(p->run_id, header);
    } catch (const CommandError& e) {
      c.verification = {{"end", "not_run"}, {"reason", e.what()}};
      return false;
    }
    const std::string log = p->log->path().string();
    const std::string program_id = p->run_id;
    const std::uint64_t total = p->total_samples;
    std::lock_guard lock(mutex_);
    if (quit_.load()) {
      p->log->close();
      c.verification = {{"end", "not_run"}, {"reason", "daemon shutting down"}};
      return false;
    }
    if (auto refused = loop_->submit(std::move(p))) {
      refused->log->close();
      c.verification = {{"end", "not_run"}, {"reason", "the loop did not accept the segment"}};
      return false;
    }
    s.program_id = program_id;
    active_run_["stage"] = "verify " + c.label;
    active_run_["total"] = total;
    active_run_["verification_log"] = log;
    finalizing_ = false;  // stop and abort now act on the verification
    return true;
  }
  return false;
}

void Bench::verification_finished(std::unique_ptr<RunProgram> run) {
  IdentifySession& s = *session_;
  {
    std::lock_guard lock(mutex_);
    finalizing_ = true;
    active_run_["stage"] = "choosing the model";
  }
  IdentifyCandidate& c = s.candidates[s.next];
  const SampleLogCounts counts = run->log ? run->log->close() : SampleLogCounts{};
  c.verification = tracking_error_json(*run);
  c.verification["end"] = to_string(run->end);
  c.verification["reason"] = run->end_reason;
  c.verification["log"] = run->log ? run->log->path().string() : "";
  c.verification["dropped"] = counts.dropped + run->log_drops;
  c.verification["clamps"] = run->clamps;
  ++s.next;
  s.interrupted = s.interrupted || run->end != RunEnd::kCompleted;
  if (s.interrupted || quit_.load() || !verify_next_candidate()) finish_identify();
}

void Bench::finish_identify() {
  std::unique_ptr<IdentifySession> session = std::move(session_);
  IdentifySession& s = *session;
  json result = std::move(s.result);
  // The verified figure decides when any candidate was verified; else the held-out error.
  std::size_t chosen = 0;
  for (std::size_t i = 1; i < s.candidates.size(); ++i) {
    if (verified_max(s.candidates[i]) < verified_max(s.candidates[chosen])) chosen = i;
  }
  try {
    IdentifyCandidate& c = s.candidates[chosen];
    hc::FitResult& fit = c.fit;
    fit.model.units = {"V", "um"};
    json candidates = json::array();
    for (const auto& other : s.candidates) candidates.push_back(candidate_summary(other));
    const std::string chosen_by =
        std::isfinite(verified_max(c)) ? "verified tracking max error" : "held-out error";
    hc::ModelFile file{fit.model, json::object()};
    file.identification = {{"run_id", result["run_id"]},
                           {"log", s.log_path},
                           {"samples", s.samples},
                           {"fit_sample_period_s", s.fit_sample_period_s},
                           {"history", s.history},
                           {"method", fit.method},
                           {"operators", fit.operators},
                           {"dead_zones", fit.dead_zones},
                           {"fit", to_json(fit.fit)},
                           {"heldout", to_json(fit.heldout)},
                           {"drift_um_per_s", fit.drift_per_s},
                           {"notes", fit.notes},
                           {"verification", c.verification},
                           {"chosen_by", chosen_by},
                           {"delay_ticks", s.history.value("delay_ticks", 0)},
                           {"exchange_ticks", s.history.value("exchange_ticks", 0)}};
    if (s.candidates.size() > 1) file.identification["candidates"] = candidates;
    std::filesystem::create_directories(settings_.model_dir);
    const std::string path = (std::filesystem::path(settings_.model_dir) /
                              (result["run_id"].get<std::string>() + ".json"))
                                 .string();
    save_model_file(path, file);
    result["model"] = {{"path", path},
                       {"type", type_name(fit)},
                       {"operators", fit.operators},
                       {"dead_zones", fit.dead_zones},
                       {"method", fit.method},
                       {"history", s.history},
                       {"delay_ticks", s.history.value("delay_ticks", 0)},
                       {"exchange_ticks", s.history.value("exchange_ticks", 0)},
                       {"fit", to_json(fit.fit)},
                       {"heldout", to_json(fit.heldout)},
                       {"drift_um_per_s", fit.drift_per_s},
                       {"notes", fit.notes},
                       {"chosen_by", chosen_by}};
    result["verification"] = c.verification;
    if (s.candidates.size() > 1) result["candidates"] = candidates;
    std::lock_guard lock(mutex_);
    model_ = std::move(file);
    model_path_ = path;
  } catch (const std::exception& e) {
    result["fit_error"] = e.what();
  }
  deliver_result(std::move(result));
}

}  // namespace hystbench::daemon
