#include "service/details/command_table.hpp"

#include <string_view>

#include "hystbench/common/command_error.hpp"
#include "runs/details/run_requests.hpp"
#include "service/details/run_history.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;
using T = ParamType;

namespace {

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
      {"identify", nullptr, kIdentifyParams,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.start_identify(r); }},
      {"track", "reference_upload", kTrackUploadedParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"track", "reference_uploads", kTrackStageUploadedParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"track", nullptr, kTrackBuiltinParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"excite", "drive_uploads", kExciteStageParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_excite(r, c); }},
      {"excite", nullptr, kExciteParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_excite(r, c); }},
      {"frf", nullptr, kFrfParams,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.start_frf(r); }},
      {"tune", nullptr, kTuneParams,
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
