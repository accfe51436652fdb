#include "hystbench/daemon/runs/upload_store.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

#include "hystbench/common/command_error.hpp"
#include "runs/details/request_params.hpp"

namespace hystbench::daemon {

using nlohmann::json;

const char* to_string(UploadKind kind) noexcept {
  return kind == UploadKind::kReference ? "reference" : "drive";
}

double Upload::time_of(std::size_t k) const noexcept {
  if (rate_hz > 0.0) return static_cast<double>(k) / rate_hz;
  return t.empty() ? 0.0 : t[k] - t.front();
}

std::size_t Upload::sample_from(double t_s) const noexcept {
  if (values.empty()) return 0;
  const std::size_t last = values.size() - 1;
  if (rate_hz > 0.0) {
    const double k = std::ceil(t_s * rate_hz - 1e-6);
    return static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(last)));
  }
  // Rounding: a grid time computed as k dt names the row it lands on.
  const double target = t.front() + t_s;
  const auto at =
      std::lower_bound(t.begin(), t.end(), target - 1e-9 * std::max(1.0, std::abs(target)));
  return std::min(static_cast<std::size_t>(at - t.begin()), last);
}

std::vector<double> Upload::resampled(double dt_s) const {
  std::vector<double> out;
  if (values.empty() || !(dt_s > 0.0)) return out;
  const double duration = duration_s();
  const auto n = static_cast<std::size_t>(std::floor(duration / dt_s + 1e-9)) + 1;
  out.reserve(n);
  std::size_t j = 0;  // time_of(j) <= tk < time_of(j + 1)
  for (std::size_t k = 0; k < n; ++k) {
    const double tk = static_cast<double>(k) * dt_s;
    while (j + 1 < values.size() && time_of(j + 1) <= tk) ++j;
    if (j + 1 >= values.size()) {
      out.push_back(values.back());
      continue;
    }
    const double t0 = time_of(j), t1 = time_of(j + 1);
    const double f = (tk - t0) / (t1 - t0);
    out.push_back(values[j] + f * (values[j + 1] - values[j]));
  }
  return out;
}

namespace {

UploadKind kind_param(const json& params) {
  const std::string kind = details::string_param(params, "kind", "");
  if (kind == "reference") return UploadKind::kReference;
  if (kind == "drive") return UploadKind::kDrive;
  throw common::CommandError(
      "bad_params",
      "kind: must be \"reference\" (um against time, for track) or \"drive\" (V "
      "against time, for excite)");
}

bool valid_name(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '-' || c == '_' || c == '.';
  });
}

/// A JSON array of finite numbers; `what` names it in errors.
std::vector<double> numbers(const json& params, const char* key, std::size_t offset) {
  if (!params.contains(key)) {
    throw common::CommandError("bad_params", std::string(key) + ": missing (an array of numbers)");
  }
  const json& a = params[key];
  if (!a.is_array())
    throw common::CommandError("bad_params", std::string(key) + ": must be an array");
  std::vector<double> out;
  out.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a[i].is_number() || !std::isfinite(a[i].get<double>())) {
      throw common::CommandError("bad_params",
                                 std::string(key) + "[" + std::to_string(i) + "] (sample " +
                                     std::to_string(offset + i) + "): must be a finite number",
                                 {{"sample", offset + i}});
    }
    out.push_back(a[i].get<double>());
  }
  return out;
}

}  // namespace

json UploadStore::begin(const json& params, std::uint64_t client) {
  details::check_keys(params, {"kind", "samples", "rate_hz", "upload", "source"});
  const UploadKind kind = kind_param(params);
  if (!params.contains("samples")) {
    throw common::CommandError("bad_params", "samples: missing (the number of samples to upload)");
  }
  const auto samples = static_cast<std::size_t>(
      details::integer_param(params, "samples", 0, 0, std::numeric_limits<long long>::max()));
  if (samples < 2) throw common::CommandError("bad_params", "samples: at least 2 are needed");
  if (samples > limits_.max_samples) {
    throw common::CommandError("upload_too_large",
                               std::to_string(samples) + " samples: an upload holds at most " +
                                   std::to_string(limits_.max_samples) + " samples");
  }
  const double rate = details::number_param(params, "rate_hz", 0.0, 1e-6, 1e9);
  std::string name = details::string_param(params, "upload", "");
  if (params.contains("upload") && !valid_name(name)) {
    throw common::CommandError(
        "bad_params",
        "upload: 1 to 64 letters, digits, '-', '_' or '.' (got '" + name.substr(0, 64) + "')");
  }
  std::string source = details::string_param(params, "source", "");
  if (source.size() > 256) source.resize(256);

  std::lock_guard lock(mutex_);
  if (name.empty()) name = "upload-" + std::to_string(++counter_);
  if (uploads_.size() >= limits_.max_open && uploads_.count({client, name}) == 0) {
    throw common::CommandError("too_many_uploads",
                               "at most " + std::to_string(limits_.max_open) +
                                   " uploads may be open at once; cancel one or "
                                   "start the run that uses it");
  }
  auto u = std::make_shared<Upload>();
  u->name = name;
  u->kind = kind;
  u->client = client;
  u->samples = samples;
  u->rate_hz = rate;
  u->source = std::move(source);
  // Begin again under the same name: the earlier one is replaced.
  if (auto old = uploads_.find({client, name}); old != uploads_.end()) {
    staged_ -= old->second->values.size();
    uploads_.erase(old);
  }
  uploads_[{client, name}] = std::move(u);
  return {{"upload", name},
          {"samples", samples},
          {"max_chunk_samples", limits_.max_chunk_samples},
          {"max_samples", limits_.max_samples}};
}

