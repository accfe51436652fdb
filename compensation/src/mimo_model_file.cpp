#include "hystbench/compensation/mimo_model_file.hpp"

#include <cmath>

#include "details/json_fields.hpp"

namespace hystbench::compensation {

using nlohmann::json;

namespace {

// Inside the unnamed namespace, so that a unity batch's other files' helpers of the same name
// overload these instead of hiding them.
using details::fail;
using details::number;

const json& member(const json& j, const std::string& key, const std::string& field) {
  if (!j.is_object() || !j.contains(key)) fail(field + key, "missing");
  return j.at(key);
}

std::vector<double> numbers(const json& j, const std::string& field) {
  if (!j.is_array()) fail(field, "not an array");
  std::vector<double> v;
  for (std::size_t i = 0; i < j.size(); ++i) {
    v.push_back(number(j[i], field + "[" + std::to_string(i) + "]"));
  }
  return v;
}

std::vector<MimoChannel> channels(const json& j, const std::string& field) {
  if (!j.is_array() || j.empty()) fail(field, "not a non-empty array");
  std::vector<MimoChannel> out;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string f = field + "[" + std::to_string(i) + "].";
    const json& n = member(j[i], "name", f);
    const json& u = member(j[i], "unit", f);
    if (!n.is_string() || !u.is_string()) fail(f + "name/unit", "not strings");
    out.push_back({n.get<std::string>(), u.get<std::string>()});
  }
  return out;
}

json matrix_json(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
    rows.push_back(std::move(row));
  }
  return rows;
}

Eigen::MatrixXd matrix_of(const json& j, std::size_t rows, std::size_t cols,
                          const std::string& field) {
  if (!j.is_array() || j.size() != rows) {
    fail(field, "not " + std::to_string(rows) + " rows (one per output)");
  }
  Eigen::MatrixXd m(rows, cols);
  for (std::size_t i = 0; i < rows; ++i) {
    const std::vector<double> row = numbers(j[i], field + "[" + std::to_string(i) + "]");
    if (row.size() != cols) {
      fail(field + "[" + std::to_string(i) + "]",
           "not " + std::to_string(cols) + " values (one per input)");
    }
    for (std::size_t c = 0; c < cols; ++c) {
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) = row[c];
    }
  }
  return m;
}

// A classical PI operator alone (what the fit makes) in the compact form; any other model of one
// input as its own model file document.
json operator_json(const std::optional<ActuatorModel>& op) {
  if (!op) return nullptr;
  const auto* pi = dynamic_cast<const PiModel*>(&op->hysteresis());
  if (pi != nullptr && !op->creep() && !op->dynamics() && op->delay_s() == 0.0) {
    const PiParameters& p = pi->parameters();
    return {{"thresholds", p.thresholds}, {"weights", p.weights}, {"offset", p.offset}};
  }
  return {{"model", to_json(ModelFile{*op, json::object()})}};
}

std::optional<ActuatorModel> operator_of(const json& j, const std::string& field) {
  if (j.is_null()) return std::nullopt;
  if (j.is_object() && j.contains("model")) {
    try {
      return model_file_from_json(j["model"]).model;
    } catch (const ModelFileError& e) {
      fail(field + ".model", e.what());
    }
  }
  PiParameters pp;
  pp.thresholds = numbers(member(j, "thresholds", field + "."), field + ".thresholds");
  pp.weights = numbers(member(j, "weights", field + "."), field + ".weights");
  pp.offset = j.contains("offset") ? number(j["offset"], field + ".offset") : 0.0;
  try {
    return classical_pi_operator(std::move(pp));
  } catch (const std::invalid_argument& e) {
    fail(field, e.what());
  }
}

// A Hammerstein model's own keys: its operators and its dynamics.
json body_json(const HammersteinMimoModel& model) {
  const auto& g = model.dynamics();
  json poles = json::array(), terms = json::array(), ops = json::array();
  for (const auto p : g.poles()) poles.push_back({p.real(), p.imag()});
  for (const auto& t : g.terms()) terms.push_back(matrix_json(t));
  for (const auto& op : model.operators()) ops.push_back(operator_json(op));
  const Eigen::VectorXd& off = g.output_offset();
  return {{"operators", ops},
          {"dynamics",
           {{"poles", poles},
            {"terms", terms},
            {"output_offset", std::vector<double>(off.data(), off.data() + off.size())}}}};
}

