// DiagnosisHiddenEffect: one effect hidden in a simulated Preisach actuator (or none), named from
// the data alone, its extended model better on a second record (diagnosis_test_support.hpp); on a
// Preisach baseline too; the resonance it names fitted; the extended model a model file.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "compensation/diagnosis/diagnosis_test_support.hpp"
#include "hystbench/compensation/diagnosis.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/model_file.hpp"

namespace hystbench::test::diagnosis {

TEST(DiagnosisHiddenEffect, NamesNothingBeyondTheShapeOfAPreisachWithNoise) {
  expect_named({hc::Cause::kNone, 200.0, 101});
}
TEST(DiagnosisHiddenEffect, NamesAsymmetryForOffCentreRelays) {
  expect_named({hc::Cause::kAsymmetry, 1000.0, 102});
}
// Relays behind a switching front: the loop widens with the square root of the rate. At 500 Hz
// the linear laws gain too little to be named beside the loop's shape; thresholds widening with
// |du/dt|^(1/2) follow it.
TEST(DiagnosisHiddenEffect, NamesRateDependenceBehindASwitchingFront) {
  expect_named({hc::Cause::kRateDependence, 2000.0, 103});
  expect_named({hc::Cause::kRateDependence, 500.0, 2019});
}
TEST(DiagnosisHiddenEffect, NamesCreep) { expect_named({hc::Cause::kCreep, 500.0, 104}); }
TEST(DiagnosisHiddenEffect, NamesDynamics) { expect_named({hc::Cause::kDynamics, 5000.0, 105}); }
TEST(DiagnosisHiddenEffect, NamesDelay) { expect_named({hc::Cause::kDelay, 1000.0, 106}); }
TEST(DiagnosisHiddenEffect, NamesDrift) { expect_named({hc::Cause::kDrift, 1000.0, 107}); }

// A Preisach plane as the baseline (`diagnose --model` of what `fit --model preisach` wrote): the
// effect hidden beside the relays is named on top of it, the extension keeps the plane (its shape
// fixed, its scale refitted), and the extended model predicts the second record better. The rate
// law's baseline is a plane fitted without one; its extension is the plane's relays widening.
TEST(DiagnosisHiddenEffect, NamesTheEffectBesideAPreisachBaseline) {
  for (const HiddenCase& c :
       {HiddenCase{hc::Cause::kCreep, 500.0, 104}, HiddenCase{hc::Cause::kDynamics, 5000.0, 105},
        HiddenCase{hc::Cause::kRateDependence, 500.0, 2019}}) {
    const HiddenData d = make_hidden(c);
    hc::FitOptions fit;
    fit.kind = hc::ModelKind::kPreisach;
    fit.delay_samples = 0;
    fit.preisach_rate_law = false;
    hc::DiagnosisOptions o;
    const hc::FitResult plane = hc::fit_model(d.first.t, d.first.u, d.first.y, fit);
    ASSERT_EQ(plane.model.hysteresis().kind(), hc::ModelKind::kPreisach)
        << testing::PrintToString(plane.notes);
    o.baseline = plane.model;
    const hc::Diagnosis dg = hc::diagnose(d.first.t, d.first.u, d.first.y, o);
    SCOPED_TRACE(name_of(c) + ": " + d.truth);
    EXPECT_EQ(dg.cause, c.cause) << hc::to_string(dg.cause);
    EXPECT_EQ(dg.extended.hysteresis().kind(), hc::ModelKind::kPreisach)
        << testing::PrintToString(dg.extended_parts)
        << (dg.causes.empty() ? "" : dg.causes.front().extension);
    const Record& r2 = d.second_without_drift;
    const double dt2 = r2.t[1] - r2.t[0];
    const double ratio = hc::validate_model(dg.extended, r2.u, r2.y, dt2).rmse /
                         hc::validate_model(dg.baseline, r2.u, r2.y, dt2).rmse;
    std::printf("%s on a Preisach baseline: named %s, gain %.2f, second record %.3fx\n",
                name_of(c).c_str(), std::string(hc::to_string(dg.cause)).c_str(),
                dg.baseline_heldout.rmse / dg.extended_heldout.rmse, ratio);
    EXPECT_LT(ratio, 0.9);
    if (c.cause == hc::Cause::kRateDependence) {
      EXPECT_TRUE(dg.extended.hysteresis().thresholds_law());
    }
  }
}

// The resonance is fitted jointly with the weights (variable projection), not only named: its
// natural frequency within 2 % and its damping within 20 %, across the range the bench meets
// (50 Hz to a fifth of the sample rate, damping 0.02 to 0.2). The first case is one a user met
// (107 Hz, damping 0.078 at 1 kHz), whose resonance a fit of the baseline alone reads off the
// truth.
TEST(DiagnosisHiddenEffect, FitsTheResonanceItNames) {
  const HiddenCase cases[] = {{hc::Cause::kDynamics, 1000.0, 211, false, 107.0, 0.078},
                              {hc::Cause::kDynamics, 1000.0, 212, false, 55.0, 0.2},
                              {hc::Cause::kDynamics, 2000.0, 213, false, 380.0, 0.03},
                              {hc::Cause::kDynamics, 5000.0, 214, false, 160.0, 0.02}};
  for (const HiddenCase& c : cases) {
    const HiddenData d = make_hidden(c);
    const Outcome o = diagnose_case(d);
    SCOPED_TRACE(name_of(c) + " (" + d.truth + ")\n" + summary(o));
    ASSERT_EQ(o.named, hc::Cause::kDynamics);
    ASSERT_TRUE(o.diagnosis.extended.dynamics().has_value());
    const hc::DynamicsParameters& fitted = *o.diagnosis.extended.dynamics();
    std::printf("%.0f Hz zeta %.3f at %.0f Hz: fitted %.2f Hz zeta %.4f, ratio %.3f, gain %.2f\n",
                c.natural_frequency_hz, c.damping_ratio, c.fs, fitted.natural_frequency_hz,
                fitted.damping_ratio, o.ratio, o.gain);
    EXPECT_NEAR(fitted.natural_frequency_hz, c.natural_frequency_hz, 0.02 * c.natural_frequency_hz);
    EXPECT_NEAR(fitted.damping_ratio, c.damping_ratio, 0.2 * c.damping_ratio);
    // The base's shape error stays in part in both models (see diagnosis_test_support.hpp).
    EXPECT_LE(o.ratio, 0.6) << "extended / baseline rms on the second record";
  }
}

// The same beside a given model whose fit alternates (a modified PI's dead zones with creep lags,
// fitted in turn: DynamicsSearch holds the lags while it searches the mode): the resonance it
// names is the truth's, within the same bounds, and it predicts a second record better.
TEST(DiagnosisHiddenEffect, FitsTheResonanceBesideAModifiedPiWithCreep) {
  HiddenCase c{hc::Cause::kDynamics, 2000.0, 213, false, 380.0, 0.03};
  c.also = hc::Cause::kCreep;
  const HiddenData d = make_hidden(c);
  hc::FitOptions fit;
  fit.kind = hc::ModelKind::kModifiedPi;
  fit.delay_samples = 0;
  fit.creep = true;
  fit.creep_always = true;
  hc::DiagnosisOptions o;
  o.baseline = hc::fit_model(d.first.t, d.first.u, d.first.y, fit).model;
  ASSERT_TRUE(o.baseline->creep().has_value());
  ASSERT_EQ(o.baseline->hysteresis().kind(), hc::ModelKind::kModifiedPi);
  const hc::Diagnosis dg = hc::diagnose(d.first.t, d.first.u, d.first.y, o);
  SCOPED_TRACE(name_of(c) + ": " + d.truth + "\n" + testing::PrintToString(dg.extended_parts));
  ASSERT_TRUE(dg.extended.dynamics().has_value()) << dg.verdict;
  const hc::DynamicsParameters& fitted = *dg.extended.dynamics();
  const Record& r2 = d.second_without_drift;
  const double dt2 = r2.t[1] - r2.t[0];
  const double ratio = hc::validate_model(dg.extended, r2.u, r2.y, dt2).rmse /
                       hc::validate_model(dg.baseline, r2.u, r2.y, dt2).rmse;
  std::printf("beside a modified PI with creep: fitted %.2f Hz zeta %.4f, second record %.3fx\n",
              fitted.natural_frequency_hz, fitted.damping_ratio, ratio);
  EXPECT_NEAR(fitted.natural_frequency_hz, c.natural_frequency_hz, 0.02 * c.natural_frequency_hz);
  EXPECT_NEAR(fitted.damping_ratio, c.damping_ratio, 0.2 * c.damping_ratio);
  EXPECT_LT(ratio, 0.9);
}

// The extended model is an ordinary model file: it survives the JSON round trip and predicts
// the second record exactly as the in-memory model does.
TEST(DiagnosisHiddenEffect, ExtendedModelRoundTripsThroughAModelFile) {
  const HiddenCase c{hc::Cause::kCreep, 500.0, 104};
  const HiddenData d = make_hidden(c);
  const hc::Diagnosis dg = hc::diagnose(d.first.t, d.first.u, d.first.y);
  ASSERT_EQ(dg.cause, hc::Cause::kCreep);
  ASSERT_TRUE(dg.extended.creep().has_value());
  const hc::ModelFile back = hc::model_file_from_json(hc::to_json(hc::ModelFile{dg.extended, {}}));
  EXPECT_NEAR(rms_error(back.model, d.second), rms_error(dg.extended, d.second), 1e-9);
}

}  // namespace hystbench::test::diagnosis
