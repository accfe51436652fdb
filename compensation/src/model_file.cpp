#include "hystbench/compensation/model_file.hpp"

#include <cmath>
#include <tuple>

#include "details/json_fields.hpp"
#include "hystbench/compensation/coupled_play_pi_model.hpp"
#include "hystbench/compensation/modified_pi_model.hpp"
#include "hystbench/compensation/pi_model.hpp"
#include "hystbench/compensation/preisach_model.hpp"
#include "hystbench/compensation/rate_dependent_pi_model.hpp"

namespace hystbench::compensation {

using nlohmann::json;

namespace {

using details::fail;
using details::member;
using details::number;
using details::numbers;

double number_member(const json& obj, const std::string& parent, const char* key,
                     std::optional<double> fallback = std::nullopt) {
  if (fallback && obj.is_object() && !obj.contains(key)) return *fallback;
  return number(member(obj, parent, key), parent + "." + key);
}

// rate.law: "signed", "magnitude" or "thresholds" (with rate.threshold_s and, 1 when absent,
// rate.threshold_exponent); absent (files written before it was a choice): magnitude.
RateLaw rate_law_from_json(const json& rate) {
  const auto it = rate.find("law");
  if (it == rate.end()) return RateLaw::kMagnitude;
  if (it->is_string()) {
    if (const auto law = rate_law_from_string(it->get<std::string>())) return *law;
  }
  fail("rate.law", "must be \"signed\", \"magnitude\" or \"thresholds\", got " + it->dump());
}

void require_increasing(const std::vector<double>& v, const std::string& field) {
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (!(v[i] > v[i - 1])) {
      fail(field + "[" + std::to_string(i) + "]", "thresholds must be strictly increasing (" +
                                                      std::to_string(v[i]) + " after " +
                                                      std::to_string(v[i - 1]) + ")");
    }
  }
}

PiParameters play_from_json(const json& j) {
  const json& p = member(j, "", "play");
  PiParameters out{numbers(p, "play", "thresholds"), numbers(p, "play", "weights"),
                   number_member(p, "play", "offset", 0.0)};
  require_increasing(out.thresholds, "play.thresholds");
  if (out.thresholds.empty()) fail("play.thresholds", "must not be empty");
  if (out.thresholds.size() != out.weights.size()) {
    fail("play.weights", "must have as many entries as play.thresholds");
  }
  return out;
}

std::pair<DeadZoneParameters, double> dead_zone_from_json(const json& j) {
  const json& d = member(j, "", "deadzone");
  DeadZoneParameters out{numbers(d, "deadzone", "thresholds"), numbers(d, "deadzone", "weights")};
  require_increasing(out.thresholds, "deadzone.thresholds");
  if (out.thresholds.size() != out.weights.size()) {
    fail("deadzone.weights", "must have as many entries as deadzone.thresholds");
  }
  return {out, number_member(d, "deadzone", "center", 0.0)};
}

json play_to_json(const PiParameters& p) {
  return {{"thresholds", p.thresholds}, {"weights", p.weights}, {"offset", p.offset}};
}

json dead_zone_to_json(const DeadZoneParameters& d, double center) {
  return {{"thresholds", d.thresholds}, {"weights", d.weights}, {"center", center}};
}

// The document's model kind, after checking that it is an object of this schema.
ModelKind model_kind_from_json(const json& j) {
  if (!j.is_object()) fail("(top level)", "a model file must be a JSON object");
  const json& schema = member(j, "", "schema");
  if (!schema.is_string() || schema.get<std::string>() != kModelSchema) {
    fail("schema", std::string("must be \"") + kModelSchema + "\", got " + schema.dump());
  }
  const json& type = member(j, "", "type");
  if (!type.is_string()) fail("type", "must be a string");
  const auto kind = model_kind_from_string(type.get<std::string>());
  if (!kind)
    fail("type",
         "unknown model type \"" + type.get<std::string>() + "\" (pi, mpi, cpi, rpi, preisach)");
  return *kind;
}

// The hysteresis model of `kind` from the document's play, deadzone, rate and coupled_play
// members. Throws ModelFileError for a bad member, std::invalid_argument from a constructor.
std::unique_ptr<HysteresisModel> hysteresis_from_json(const json& j, ModelKind kind) {
  std::unique_ptr<HysteresisModel> h;
  switch (kind) {
    case ModelKind::kPi:
      h = std::make_unique<PiModel>(play_from_json(j));
      break;
    case ModelKind::kModifiedPi: {
      auto [dz, center] = dead_zone_from_json(j);
      h = std::make_unique<ModifiedPiModel>(ModifiedPiParameters{play_from_json(j), dz, center});
      break;
    }
    case ModelKind::kRateDependentPi: {
      auto [dz, center] = dead_zone_from_json(j);
      const json& r = member(j, "", "rate");
      RateDependentPiParameters p{
          ModifiedPiParameters{play_from_json(j), dz, center}, numbers(r, "rate", "coefficients"),
          number_member(r, "rate", "max_rate", 0.0), number_member(r, "rate", "filter_s", 0.0),
          number_member(r, "rate", "record_max_rate", 0.0)};
      p.rate_law = rate_law_from_json(r);
      p.threshold_rate_s = number_member(r, "rate", "threshold_s", 0.0);
      p.threshold_rate_exponent = number_member(r, "rate", "threshold_exponent", 1.0);
      h = std::make_unique<RateDependentPiModel>(std::move(p));
      break;
    }
    case ModelKind::kCoupledPlayPi: {
      const json& c = member(j, "", "coupled_play");
      CoupledPlayParameters p{numbers(c, "coupled_play", "r"),
                              numbers(c, "coupled_play", "ra"),
                              numbers(c, "coupled_play", "rb"),
                              numbers(c, "coupled_play", "rc"),
                              numbers(c, "coupled_play", "weights"),
                              number_member(c, "coupled_play", "offset", 0.0),
                              {},
                              0.0};
      if (j.contains("deadzone")) std::tie(p.dead_zone, p.center) = dead_zone_from_json(j);
      h = std::make_unique<CoupledPlayPiModel>(std::move(p));
      break;
    }
    case ModelKind::kPreisach: {
      const json& c = member(j, "", "preisach");
      const json& cells = member(c, "preisach", "cells");
      if (!cells.is_number_integer() || cells.get<long long>() < 1) {
        fail("preisach.cells", "must be an integer >= 1");
      }
      PreisachParameters p{number(member(c, "preisach", "u_min"), "preisach.u_min"),
                           number(member(c, "preisach", "u_max"), "preisach.u_max"),
                           cells.get<std::size_t>(),
                           numbers(c, "preisach", "densities"),
                           number(member(c, "preisach", "slope"), "preisach.slope"),
                           number(member(c, "preisach", "offset"), "preisach.offset")};
      if (c.contains("output_map")) {  // files without it: the identity
        const json& o = c["output_map"];
        p.output_map = {numbers(o, "preisach.output_map", "thresholds"),
                        numbers(o, "preisach.output_map", "weights")};
        p.center = number(member(o, "preisach.output_map", "center"), "preisach.output_map.center");
      }
      if (c.contains("rate")) {  // files without it: no rate law
        const json& r = c["rate"];
        if (rate_law_from_json(r) != RateLaw::kThresholds) {
          fail("preisach.rate.law", "must be \"thresholds\" (the plane's relays widen)");
        }
        p.rate_law = {
            number(member(r, "preisach.rate", "threshold_s"), "preisach.rate.threshold_s"),
            number_member(r, "preisach.rate", "threshold_exponent", 1.0),
            number_member(r, "preisach.rate", "max_rate", 0.0),
            number_member(r, "preisach.rate", "record_max_rate", 0.0),
            number_member(r, "preisach.rate", "filter_s", 0.0)};
      }
      h = std::make_unique<PreisachModel>(std::move(p));
      break;
    }
  }
  return h;
}

// The units member's input and output names (each optional) into `units`.
void units_from_json(const json& u, Units& units) {
  if (!u.is_object()) fail("units", "must be an object");
  if (u.contains("input")) {
    if (!u["input"].is_string()) fail("units.input", "must be a string");
    units.input = u["input"].get<std::string>();
  }
  if (u.contains("output")) {
    if (!u["output"].is_string()) fail("units.output", "must be a string");
    units.output = u["output"].get<std::string>();
  }
}

}  // namespace

