#include "diagnosis/details/reference.hpp"

#include <stdexcept>
#include <string>
#include <utility>

#include "diagnosis/details/baseline.hpp"
#include "diagnosis/details/residual_profiles.hpp"

namespace hystbench::compensation::details::diagnosis {

Baseline fit_baseline(Diagnosis& d, const details::DiagnosisRecord& r,
                      const DiagnosisOptions& options) {
  Baseline base;
  if (options.baseline) {
    if (!options.baseline->valid())
      throw std::invalid_argument("the given baseline model is empty");
    d.baseline_given = true;
    d.baseline = *options.baseline;
    ActuatorModel sim(d.baseline);
    d.baseline_prediction = sim.simulate(r.u, r.dt);
    d.baseline_description = "given model: " + details::describe_model(d.baseline);
    base.spec = details::spec_of_model(d.baseline, r);
    base.fit = details::fit_extension(r, base.spec);
    d.refit_heldout = base.fit.heldout;
  } else {
    details::PiBaseline b = details::fit_pi_baseline(r);
    d.baseline = b.fit.model;
    d.baseline_prediction = std::move(b.fit.prediction);
    d.baseline_description = b.description;
    base.spec = b.finest_spec;
    base.fit = std::move(b.finest_fit);
  }
  const details::SplitErrors be = details::split_errors(r, d.baseline_prediction);
  d.baseline_fit = be.fit;
  d.baseline_heldout = be.heldout;
  return base;
}

std::vector<double> residual_and_noise(Diagnosis& d, const details::DiagnosisRecord& r) {
  std::vector<double> e = residual_of(r, d.baseline_prediction);
  d.noise_rms = details::noise_rms(e);
  d.noise_source = "second differences of the baseline residual";
  d.input_period = details::input_period(r.u);
  if (d.input_period > 0) {
    const double periodic = details::periodic_noise_rms(r.y, d.input_period);
    if (periodic > 0.0 && periodic < d.noise_rms) {
      d.noise_rms = periodic;
      d.noise_source = "period-to-period difference of the output (the input repeats every " +
                       std::to_string(d.input_period) + " samples)";
    }
  }
  return e;
}

void set_coherent_share(Diagnosis& d) {
  const FrequencyResponse& fr = d.frequency_response;
  double coherent = 0.0, total = 0.0;
  for (std::size_t i = 0; i < fr.coherence.size(); ++i) {
    coherent += fr.coherence[i] * fr.output_psd[i];
    total += fr.output_psd[i];
  }
  if (total > 0.0) d.coherent_share = coherent / total;
}

bool given_model_stale(const Diagnosis& d, const DiagnosisOptions& options) {
  return d.refit_heldout && d.refit_heldout->rmse > 0.0 &&
         d.baseline_heldout.rmse / d.refit_heldout->rmse >= options.min_gain;
}

Reference reference_of(const Diagnosis& d, const details::DiagnosisRecord& r,
                       const details::ExtensionFit& base_fit, const details::InputEvents& ev,
                       std::vector<double> e, const DiagnosisOptions& options) {
  Reference ref{std::move(e), d.profiles, d.frequency_response, d.baseline_prediction};
  if (given_model_stale(d, options)) {
    ref.residual = residual_of(r, base_fit.prediction);
    ref.profiles = residual_profiles(r, ref.residual, ev);
    ref.response = details::frequency_response(base_fit.prediction, r.y, r.dt, d.noise_rms);
    ref.prediction = base_fit.prediction;
  }
  return ref;
}

}  // namespace hystbench::compensation::details::diagnosis