// The Hammerstein model of m inputs and p outputs in j's "operators" and "dynamics"; field: the
// prefix that names where j is in the file.
HammersteinMimoModel body_of(const json& j, std::size_t m, std::size_t p, double dt,
                             const std::string& field) {
  const json& ops = member(j, "operators", field);
  if (!ops.is_array() || ops.size() != m) fail(field + "operators", "not one entry per input");
  std::vector<std::optional<ActuatorModel>> operators(m);
  for (std::size_t i = 0; i < m; ++i) {
    operators[i] = operator_of(ops[i], field + "operators[" + std::to_string(i) + "]");
  }
  const std::string d = field + "dynamics.";
  const json& dyn = member(j, "dynamics", field);
  const json& pj = member(dyn, "poles", d);
  if (!pj.is_array()) fail(d + "poles", "not an array");
  std::vector<std::complex<double>> poles;
  for (std::size_t i = 0; i < pj.size(); ++i) {
    const auto v = numbers(pj[i], d + "poles[" + std::to_string(i) + "]");
    if (v.size() != 2) fail(d + "poles[" + std::to_string(i) + "]", "not [re, im]");
    poles.emplace_back(v[0], v[1]);
  }
  const json& tj = member(dyn, "terms", d);
  if (!tj.is_array()) fail(d + "terms", "not an array");
  std::vector<Eigen::MatrixXd> terms;
  for (std::size_t q = 0; q < tj.size(); ++q) {
    terms.push_back(matrix_of(tj[q], p, m, d + "terms[" + std::to_string(q) + "]"));
  }
  const auto off = numbers(member(dyn, "output_offset", d), d + "output_offset");
  if (off.size() != p) fail(d + "output_offset", "not one value per output");
  try {
    MimoLinearModel g(std::move(poles), std::move(terms),
                      Eigen::Map<const Eigen::VectorXd>(off.data(), static_cast<Eigen::Index>(p)));
    return HammersteinMimoModel(std::move(operators), std::move(g), dt);
  } catch (const std::invalid_argument& e) {
    fail(field + "dynamics", e.what());
  }
}

json channel_list(const std::vector<MimoChannel>& cs) {
  json a = json::array();
  for (const auto& c : cs) a.push_back({{"name", c.name}, {"unit", c.unit}});
  return a;
}

}  // namespace

bool is_mimo_model_file(const json& j) {
  return j.is_object() && j.contains("type") &&
         (j["type"] == kMimoModelType || j["type"] == kScheduledMimoModelType);
}

json to_json(const MimoModelFile& file) {
  json doc = {{"schema", kModelSchema},
              {"type", file.scheduled ? kScheduledMimoModelType : kMimoModelType},
              {"sample_period_s", file.sample_period_s},
              {"inputs", channel_list(file.inputs)},
              {"outputs", channel_list(file.outputs)}};
  if (file.scheduled) {
    const AmplitudeScheduledMimoModel& s = *file.scheduled;
    doc["schedule"] = {{"window_s", s.window_s()}};
    json local = json::array();
    for (std::size_t i = 0; i < s.local_models().size(); ++i) {
      json l = body_json(s.local_models()[i]);
      l["amplitude"] = s.amplitudes()[i];
      l["identification"] =
          i < file.local_identification.size() ? file.local_identification[i] : json::object();
      local.push_back(std::move(l));
    }
    doc["local_models"] = std::move(local);
  } else {
    doc.update(body_json(file.model));
  }
  doc["identification"] = file.identification;
  return doc;
}

MimoModelFile mimo_model_file_from_json(const json& j) {
  if (!j.is_object()) fail("model", "not a JSON object");
  const json& schema = member(j, "schema", "");
  if (schema != kModelSchema) fail("schema", "not " + std::string(kModelSchema));
  if (!is_mimo_model_file(j)) {
    fail("type", std::string("not ") + kMimoModelType + " or " + kScheduledMimoModelType);
  }
  MimoModelFile f;
  f.sample_period_s = number(member(j, "sample_period_s", ""), "sample_period_s");
  if (!(f.sample_period_s > 0.0)) fail("sample_period_s", "not > 0");
  f.inputs = channels(member(j, "inputs", ""), "inputs");
  f.outputs = channels(member(j, "outputs", ""), "outputs");
  const std::size_t m = f.inputs.size(), p = f.outputs.size();
  if (j["type"] == kScheduledMimoModelType) {
    const json& sj = member(j, "schedule", "");
    const double window_s = number(member(sj, "window_s", "schedule."), "schedule.window_s");
    const json& lj = member(j, "local_models", "");
    if (!lj.is_array() || lj.empty()) fail("local_models", "not a non-empty array");
    std::vector<double> amplitudes;
    std::vector<HammersteinMimoModel> local;
    for (std::size_t i = 0; i < lj.size(); ++i) {
      const std::string field = "local_models[" + std::to_string(i) + "].";
      amplitudes.push_back(number(member(lj[i], "amplitude", field), field + "amplitude"));
      local.push_back(body_of(lj[i], m, p, f.sample_period_s, field));
      f.local_identification.push_back(lj[i].value("identification", json::object()));
    }
    try {
      f.scheduled.emplace(std::move(amplitudes), std::move(local), window_s);
    } catch (const std::invalid_argument& e) {
      fail("local_models", e.what());
    }
    f.model = f.scheduled->local_models().back();
  } else {
    f.model = body_of(j, m, p, f.sample_period_s, "");
  }
  if (j.contains("identification")) f.identification = j["identification"];
  return f;
}

}  // namespace hystbench::compensation