json to_json(const Units& units) { return {{"input", units.input}, {"output", units.output}}; }

json to_json(const ModelFile& file) {
  const ActuatorModel& m = file.model;
  if (!m.valid()) throw ModelFileError("model: empty model cannot be saved");
  json j;
  j["schema"] = kModelSchema;
  j["type"] = std::string(to_string(m.hysteresis().kind()));
  j["units"] = to_json(m.units);
  if (m.input_min < m.input_max) j["input_range"] = {m.input_min, m.input_max};
  switch (m.hysteresis().kind()) {
    case ModelKind::kPi:
      j["play"] = play_to_json(static_cast<const PiModel&>(m.hysteresis()).parameters());
      break;
    case ModelKind::kModifiedPi: {
      const auto& p = static_cast<const ModifiedPiModel&>(m.hysteresis()).parameters();
      j["play"] = play_to_json(p.play);
      j["deadzone"] = dead_zone_to_json(p.dead_zone, p.center);
      break;
    }
    case ModelKind::kRateDependentPi: {
      const auto& p = static_cast<const RateDependentPiModel&>(m.hysteresis()).parameters();
      j["play"] = play_to_json(p.base.play);
      j["deadzone"] = dead_zone_to_json(p.base.dead_zone, p.base.center);
      j["rate"] = {{"coefficients", p.rate_coefficients},
                   {"max_rate", p.max_rate},
                   {"filter_s", p.rate_filter_s},
                   {"record_max_rate", p.record_max_rate},
                   {"law", to_string(p.rate_law)}};
      if (p.rate_law == RateLaw::kThresholds) {
        j["rate"]["threshold_s"] = p.threshold_rate_s;
        j["rate"]["threshold_exponent"] = p.threshold_rate_exponent;
      }
      break;
    }
    case ModelKind::kCoupledPlayPi: {
      const auto& p = static_cast<const CoupledPlayPiModel&>(m.hysteresis()).parameters();
      j["coupled_play"] = {{"r", p.r},   {"ra", p.ra},           {"rb", p.rb},
                           {"rc", p.rc}, {"weights", p.weights}, {"offset", p.offset}};
      if (p.has_dead_zones()) j["deadzone"] = dead_zone_to_json(p.dead_zone, p.center);
      break;
    }
    case ModelKind::kPreisach: {
      const auto& p = static_cast<const PreisachModel&>(m.hysteresis()).parameters();
      j["preisach"] = {{"u_min", p.u_min},
                       {"u_max", p.u_max},
                       {"cells", p.cells},
                       {"densities", p.densities},
                       {"slope", p.slope},
                       {"offset", p.offset},
                       {"output_map",
                        {{"thresholds", p.output_map.thresholds},
                         {"weights", p.output_map.weights},
                         {"center", p.center}}}};
      if (p.rate_law.active()) {
        j["preisach"]["rate"] = {{"law", to_string(RateLaw::kThresholds)},
                                 {"threshold_s", p.rate_law.threshold_rate_s},
                                 {"threshold_exponent", p.rate_law.exponent},
                                 {"max_rate", p.rate_law.max_rate},
                                 {"record_max_rate", p.rate_law.record_max_rate},
                                 {"filter_s", p.rate_law.rate_filter_s}};
      }
      break;
    }
  }
  if (m.creep()) {
    j["creep"] = {{"time_constants_s", m.creep()->time_constants_s}, {"gains", m.creep()->gains}};
  }
  if (m.dynamics()) {
    j["dynamics"] = {{"natural_frequency_hz", m.dynamics()->natural_frequency_hz},
                     {"damping_ratio", m.dynamics()->damping_ratio}};
    if (m.dynamics()->feedforward_bandwidth_hz > 0.0) {
      j["dynamics"]["feedforward_bandwidth_hz"] = m.dynamics()->feedforward_bandwidth_hz;
    }
  }
  if (m.delay_s() > 0.0) j["delay_s"] = m.delay_s();
  if (file.responses) j["frequency_response"] = to_json(*file.responses);
  j["identification"] = file.identification.is_null() ? json::object() : file.identification;
  return j;
}