json UploadStore::chunk(const json& params, std::uint64_t client) {
  details::check_keys(params, {"upload", "offset", "values", "t"});
  const std::string name = details::string_param(params, "upload", "");
  if (!params.contains("offset")) throw common::CommandError("bad_params", "offset: missing");
  const auto offset = static_cast<std::size_t>(
      details::integer_param(params, "offset", 0, 0, std::numeric_limits<long long>::max()));
  const std::vector<double> values = numbers(params, "values", offset);
  if (values.empty()) throw common::CommandError("bad_params", "values: empty chunk");
  if (values.size() > limits_.max_chunk_samples) {
    throw common::CommandError("upload_too_large", std::to_string(values.size()) +
                                                       " values in one chunk: at most " +
                                                       std::to_string(limits_.max_chunk_samples));
  }

  std::lock_guard lock(mutex_);
  const auto it = uploads_.find({client, name});
  if (it == uploads_.end()) {
    throw common::CommandError("upload_unknown",
                               "no upload '" + name + "' on this connection (upload.begin first)");
  }
  Upload& u = *it->second;
  std::vector<double> t;
  if (u.rate_hz > 0.0) {
    if (params.contains("t")) {
      throw common::CommandError("bad_params",
                                 "t: this upload is sampled at rate_hz; send values only");
    }
  } else {
    t = numbers(params, "t", offset);
    if (t.size() != values.size()) {
      throw common::CommandError("bad_params", "t and values: " + std::to_string(t.size()) +
                                                   " and " + std::to_string(values.size()) +
                                                   " entries; one time per value");
    }
  }
  if (offset != u.values.size()) {
    throw common::CommandError("bad_params", "offset: " + std::to_string(offset) + ", expected " +
                                                 std::to_string(u.values.size()) +
                                                 " (chunks in order, none repeated)");
  }
  if (offset + values.size() > u.samples) {
    throw common::CommandError("upload_too_large", "upload '" + name + "' declared " +
                                                       std::to_string(u.samples) +
                                                       " samples; this chunk would make " +
                                                       std::to_string(offset + values.size()));
  }
  if (staged_ + values.size() > limits_.max_staged_samples) {
    throw common::CommandError("upload_too_large",
                               "the daemon holds at most " +
                                   std::to_string(limits_.max_staged_samples) +
                                   " uploaded samples at once; cancel an upload or start its run");
  }
  for (std::size_t i = 0; i < t.size(); ++i) {
    const double before = i > 0 ? t[i - 1] : (u.t.empty() ? -HUGE_VAL : u.t.back());
    if (!(t[i] > before)) {
      throw common::CommandError("bad_params",
                                 "t[" + std::to_string(i) + "] (sample " +
                                     std::to_string(offset + i) + "): times must increase strictly",
                                 {{"sample", offset + i}});
    }
  }
  u.t.insert(u.t.end(), t.begin(), t.end());
  u.values.insert(u.values.end(), values.begin(), values.end());
  staged_ += values.size();
  return {{"upload", name},
          {"received", u.values.size()},
          {"samples", u.samples},
          {"complete", u.complete()}};
}

json UploadStore::cancel(const json& params, std::uint64_t client) {
  details::check_keys(params, {"upload"});
  const std::string name = details::string_param(params, "upload", "");
  std::lock_guard lock(mutex_);
  const auto it = uploads_.find({client, name});
  if (it == uploads_.end()) {
    throw common::CommandError("upload_unknown", "no upload '" + name + "' on this connection");
  }
  staged_ -= it->second->values.size();
  uploads_.erase(it);
  return {{"cancelled", name}};
}

std::shared_ptr<const Upload> UploadStore::complete(const std::string& name, std::uint64_t client,
                                                    UploadKind kind) const {
  std::lock_guard lock(mutex_);
  const auto it = uploads_.find({client, name});
  if (it == uploads_.end()) {
    throw common::CommandError("upload_unknown",
                               "no upload '" + name + "' on this connection (upload.begin first)");
  }
  const Upload& u = *it->second;
  if (u.kind != kind) {
    throw common::CommandError("bad_params", "upload '" + name + "' is a " + to_string(u.kind) +
                                                 ", this run needs a " + to_string(kind));
  }
  if (!u.complete()) {
    throw common::CommandError("upload_incomplete", "upload '" + name + "' has " +
                                                        std::to_string(u.values.size()) + " of " +
                                                        std::to_string(u.samples) + " samples");
  }
  return it->second;
}

void UploadStore::erase(const std::string& name, std::uint64_t client) {
  std::lock_guard lock(mutex_);
  if (const auto it = uploads_.find({client, name}); it != uploads_.end()) {
    staged_ -= it->second->values.size();
    uploads_.erase(it);
  }
}

void UploadStore::drop_client(std::uint64_t client) {
  std::lock_guard lock(mutex_);
  for (auto it = uploads_.begin(); it != uploads_.end();) {
    if (it->first.first == client) {
      staged_ -= it->second->values.size();
      it = uploads_.erase(it);
    } else {
      ++it;
    }
  }
}

std::size_t UploadStore::open() const {
  std::lock_guard lock(mutex_);
  return uploads_.size();
}

std::size_t UploadStore::staged_samples() const {
  std::lock_guard lock(mutex_);
  return staged_;
}

}  // namespace hystbench::daemon
