#include "service/details/command_table.hpp"

#include <string_view>

#include "hystbench/common/command_error.hpp"
#include "service/details/run_history.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;
using T = ParamType;

namespace {

constexpr double kWeekS = 7.0 * 24 * 3600;

// Ranges that depend on the bench (frequency_hz up to a twentieth of the loop rate, identify's
// u_min/u_max within the output limits) are checked by the run builders on top of these.
constexpr ParamSpec kIdentify[] = {{"model", T::kString},
                                   {"operators", T::kInteger, 0, 500},
                                   {"dead_zones", T::kInteger, -1, 100},
                                   {"u_min", T::kNumber},
                                   {"u_max", T::kNumber},
                                   {"extend", T::kBoolean}};
constexpr ParamSpec kTrackUploaded[] = {{"reference_upload", T::kString},
                                        {"approach_s", T::kNumber, 0.0, 60.0},
                                        {"compensator", T::kString},
                                        {"kp", T::kNumber, 0.0, 1e6},
                                        {"ki", T::kNumber, 0.0, 1e9},
                                        {"kd", T::kNumber, 0.0, 1e3},
                                        {"force_gains", T::kBoolean},
                                        {"precondition_s", T::kNumber, 0.0, 60.0},
                                        {"learn_trials", T::kInteger, 0, 1000},
                                        {"learn_gain", T::kNumber, 1e-3, 20.0},
                                        {"learn_cutoff_hz", T::kNumber, 1e-3, 1e9},
                                        {"learned", T::kString},
                                        {"lead_in_max_s", T::kNumber, 0.0, 600.0}};
// A stage's (several axes): an uploaded reference per axis, {axis: upload name}.
constexpr ParamSpec kTrackStageUploaded[] = {
    {"reference_uploads", T::kObject}, {"approach_s", T::kNumber, 0.0, 60.0},
    {"compensator", T::kString},       {"precondition_s", T::kNumber, 0.0, 60.0},
    {"decouple", T::kBoolean},         {"decoupling", T::kString}};
constexpr ParamSpec kTrackBuiltin[] = {{"reference", T::kString},
                                       {"frequency_hz", T::kNumber, 1e-3},
                                       {"periods", T::kNumber, 0.0, 1e7},
                                       {"duration_s", T::kNumber, 0.0, kWeekS},
                                       {"compensator", T::kString},
                                       {"range_fraction", T::kNumber, 0.01, 1.0},
                                       {"min_um", T::kNumber, -1e9, 1e9},
                                       {"max_um", T::kNumber, -1e9, 1e9},
                                       {"kp", T::kNumber, 0.0, 1e6},
                                       {"ki", T::kNumber, 0.0, 1e9},
                                       {"kd", T::kNumber, 0.0, 1e3},
                                       {"force_gains", T::kBoolean},
                                       {"precondition_s", T::kNumber, 0.0, 60.0},
                                       {"learn_trials", T::kInteger, 0, 1000},
                                       {"learn_gain", T::kNumber, 1e-3, 20.0},
                                       {"learn_cutoff_hz", T::kNumber, 1e-3, 1e9},
                                       {"learned", T::kString},
                                       {"lead_in_max_s", T::kNumber, 0.0, 600.0},
                                       {"frequencies_hz", T::kArray},
                                       {"decouple", T::kBoolean},
                                       {"decoupling", T::kString}};
constexpr ParamSpec kExcite[] = {{"drive_upload", T::kString}};
constexpr ParamSpec kExciteStage[] = {{"drive_uploads", T::kObject}};
constexpr ParamSpec kFrf[] = {{"amplitude", T::kNumber, 1e-3, 0.1},
                              {"periods", T::kInteger, 2, 64}};
constexpr ParamSpec kTune[] = {{"compensator", T::kString},
                               {"kp", T::kNumber, 0.0, 1e6},
                               {"ki", T::kNumber, 0.0, 1e9},
                               {"kd", T::kNumber, 0.0, 1e3}};
// The upload store checks the ranges (and what is missing) itself, with the same validator.
constexpr ParamSpec kUploadBegin[] = {{"kind", T::kString},
                                      {"samples", T::kInteger},
                                      {"rate_hz", T::kNumber},
                                      {"upload", T::kString},
                                      {"source", T::kString}};
constexpr ParamSpec kUploadChunk[] = {
    {"upload", T::kString}, {"offset", T::kInteger}, {"values", T::kArray}, {"t", T::kArray}};
constexpr ParamSpec kUploadCancel[] = {{"upload", T::kString}};
constexpr ParamSpec kModelDelete[] = {{"name", T::kString}};
constexpr ParamSpec kRunGet[] = {{"run_id", T::kString}};
constexpr ParamSpec kModelLoad[] = {
    {"model", T::kObject, 0, 0, "the model file's JSON object"},
    {"models", T::kObject, 0, 0, "a stage's model files' JSON objects by axis"},
    {"name", T::kString},
    {"stored", T::kString},
    {"path", T::kString, 0, 0, nullptr,
     "model.load takes the model document ('model', which `hystbench model load FILE` reads and "
     "sends) or the name of a model in the daemon's model folder ('stored'); the daemon never "
     "opens a path a client names"}};

// run.get: the kept result of run_id, which the request must name.
json run_get(const RunHistory& history, const RequestParams& request) {
  if (!request.has("run_id")) {
    throw common::CommandError("bad_params", "run_id: missing (`runs` lists them)");
  }
  return history.run(request.string("run_id", ""));
}

}  // namespace

