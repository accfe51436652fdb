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

json complex_json(std::complex<double> x) { return json::array({x.real(), x.imag()}); }

std::complex<double> complex_from(const json& v, const std::string& field) {
  if (!v.is_array() || v.size() != 2) fail(field, "must be [real, imag]");
  return {number(v[0], field + "[0]"), number(v[1], field + "[1]")};
}

MovingResponse moving_from(const json& j, const std::string& f) {
  MovingResponse m;
  m.frequency_hz = number(member(j, f, "frequency_hz"), f + ".frequency_hz");
  if (!(m.frequency_hz > 0.0)) fail(f + ".frequency_hz", "must be > 0");
  m.rising = complex_from(member(j, f, "rising"), f + ".rising");
  m.falling = complex_from(member(j, f, "falling"), f + ".falling");
  m.ramps = count(member(j, f, "ramps"), f + ".ramps");
  m.lag_deg = number(member(j, f, "lag_deg"), f + ".lag_deg");
  m.lag_noise_deg = number(member(j, f, "lag_noise_deg"), f + ".lag_noise_deg");
  const json& lagging = member(j, f, "lagging");
  if (!lagging.is_string() || (lagging != "rising" && lagging != "falling")) {
    fail(f + ".lagging", "must be \"rising\" or \"falling\"");
  }
  m.lagging = lagging.get<std::string>();
  const json& zero = member(j, f, "zero_hz");
  if (!zero.is_null()) {
    m.zero_hz = number(zero, f + ".zero_hz");
    if (!(m.zero_hz > 0.0)) fail(f + ".zero_hz", "must be > 0 or null");
  }
  return m;
}

}  // namespace

json to_json(const MovingResponse& m) {
  return {{"frequency_hz", m.frequency_hz},
          {"rising", complex_json(m.rising)},
          {"falling", complex_json(m.falling)},
          {"ramps", m.ramps},
          {"lag_deg", m.lag_deg},
          {"lag_noise_deg", m.lag_noise_deg},
          {"lagging", m.lagging},
          {"zero_hz", m.zero_hz > 0.0 ? json(m.zero_hz) : json(nullptr)}};
}

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
  json out = {{"rate_hz", r.rate_hz},
              {"run_id", r.run_id},
              {"excitation", r.excitation},
              {"responses", responses}};
  if (r.moving) out["moving"] = to_json(*r.moving);
  return out;
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
  if (j.contains("moving")) out.moving = moving_from(j["moving"], field + ".moving");
  return out;
}

}  // namespace hystbench::compensation
