#include "service/details/command_table.hpp"

#include <string_view>

#include "hystbench/common/command_error.hpp"
#include "hystbench/common/run_requests.hpp"
#include "service/details/run_history.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;
using T = ParamType;

namespace {

// The upload store checks the ranges (and what is missing) itself, with the same validator.
constexpr ParamSpec kUploadBegin[] = {
    {.key = "kind", .type = T::kString, .doc = "`reference` or `drive`"},
    {.key = "samples", .type = T::kInteger, .doc = "the samples to come, at most 10 M"},
    {.key = "rate_hz",
     .type = T::kNumber,
     .doc = "their sample rate [Hz]; without it each chunk carries `t`"},
    {.key = "upload", .type = T::kString, .doc = "a name for it", .fallback_doc = "one is given"},
    {.key = "source",
     .type = T::kString,
     .doc = "the file it came from, kept in the run log's header"}};
constexpr ParamSpec kUploadChunk[] = {
    {.key = "upload", .type = T::kString, .doc = "the upload's name"},
    {.key = "offset", .type = T::kInteger, .doc = "the samples received so far"},
    {.key = "values", .type = T::kArray, .doc = "at most 1000 finite values"},
    {.key = "t",
     .type = T::kArray,
     .doc = "their times [s], strictly increasing (only without `rate_hz`)"}};
constexpr ParamSpec kUploadCancel[] = {
    {.key = "upload", .type = T::kString, .doc = "the upload to discard"}};
constexpr ParamSpec kModelDelete[] = {
    {.key = "name",
     .type = T::kString,
     .doc = "a model or a learned drive in the folder (never the active model)"}};
constexpr ParamSpec kRunGet[] = {
    {.key = "run_id",
     .type = T::kString,
     .doc = "one of `runs`' ids: that run's result, as `run.finished` gave it (`unknown_run` "
            "otherwise)"}};
constexpr ParamSpec kModelLoad[] = {
    {.key = "model",
     .type = T::kObject,
     .doc = "the model file's JSON object (`hystbench model load FILE` reads the file and sends "
            "it)",
     .what = "the model file's JSON object"},
    {.key = "models",
     .type = T::kObject,
     .doc = "on a stage: `{axis: document}`, every axis's file of one stage identify (`hystbench "
            "model load RUN-x.json RUN-y.json`); checked together, then kept as that identify's "
            "`RUN-AXIS.json` and loaded as `stored` would (one request carries at most 1 MiB)",
     .what = "a stage's model files' JSON objects by axis"},
    {.key = "name",
     .type = T::kString,
     .doc = "the name it is kept under in the model folder (with `model`)",
     .fallback = "uploaded"},
    {.key = "stored",
     .type = T::kString,
     .doc = "the name of a model in the daemon's model folder; on a stage, the stage identify's "
            "run id: every axis's `RUN-AXIS.json` loads, with the coupling and the responses "
            "they carry (the reply gives `stage_run_id`, `axes` {`name`, `type`, `responses`} "
            "and `coupling`)"},
    {.key = "path",
     .type = T::kString,
     .doc = "refused: the daemon never opens a path a client names",
     .refusal = "model.load takes the model document ('model', which `hystbench model load "
                "FILE` reads and sends) or the name of a model in the daemon's model folder "
                "('stored'); the daemon never opens a path a client names"}};

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
      {"identify", nullptr, common::kIdentifyParams,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.start_identify(r); }},
      {"track", "reference_upload", common::kTrackUploadedParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"track", "reference_uploads", common::kTrackStageUploadedParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"track", nullptr, common::kTrackBuiltinParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_track(r, c); }},
      {"excite", "drive_uploads", common::kExciteStageParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_excite(r, c); }},
      {"excite", nullptr, common::kExciteParams,
       [](Bench& b, const RequestParams& r, std::uint64_t c) { return b.start_excite(r, c); }},
      {"frf", nullptr, common::kFrfParams,
       [](Bench& b, const RequestParams& r, std::uint64_t) { return b.start_frf(r); }},
      {"tune", nullptr, common::kTuneParams,
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
