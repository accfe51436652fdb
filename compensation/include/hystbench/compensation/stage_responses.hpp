#pragma once
// The frequency responses a bench measured of its stage (`hystbench frf`, identify), as model
// files keep them under "frequency_response":
//   {"rate_hz": 10000, "run_id": "...", "excitation": {... the options it was played with ...},
//    "responses": [{"label": "...", "operating_point": 37.5, "amplitude": 3,
//                   "output_noise_rms": 0.005, "segment": {"first": 0, "period": 1000,
//                                                          "periods": 4},
//                   "frequency_hz": [...], "real": [...], "imag": [...],
//                   "noise": [...], "coherence": [...]}, ...],
//    "moving": {"frequency_hz": 20, "rising": [re, im], "falling": [re, im], "ramps": 4,
//               "lag_deg": 0.4, "lag_noise_deg": 0.05, "lagging": "rising", "zero_hz": null}}
// ("moving", the response while the stage moves (moving_response.hpp), is absent in files
// written before it was measured, and where the excitation had no moving part)
// the response (real, imag: exact through a round trip) in output unit per input unit, noise
// its standard deviation in the same unit. The excitation's options are the bench's to read (the
// drive is played again from them to see it through another model). Pure conversion; throws
// ModelFileError naming the field.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/compensation/measured_response.hpp"
#include "hystbench/compensation/moving_response.hpp"

namespace hystbench::compensation {

struct StageResponses {
  double rate_hz = 0.0;  ///< the loop rate they were measured at [Hz]
  std::vector<MeasuredResponse> responses;
  std::vector<ResponseSegment> segments;  ///< where in the excitation each was measured
  std::optional<MovingResponse> moving;   ///< while the stage moves; absent: not measured
  nlohmann::json excitation = nlohmann::json::object();
  std::string run_id;  ///< the run that measured them
};

nlohmann::json to_json(const StageResponses& r);
/// Its "moving" object.
nlohmann::json to_json(const MovingResponse& m);
/// `field` names the object in error messages ("frequency_response").
StageResponses stage_responses_from_json(const nlohmann::json& j, const std::string& field);

}  // namespace hystbench::compensation