ModelFile model_file_from_json(const json& j) {
  const ModelKind kind = model_kind_from_json(j);
  ModelFile out;
  try {
    out.model = ActuatorModel(hysteresis_from_json(j, kind));
    if (j.contains("creep")) {
      const json& c = j["creep"];
      out.model.set_creep(
          CreepParameters{numbers(c, "creep", "time_constants_s"), numbers(c, "creep", "gains")});
    }
    if (j.contains("dynamics")) {
      const json& d = j["dynamics"];
      out.model.set_dynamics(
          DynamicsParameters{number_member(d, "dynamics", "natural_frequency_hz"),
                             number_member(d, "dynamics", "damping_ratio"),
                             number_member(d, "dynamics", "feedforward_bandwidth_hz", 0.0)});
    }
    if (j.contains("delay_s")) out.model.set_delay(number(j["delay_s"], "delay_s"));
  } catch (const std::invalid_argument& e) {
    // Model constructors name the field; keep their message.
    throw ModelFileError(e.what());
  }
  if (j.contains("units")) units_from_json(j["units"], out.model.units);
  if (j.contains("input_range")) {
    const json& r = j["input_range"];
    if (!r.is_array() || r.size() != 2) fail("input_range", "must be [min, max]");
    out.model.input_min = number(r[0], "input_range[0]");
    out.model.input_max = number(r[1], "input_range[1]");
    if (!(out.model.input_min < out.model.input_max)) fail("input_range", "needs min < max");
  }
  if (j.contains("identification")) out.identification = j["identification"];
  if (j.contains("frequency_response")) {
    out.responses = stage_responses_from_json(j["frequency_response"], "frequency_response");
  }
  return out;
}

namespace {

// Where a JSON syntax error is, and what it is, without the bytes the parser read there (a model
// file's text is never echoed: it may be a file the reader can open and the asker cannot).
// nlohmann's text: "[json.exception.parse_error.101] parse error at line L, column C: <what>;
// last read: '<bytes>'": the part from "line" to "; last read" is kept.
std::string syntax_error(const json::parse_error& e) {
  std::string what = e.what();
  if (const auto cut = what.find("; last read"); cut != std::string::npos) what.resize(cut);
  const auto at = what.find("at line ");
  return "not valid JSON " +
         (at == std::string::npos ? std::string("(syntax error)") : what.substr(at));
}

}  // namespace

ModelFile parse_model_file(const std::string& text) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw ModelFileError(syntax_error(e));
  } catch (const json::exception&) {
    // out_of_range (406) for a number beyond double such as 7e777: bad input too.
    throw ModelFileError("not valid JSON: a number is out of the range of a double");
  }
  return model_file_from_json(j);
}

}  // namespace hystbench::compensation
