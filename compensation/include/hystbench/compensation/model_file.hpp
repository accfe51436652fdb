#pragma once
// Model files: JSON, versioned schema "hystbench.model/1", human-readable.
//   {"schema": "hystbench.model/1", "type": "pi|mpi|cpi|rpi",
//    "units": {"input": "V", "output": "um"}, "input_range": [min, max],
//    "play": {"thresholds": [...], "weights": [...], "offset": 0},          (pi, mpi, rpi)
//    "deadzone": {"thresholds": [...], "weights": [...], "center": 0},      (mpi, rpi; cpi:
//    optional) "rate": {"coefficients": [...], "max_rate": 0},                         (rpi)
//    "coupled_play": {"r": [...], "ra": [...], "rb": [...], "rc": [...],
//                     "weights": [...], "offset": 0},                        (cpi)
//    "creep": {"time_constants_s": [...], "gains": [...]},                   (optional)
//    "dynamics": {"natural_frequency_hz": f, "damping_ratio": z},           (optional)
//    "delay_s": 0,                                                           (optional)
//    "frequency_response": {...},         (optional: the stage's, stage_responses.hpp)
//    "identification": {...}}                                                (free-form metadata)
// Pure conversion between JSON values and models; reading and writing files is the caller's.
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/stage_responses.hpp"

namespace hystbench::compensation {

inline constexpr const char* kModelSchema = "hystbench.model/1";

/// Thrown for a malformed model file; what() names the field (e.g. "play.thresholds[3]: ...").
class ModelFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ModelFile {
  ActuatorModel model;
  nlohmann::json identification = nlohmann::json::object();
  /// The stage's frequency responses measured with the model (its feedback is designed on them).
  std::optional<StageResponses> responses = std::nullopt;
};

nlohmann::json to_json(const ModelFile& file);
/// {"input": unit, "output": unit}, as a model file's `units`.
nlohmann::json to_json(const Units& units);
/// Validates schema, type, every field (type, NaN, ordering) and builds the model.
ModelFile model_file_from_json(const nlohmann::json& j);
/// Parses text (the contents of a model file). Syntax errors become ModelFileError too.
ModelFile parse_model_file(const std::string& text);

}  // namespace hystbench::compensation