std::span<const Command> bench_commands() {
  // Defined here, a friend of Bench: the handlers reach its private members.
  static const Command kCommands[] = {
      {"status",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.status(); },
       true},
      {"identify", nullptr, kIdentify,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.start_identify(r); }},
      {"track", "reference_upload", kTrackUploaded,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"track", "reference_uploads", kTrackStageUploaded,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"track", nullptr, kTrackBuiltin,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"excite", "drive_uploads", kExciteStage,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_excite(r, c); }},
      {"excite", nullptr, kExcite,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_excite(r, c); }},
      {"frf", nullptr, kFrf,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.start_frf(r); }},
      {"tune", nullptr, kTune,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.tune(r); }},
      {"upload.begin", nullptr, kUploadBegin,
       [](Bench& b, const RequestParams& r, std::uint64_t c) {
         return b.uploads_.begin(r.params(), c);
       }},
      {"upload.chunk", nullptr, kUploadChunk,
       [](Bench& b, const RequestParams& r, std::uint64_t c) {
         return b.uploads_.chunk(r.params(), c);
       }},
      {"upload.cancel", nullptr, kUploadCancel,
       [](Bench& b, const RequestParams& r, std::uint64_t c) {
         return b.uploads_.cancel(r.params(), c);
       }},
      {"stop",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.stop_run(); }},
      {"abort",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.abort_run(); }},
      {"reset",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.reset(); }},
      {"model.get",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.model_get(); },
       true},
      {"model.load", nullptr, kModelLoad,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.load_model(r); }},
      {"model.delete", nullptr, kModelDelete,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.delete_model(r); }},
      {"model.list",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.list_models(); },
       true},
      {"runs",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.history_->runs(); },
       true},
      {"run.get", nullptr, kRunGet,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return run_get(*b.history_, r); },
       true},
      {"config.get",
       nullptr,
       {},
       [](Bench& b, const RequestParams&, std::uint64_t) { return b.settings_.config_json; },
       true},
  };
  return kCommands;
}

std::span<const ParamSpec> track_builtin_params() { return kTrackBuiltin; }

bool command_reads_only(const std::string& name) {
  bool found = false;
  for (const Command& c : bench_commands()) {
    if (name != c.name) continue;
    if (!c.reads_only) return false;
    found = true;
  }
  return found;
}

const Command& find_command(const std::string& name, const json& params) {
  const Command* fallback = nullptr;
  std::string names;
  std::string_view previous;
  for (const Command& c : bench_commands()) {
    if (name == c.name) {
      const bool applies =
          c.when_key == nullptr || (params.is_object() && params.contains(c.when_key));
      if (applies && c.when_key != nullptr) return c;
      if (applies && fallback == nullptr) fallback = &c;
    }
    if (previous != c.name) names += (names.empty() ? "" : ", ") + std::string(c.name);
    previous = c.name;
  }
  if (fallback != nullptr) return *fallback;
  throw common::CommandError("unknown_command", "unknown command '" + name + "' (" + names + ")");
}

}  // namespace hystbench::daemon::details
