#include "hystbench/compensation/stage_responses.hpp"

#include <cmath>

#include "details/json_fields.hpp"

namespace hystbench::compensation {

using nlohmann::json;

namespace {

using details::fail;
using details::member;
using details::number;
using details::numbers;

std::size_t count(const json& v, const std::string& field) {
  if (!v.is_number_integer() || v.get<long long>() < 0) fail(field, "must be an integer >= 0");
  return v.get<std::size_t>();
}

}  // namespace

json to_json(const StageResponses& r) {
  json responses = json::array();
  for (std::size_t i = 0; i < r.responses.size(); ++i) {
    const MeasuredResponse& m = r.responses[i];
    std::vector<double> real, imag;
    for (const auto& x : m.response) {
      real.push_back(x.real());
      imag.push_back(x.imag());
    }
    const ResponseSegment s = i < r.segments.size() ? r.segments[i] : ResponseSegment{};
    responses.push_back(
        {{"label", m.label},
         {"operating_point", m.operating_point},
         {"amplitude", m.amplitude},
         {"output_noise_rms", m.output_noise_rms},
         {"segment", {{"first", s.first}, {"period", s.period}, {"periods", s.periods}}},
         {"frequency_hz", m.frequency_hz},
         {"real", real},
         {"imag", imag},
         {"noise", m.noise},
         {"coherence", m.coherence}});
  }
  return {{"rate_hz", r.rate_hz},
          {"run_id", r.run_id},
          {"excitation", r.excitation},
          {"responses", responses}};
}

StageResponses stage_responses_from_json(const json& j, const std::string& field) {
  StageResponses out;
  out.rate_hz = number(member(j, field, "rate_hz"), field + ".rate_hz");
  if (!(out.rate_hz > 0.0)) fail(field + ".rate_hz", "must be > 0");
  if (j.contains("run_id") && j["run_id"].is_string()) out.run_id = j["run_id"].get<std::string>();
  if (j.contains("excitation")) out.excitation = j["excitation"];
  const json& list = member(j, field, "responses");
  if (!list.is_array() || list.empty()) fail(field + ".responses", "must be a non-empty array");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string f = field + ".responses[" + std::to_string(i) + "]";
    const json& r = list[i];
    MeasuredResponse m;
    if (r.contains("label") && r["label"].is_string()) m.label = r["label"].get<std::string>();
    m.operating_point = number(member(r, f, "operating_point"), f + ".operating_point");
    m.amplitude = number(member(r, f, "amplitude"), f + ".amplitude");
    m.output_noise_rms = number(member(r, f, "output_noise_rms"), f + ".output_noise_rms");
    m.frequency_hz = numbers(r, f, "frequency_hz");
    const std::vector<double> real = numbers(r, f, "real");
    const std::vector<double> imag = numbers(r, f, "imag");
    m.noise = numbers(r, f, "noise");
    m.coherence = numbers(r, f, "coherence");
    if (real.size() != m.frequency_hz.size() || imag.size() != m.frequency_hz.size()) {
      fail(f, "frequency_hz, real and imag differ in length");
    }
    for (std::size_t k = 0; k < real.size(); ++k) m.response.emplace_back(real[k], imag[k]);
    try {
      validate(m, f);
    } catch (const std::invalid_argument& e) {
      throw ModelFileError(e.what());
    }
    const json& seg = member(r, f, "segment");
    ResponseSegment s;
    s.first = count(member(seg, f + ".segment", "first"), f + ".segment.first");
    s.period = count(member(seg, f + ".segment", "period"), f + ".segment.period");
    s.periods = count(member(seg, f + ".segment", "periods"), f + ".segment.periods");
    out.responses.push_back(std::move(m));
    out.segments.push_back(s);
  }
  return out;
}

}  // namespace hystbench::compensation
