#include "service/details/run_history.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/model_file_io.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"
#include "loop/details/utc_clock.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {

constexpr std::string_view kSuffix = ".result.json";

json finite_number(const json& object, const char* key) {
  if (!object.is_object()) return nullptr;
  const auto it = object.find(key);
  return it != object.end() && it->is_number() && std::isfinite(it->get<double>()) ? *it
                                                                                   : json(nullptr);
}

// The worst of a stage's axes' `key` (holder["axes"][axis][key]); null when none has it.
json worst_axis(const json& holder, const char* key) {
  json worst = nullptr;
  const auto axes = holder.is_object() ? holder.find("axes") : holder.end();
  if (axes == holder.end() || !axes->is_object()) return worst;
  for (const auto& [name, axis] : axes->items()) {
    json e = finite_number(axis, key);
    if (!e.is_null() && (worst.is_null() || e.get<double>() > worst.get<double>())) worst = e;
  }
  return worst;
}

// The figure a list shows for a run, the first there is of: its tracking error (a stage's worst
// axis's); identify's verification through its model (a stage identify's worst held-out fit);
// the model's error on the run (excite), where a model predicted it (y_model_from).
// Identify's own model error is not one: it is the previous model's, or the straight line's
// before any; nor is an excite's before any model (the straight line of the limits).
json headline_error(const json& result) {
  if (json e = finite_number(result, "rms_error_percent"); !e.is_null()) return e;
  if (json e = worst_axis(result, "rms_error_percent"); !e.is_null()) return e;
  if (const auto v = result.find("verification"); v != result.end()) {
    if (json e = finite_number(*v, "rms_error_percent"); !e.is_null()) return e;
  }
  if (const auto stage_model = result.find("stage_model"); stage_model != result.end()) {
    if (json e = worst_axis(*stage_model, "heldout_rms_error_percent"); !e.is_null()) return e;
  }
  if (result.value("kind", "") == "identify") return nullptr;
  const bool model_predicted = result.value("y_model_from", "") == "model";
  return model_predicted ? finite_number(result, "model_rms_error_percent") : json(nullptr);
}

json string_or_null(const json& result, const char* key) {
  const auto it = result.find(key);
  return it != result.end() && it->is_string() && !it->get<std::string>().empty() ? *it
                                                                                  : json(nullptr);
}

}  // namespace

RunHistory::RunHistory(std::filesystem::path folder, std::size_t max_runs, std::size_t max_faults)
    : folder_(std::move(folder)), max_runs_(max_runs), max_faults_(max_faults) {
  if (max_runs == 0 || max_faults == 0) {
    throw std::invalid_argument("run history: keeps at least one run and one fault");
  }
  if (!folder_.empty()) read_folder();
}

void RunHistory::read_folder() {
  std::error_code ec;
  std::vector<std::pair<std::filesystem::file_time_type, std::filesystem::path>> files;
  for (const auto& entry : std::filesystem::directory_iterator(folder_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > kSuffix.size() && name.ends_with(kSuffix)) {
      files.emplace_back(entry.last_write_time(ec), entry.path());
    }
  }
  // The newest max_runs results, read newest first; kept oldest first, so that each keep() puts
  // the newer in front.
  std::sort(files.rbegin(), files.rend());
  std::vector<json> docs;
  for (std::size_t i = 0; i < files.size() && docs.size() < max_runs_; ++i) {
    std::ifstream in(files[i].second);
    json doc = json::parse(in, nullptr, false);
    if (doc.is_discarded() || !doc.is_object() || !doc.contains("result") ||
        !doc["result"].is_object() || !doc.value("finished", json()).is_string()) {
      spdlog::warn("run history: {} is not a run's result; skipped", files[i].second.string());
      continue;
    }
    docs.push_back(std::move(doc));
  }
  for (auto it = docs.rbegin(); it != docs.rend(); ++it) {
    keep((*it)["result"], (*it)["finished"].get<std::string>());
  }
}

void RunHistory::add(const json& result) {
  const std::string finished = utc_now_iso8601();
  {
    std::lock_guard lock(mutex_);
    keep(result, finished);
  }
  const std::string run_id = result.value("run_id", "");
  if (folder_.empty() || !valid_sample_log_id(run_id)) return;
  try {
    std::filesystem::create_directories(folder_);
    common::save_json_document((folder_ / (run_id + std::string(kSuffix))).string(),
                               {{"finished", finished}, {"result", result}});
  } catch (const std::exception& e) {
    spdlog::warn("run history: the result of {} is not kept across a restart: {}", run_id,
                 e.what());
  }
}

void RunHistory::keep(const json& result, const std::string& finished) {
  json summary = {{"run_id", result.value("run_id", "")},
                  {"kind", result.value("kind", "")},
                  {"end", result.value("end", "")},
                  {"reason", result.value("reason", "")},
                  {"finished", finished},
                  {"rms_error_percent", headline_error(result)},
                  {"log", string_or_null(result, "log")}};
  if (summary["end"] == "fault") {
    faults_.push_front({{"time", finished},
                        {"run_id", summary["run_id"]},
                        {"kind", summary["kind"]},
                        {"reason", summary["reason"]}});
    if (faults_.size() > max_faults_) faults_.pop_back();
  }
  runs_.push_front({std::move(summary), result});
  if (runs_.size() > max_runs_) runs_.pop_back();
}

json RunHistory::runs() const {
  json list = json::array();
  std::lock_guard lock(mutex_);
  for (const Entry& e : runs_) list.push_back(e.summary);
  return {{"runs", std::move(list)}};
}

json RunHistory::run(const std::string& run_id) const {
  std::lock_guard lock(mutex_);
  const auto it = std::find_if(runs_.begin(), runs_.end(),
                               [&](const Entry& e) { return e.summary["run_id"] == run_id; });
  if (it != runs_.end()) return it->result;
  throw common::CommandError(
      "unknown_run",
      "no run '" + run_id + "' kept (" + std::to_string(runs_.size()) + " are; `runs` lists them)");
}

json RunHistory::faults() const {
  std::lock_guard lock(mutex_);
  json list = json::array();
  for (const json& f : faults_) list.push_back(f);
  return list;
}

}  // namespace hystbench::daemon::details
