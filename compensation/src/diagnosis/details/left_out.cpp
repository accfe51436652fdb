#include "diagnosis/details/left_out.hpp"

#include <exception>
#include <utility>

namespace hystbench::compensation::details {

LeftOutScorer::LeftOutScorer(const DiagnosisRecord& r, std::vector<RecordPart> parts,
                             const DiagnosisOptions& options)
    : r_(r), parts_(std::move(parts)) {
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    auto o = std::make_unique<Others>();
    std::vector<std::size_t> starts;
    for (std::size_t j = 0; j < parts_.size(); ++j) {
      if (j == i) continue;
      starts.push_back(o->u.size());
      const RecordPart& p = parts_[j];
      o->u.insert(o->u.end(), r.u.begin() + p.begin, r.u.begin() + p.end);
      o->y.insert(o->y.end(), r.y.begin() + p.begin, r.y.begin() + p.end);
    }
    o->t.resize(o->u.size());
    for (std::size_t k = 0; k < o->t.size(); ++k) o->t[k] = static_cast<double>(k) * r.dt;
    DiagnosisOptions others_options;
    others_options.blocks = options.blocks;
    others_options.heldout_every = options.heldout_every;
    others_options.units = options.units;
    o->record = make_diagnosis_record(o->t, o->u, o->y, others_options, starts);
    others_.push_back(std::move(o));
  }
}

std::optional<std::vector<double>> LeftOutScorer::rms(const ExtensionSpec& spec) const {
  std::vector<double> out;
  for (std::size_t i = 0; i < parts_.size(); ++i) {
    const RecordPart& p = parts_[i];
    ActuatorModel model;
    try {
      model = fit_extension(others_[i]->record, spec, FitRows::kAll, false).model;
    } catch (const std::exception&) {
      return std::nullopt;  // a structure the others cannot support (too few rows, ...)
    }
    const std::span<const double> u = r_.u.subspan(p.begin, p.end - p.begin);
    const std::span<const double> y = r_.y.subspan(p.begin, p.end - p.begin);
    out.push_back(validate_model(std::move(model), u, y, r_.dt).rmse);
  }
  return out;
}

}  // namespace hystbench::compensation::details
