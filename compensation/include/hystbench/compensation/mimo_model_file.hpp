#pragma once
// Model files of several inputs and outputs (schema "hystbench.model/1", type
// "mimo_hammerstein"):
//   {"schema": ..., "type": "mimo_hammerstein", "sample_period_s": dt,
//    "inputs": [{"name": "u1_V", "unit": "V"}, ...], "outputs": [{"name": ..., "unit": ...}],
//    "operators": [null                                     (per input: none, the input as it is)
//                  | {"thresholds": [...], "weights": [...], "offset": 0}     (a classical PI)
//                  | {"model": {a model file of one input: any PI family}}, ...],
//    "dynamics": {"poles": [[re, im], ...], "terms": [[[row], ...], ...],          (p x m each)
//                 "output_offset": [...]},
//    "identification": {...}}                                                     (free-form)
// Type "mimo_amplitude_scheduled" (AmplitudeScheduledMimoModel) holds, in place of "operators"
// and "dynamics", local models fitted at several amplitudes and the schedule that blends them:
//    "schedule": {"window_s": 0.25},
//    "local_models": [{"amplitude": a [input unit], "operators": [...], "dynamics": {...},
//                      "identification": {...}}, ...]                     (amplitudes ascending)
// The dynamics are discrete-time: the model holds at its own sample period only.
// Pure conversion between JSON values and models; reading and writing files is the caller's.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/compensation/amplitude_scheduled_model.hpp"
#include "hystbench/compensation/hammerstein_mimo_model.hpp"
#include "hystbench/compensation/model_file.hpp"

namespace hystbench::compensation {

inline constexpr const char* kMimoModelType = "mimo_hammerstein";
inline constexpr const char* kScheduledMimoModelType = "mimo_amplitude_scheduled";

struct MimoChannel {
  std::string name;  ///< the record's column
  std::string unit;  ///< after the column's scale
};

struct MimoModelFile {
  /// The model; with a schedule, its local model of the largest amplitude.
  HammersteinMimoModel model;
  /// Set for a model fitted at several amplitudes: what simulate() runs.
  std::optional<AmplitudeScheduledMimoModel> scheduled;
  /// With a schedule: each local model's identification (free-form), in its order.
  std::vector<nlohmann::json> local_identification;
  double sample_period_s = 0.0;  ///< > 0 [s]
  std::vector<MimoChannel> inputs, outputs;
  nlohmann::json identification = nlohmann::json::object();

  /// Output (p x N) for input u (m x N), from rest: the schedule's where there is one.
  Eigen::MatrixXd simulate(const Eigen::MatrixXd& u) const {
    return scheduled ? scheduled->simulate(u) : model.simulate(u);
  }
};

/// True for a model file of either type (whatever else it holds).
bool is_mimo_model_file(const nlohmann::json& j);
nlohmann::json to_json(const MimoModelFile& file);
/// Validates every field and builds the model; throws ModelFileError naming the field.
MimoModelFile mimo_model_file_from_json(const nlohmann::json& j);

}  // namespace hystbench::compensation
