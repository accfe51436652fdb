#pragma once
// Data a client sends in chunks over the socket before a run uses it: a reference trajectory
// (µm against time) for track, or a drive (V against time) for excite. The daemon never opens a
// client's path: the client reads its file and the samples travel in `upload.chunk` requests,
// each below the 64 KiB line limit.
//
//   upload.begin  {"kind":"reference"|"drive", "samples":N, "rate_hz":R?, "upload":name?,
//                  "source":"file name"?}
//                 -> {"upload":name, "samples":N, "max_chunk_samples":..., "max_samples":...}
//   upload.chunk  {"upload":name, "offset":k, "values":[...], "t":[...]}   (t only without R)
//                 -> {"upload":name, "received":k+n, "samples":N, "complete":bool}
//   upload.cancel {"upload":name} -> {"cancelled":name}
//
// An upload belongs to the connection that began it: it is discarded when that connection
// closes, and a run started on that connection consumes it. Chunks come in order (offset = the
// samples received so far); times are finite and strictly increasing, values finite. Bounds:
// UploadLimits, each named in its error. Thread-safe (one mutex); not real-time safe.
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace hystbench::daemon {

enum class UploadKind { kReference, kDrive };
const char* to_string(UploadKind kind) noexcept;

struct UploadLimits {
  std::size_t max_samples = 10'000'000;         ///< per upload
  std::size_t max_chunk_samples = 1'000;        ///< per upload.chunk (t and values fit 64 KiB)
  std::size_t max_staged_samples = 20'000'000;  ///< received, over every open upload
  std::size_t max_open = 16;                    ///< open uploads over every connection
};

struct Upload {
  std::string name;
  UploadKind kind = UploadKind::kReference;
  std::uint64_t client = 0;
  std::size_t samples = 0;  ///< declared at upload.begin
  double rate_hz = 0.0;     ///< > 0: uniform, sample k at k / rate_hz; 0: times in `t`
  std::string source;       ///< what the client called it (a file name), for logs
  std::vector<double> t;    ///< [s], strictly increasing (empty when rate_hz > 0)
  std::vector<double> values;

  bool complete() const noexcept { return values.size() == samples; }
  /// Time of sample k from the start of the upload [s] (the first sample at 0).
  double time_of(std::size_t k) const noexcept;
  /// Duration from the first to the last sample [s].
  double duration_s() const noexcept { return values.empty() ? 0.0 : time_of(values.size() - 1); }
  /// The values at t = k dt_s from the first sample's time to the last (linear interpolation).
  std::vector<double> resampled(double dt_s) const;
  /// The first sample at or after time t_s from the start (the last one beyond the end): the
  /// row a message names for what happens at t_s.
  std::size_t sample_from(double t_s) const noexcept;
};

class UploadStore {
 public:
  explicit UploadStore(UploadLimits limits = {}) : limits_(limits) {}

  /// The three upload commands; each throws CommandError (bad_params, upload_unknown,
  /// upload_too_large, too_many_uploads) and changes nothing when it does.
  nlohmann::json begin(const nlohmann::json& params, std::uint64_t client);
  nlohmann::json chunk(const nlohmann::json& params, std::uint64_t client);
  nlohmann::json cancel(const nlohmann::json& params, std::uint64_t client);

  /// The complete upload `name` of `client`, of `kind`; throws CommandError (upload_unknown,
  /// upload_incomplete, bad_params for the wrong kind). It stays stored until erase().
  std::shared_ptr<const Upload> complete(const std::string& name, std::uint64_t client,
                                         UploadKind kind) const;
  void erase(const std::string& name, std::uint64_t client);
  /// Discards every upload of a connection that went away.
  void drop_client(std::uint64_t client);

  std::size_t open() const;
  std::size_t staged_samples() const;
  const UploadLimits& limits() const noexcept { return limits_; }

 private:
  using Key = std::pair<std::uint64_t, std::string>;
  UploadLimits limits_;
  mutable std::mutex mutex_;
  std::map<Key, std::shared_ptr<Upload>> uploads_;
  std::size_t staged_ = 0;
  std::uint64_t counter_ = 0;
};

}  // namespace hystbench::daemon
