// DiagnosisHiddenEffect, the long runs (HYSTBENCH_LONG_TESTS=1): the randomised sweep of every
// cause at 100 Hz .. 20 kHz with its confusion table, and many draws of the cases a delay and a
// rate law are hardest to tell apart in (docs/measurements.md, Diagnosis).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "compensation/diagnosis/diagnosis_test_support.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::test::diagnosis {

namespace {

// The sweep's sampling rates, one case of each cause at each.
constexpr double kSweepRates[] = {100, 200, 500, 1000, 2000, 5000, 10000, 20000};
// The causes of the single-effect rows, in the confusion table's order.
constexpr std::array<hc::Cause, 7> kSweepCauses{
    hc::Cause::kNone,     hc::Cause::kAsymmetry, hc::Cause::kRateDependence, hc::Cause::kCreep,
    hc::Cause::kDynamics, hc::Cause::kDelay,     hc::Cause::kDrift};
constexpr int kWalkRow = 100;  // confusion row of the random-walk drifts

// Every case of the sweep from `seed` on: each cause at each rate, the random-walk drifts, and
// two effects at once, one pair per sampling rate; only those that hide `only` when given.
std::vector<HiddenCase> sweep_cases(std::uint64_t seed, const char* only) {
  std::vector<HiddenCase> cases;
  for (const hc::Cause cause : kSweepCauses) {
    bool widening = false;
    for (const double fs : kSweepRates) {
      // Rate dependence alternates its two mechanisms: a switching front, widening thresholds.
      cases.push_back({cause, fs, ++seed});
      cases.back().widening_thresholds = cause == hc::Cause::kRateDependence && widening;
      widening = !widening;
    }
  }
  for (const double fs : kSweepRates) cases.push_back({hc::Cause::kDrift, fs, ++seed, true});
  // Two effects at once, one pair per sampling rate.
  const std::pair<hc::Cause, hc::Cause> pairs[] = {
      {hc::Cause::kRateDependence, hc::Cause::kDelay},
      {hc::Cause::kDelay, hc::Cause::kDynamics},
      {hc::Cause::kRateDependence, hc::Cause::kDelay},
      {hc::Cause::kAsymmetry, hc::Cause::kDelay},
      {hc::Cause::kDynamics, hc::Cause::kRateDependence},
      {hc::Cause::kCreep, hc::Cause::kDelay},
      {hc::Cause::kAsymmetry, hc::Cause::kRateDependence},
      {hc::Cause::kDelay, hc::Cause::kDrift}};
  for (std::size_t i = 0; i < std::size(pairs); ++i) {
    HiddenCase c{pairs[i].first, kSweepRates[i], ++seed};
    c.also = pairs[i].second;
    c.widening_thresholds = i % 2 == 0;
    cases.push_back(c);
  }
  if (only != nullptr) {
    std::erase_if(cases, [&](const HiddenCase& c) {
      return hc::to_string(c.cause) != only && hc::to_string(c.also) != only;
    });
  }
  return cases;
}

// What the sweep counts over its cases.
struct SweepTally {
  std::map<std::pair<int, int>, int> confusion;
  // Per cause: named anywhere in a case (random walks aside) that does not hide it. The shape
  // (asymmetry) is the Preisach base's own and may be named in any case.
  std::map<int, int> named_not_hidden;
  std::vector<double> walk_ratios;
  std::map<int, std::vector<double>> ratios, raw_ratios;
  std::map<int, std::pair<int, int>> recall;  // per hidden cause: named anywhere, cases
  int wrong = 0, count = 0, bad_ratio = 0, combined = 0, both_named = 0, rate_as_delay = 0,
      delay_as_rate = 0;
  double slowest = 0.0;
  std::size_t slowest_samples = 0;
};

bool named_anywhere(const Outcome& o, hc::Cause h) {
  return std::any_of(o.diagnosis.causes.begin(), o.diagnosis.causes.end(),
                     [&](const hc::NamedCause& n) { return n.cause == h; });
}

// Counts what a case (random walks aside) names where it does not hide it, and its recall.
void count_names(SweepTally& tally, const HiddenCase& c, const Outcome& o) {
  if (c.random_walk) return;
  for (const hc::NamedCause& n : o.diagnosis.causes) {
    const bool hidden = n.cause == c.cause || n.cause == c.also;
    if (!hidden && n.cause != hc::Cause::kAsymmetry)
      ++tally.named_not_hidden[static_cast<int>(n.cause)];
  }
  for (const hc::Cause h : {c.cause, c.also}) {
    if (h == hc::Cause::kNone) continue;
    auto& [hit, n] = tally.recall[static_cast<int>(h)];
    hit += named_anywhere(o, h) ? 1 : 0;
    ++n;
  }
}

// A case of two effects: whether both are named, printed.
void count_combined(SweepTally& tally, const HiddenCase& c, const HiddenData& d, const Outcome& o) {
  ++tally.combined;
  const bool both = named_anywhere(o, c.cause) && named_anywhere(o, c.also);
  tally.both_named += both ? 1 : 0;
  std::printf("%-52s %-6s named", name_of(c).c_str(), both ? "both" : "MISSED");
  for (const auto& n : o.diagnosis.causes) {
    std::printf(" %s (%.2f)", std::string(hc::to_string(n.cause)).c_str(), n.gain);
  }
  std::printf("  %.2f s\n", o.seconds);
  if (!both) std::printf("  truth: %s\n%s", d.truth.c_str(), summary(o).c_str());
  std::fflush(stdout);
}

// Each candidate's own model on the second record, against the baseline.
void print_candidates_on_the_second_record(const HiddenData& d, const Outcome& o) {
  const Record& r2 = d.second_without_drift;
  const double dt2 = r2.t[1] - r2.t[0];
  const double base = hc::validate_model(o.diagnosis.baseline, r2.u, r2.y, dt2).rmse;
  std::printf("  on the second record:");
  for (const hc::CandidateReport& cr : o.diagnosis.candidates) {
    std::printf(" %s %.3f", std::string(hc::to_string(cr.cause)).c_str(),
                hc::validate_model(cr.model, r2.u, r2.y, dt2).rmse / base);
  }
  std::printf("\n");
}

// A case of one effect (or none): its confusion cell, its second-record ratio, whether it is
// right, printed.
void count_single(SweepTally& tally, const HiddenCase& c, const HiddenData& d, const Outcome& o,
                  bool verbose) {
  const hc::Cause cause = c.cause;
  ++tally
        .confusion[{c.random_walk ? kWalkRow : static_cast<int>(cause), static_cast<int>(o.named)}];
  if (cause == hc::Cause::kRateDependence && named_anywhere(o, hc::Cause::kDelay))
    ++tally.rate_as_delay;
  if (cause == hc::Cause::kDelay && named_anywhere(o, hc::Cause::kRateDependence))
    ++tally.delay_as_rate;
  // With nothing hidden, the base's own shape may be named (see diagnosis_test_support.hpp).
  const bool shape_only = cause == hc::Cause::kNone && o.named == hc::Cause::kAsymmetry;
  const bool ratio_checked = (cause != hc::Cause::kNone || shape_only) && !c.random_walk;
  if (ratio_checked) tally.ratios[static_cast<int>(cause)].push_back(o.ratio);
  if (ratio_checked) tally.raw_ratios[static_cast<int>(cause)].push_back(o.raw_ratio);
  if (c.random_walk) tally.walk_ratios.push_back(o.ratio);
  const bool ok =
      (o.named == cause || shape_only) && (!ratio_checked || o.ratio <= max_ratio(cause));
  // Reported in their own rows, not asserted: random walks, the harder class beyond the
  // causes (a walk's fast part is not a slow drift), and rate dependence, whose weaker cases
  // gain less than the naming asks beside the loop's shape the baseline misses (behind a
  // switching front or with widening thresholds alike). That a rate effect is never called
  // delay, nor a delay rate dependence, is asserted.
  const bool reported = c.random_walk || cause == hc::Cause::kRateDependence;
  if (!ok && !reported) ++tally.wrong;
  if (ratio_checked && !reported && o.ratio > max_ratio(cause)) ++tally.bad_ratio;
  if (o.seconds > tally.slowest) tally.slowest = o.seconds, tally.slowest_samples = o.samples;
  std::printf("%-52s %-6s named %-16s ratio %.3f (raw %.3f) gain %7.2f  %.2f s / %zu samples\n",
              name_of(c).c_str(), ok ? "ok" : "WRONG", std::string(hc::to_string(o.named)).c_str(),
              o.ratio, o.raw_ratio, o.gain, o.seconds, o.samples);
  if (!ok || verbose) std::printf("  truth: %s\n%s", d.truth.c_str(), summary(o).c_str());
  if (verbose) print_candidates_on_the_second_record(d, o);
  std::fflush(stdout);
}

// The confusion table of the single effects, the recall per hidden cause, what was named where
// not hidden, and the combined cases.
void print_confusion(SweepTally& tally) {
  std::printf("\nconfusion of the single effects (rows: hidden, columns: named), %d cases\n%-16s",
              tally.count - tally.combined, "");
  for (const hc::Cause n : kSweepCauses) {
    std::printf("%9.8s", std::string(hc::to_string(n)).c_str());
  }
  std::printf("\n");
  std::vector<std::pair<std::string, int>> rows;
  rows.reserve(kSweepCauses.size() + 1);
  for (const hc::Cause h : kSweepCauses) rows.emplace_back(hc::to_string(h), static_cast<int>(h));
  rows.emplace_back("drift (walk)", kWalkRow);
  for (const auto& [label, row] : rows) {
    std::printf("%-16s", label.c_str());
    for (const hc::Cause n : kSweepCauses) {
      std::printf("%9d", tally.confusion[{row, static_cast<int>(n)}]);
    }
    std::printf("\n");
  }
  std::printf("\nrecall per hidden cause (named anywhere in causes[], single and combined):\n");
  for (const auto& [cause, hits] : tally.recall) {
    std::printf("  %-16s %d / %d (%.0f %%)\n",
                std::string(hc::to_string(static_cast<hc::Cause>(cause))).c_str(), hits.first,
                hits.second, 100.0 * hits.first / std::max(hits.second, 1));
  }
  std::printf("named where not hidden (random walks aside, the shape allowed):");
  for (const auto& [cause, n] : tally.named_not_hidden) {
    std::printf(" %s %d", std::string(hc::to_string(static_cast<hc::Cause>(cause))).c_str(), n);
  }
  std::printf("\n");
  std::printf(
      "both effects named in %d of %d combined cases; rate dependence called delay %d, delay "
      "called rate dependence %d\n",
      tally.both_named, tally.combined, tally.rate_as_delay, tally.delay_as_rate);
}

// The second record's ratios per cause, median and worst (each list sorted in place).
void print_ratios(SweepTally& tally) {
  std::printf(
      "\nextended / baseline rms on the second record (median, worst; raw: from its first "
      "sample):\n");
  for (auto& [cause, v] : tally.ratios) {
    std::vector<double>& raw = tally.raw_ratios[cause];
    std::sort(v.begin(), v.end());
    std::sort(raw.begin(), raw.end());
    std::printf("  %-16s %.3f  %.3f   raw %.3f  %.3f\n",
                std::string(hc::to_string(static_cast<hc::Cause>(cause))).c_str(), v[v.size() / 2],
                v.back(), raw[raw.size() / 2], raw.back());
  }
}

}  // namespace

TEST(DiagnosisHiddenEffect, RandomisedSweepConfusionTable) {
  if (!long_tests()) GTEST_SKIP() << "set HYSTBENCH_LONG_TESTS=1 for the 72-case sweep";
  // HYSTBENCH_SWEEP_SEED draws another set of cases.
  const char* base = std::getenv("HYSTBENCH_SWEEP_SEED");
  const std::uint64_t seed = base != nullptr ? std::strtoull(base, nullptr, 10) : 1000;
  // HYSTBENCH_SWEEP_CAUSE runs the cases that hide that cause only (seeds as in the whole sweep).
  const char* only = std::getenv("HYSTBENCH_SWEEP_CAUSE");
  const bool verbose = std::getenv("HYSTBENCH_SWEEP_VERBOSE") != nullptr;  // every case's report
  SweepTally tally;
  for (const HiddenCase& c : sweep_cases(seed, only)) {
    const HiddenData d = make_hidden(c);
    const Outcome o = diagnose_case(d);
    ++tally.count;
    count_names(tally, c, o);
    if (c.also != hc::Cause::kNone) {
      count_combined(tally, c, d, o);
    } else {
      count_single(tally, c, d, o, verbose);
    }
  }
  print_confusion(tally);
  print_ratios(tally);
  // A fitted resonance carries over to another record of the same actuator.
  if (const auto& dyn = tally.ratios[static_cast<int>(hc::Cause::kDynamics)]; !dyn.empty()) {
    EXPECT_LE(dyn.back(), 0.6);
  }
  std::vector<double>& walk_ratios = tally.walk_ratios;
  std::sort(walk_ratios.begin(), walk_ratios.end());
  if (!walk_ratios.empty()) {
    std::printf(
        "  %-16s %.3f  %.3f  (random-walk drift: naming and ratio reported, not asserted)\n",
        "drift (walk)", walk_ratios[walk_ratios.size() / 2], walk_ratios.back());
  }
  std::printf("slowest diagnosis: %.2f s for %zu samples\n", tally.slowest, tally.slowest_samples);
  EXPECT_EQ(tally.wrong, 0);
  EXPECT_EQ(tally.bad_ratio, 0);
  EXPECT_EQ(tally.rate_as_delay, 0);
  EXPECT_EQ(tally.delay_as_rate, 0);
}

// Many draws of the cases a delay and a rate law are hardest to tell apart in: a delay, a rate law
// (widening thresholds, a switching front) and a widening law beside a delay, 60 each at 100,
// 200, 500 and 1000 Hz (at 100-200 Hz every delay is 1 sample). Prints per kind and rate how
// often each was named; asserts that a rate law alone is never called delay, and that a delay
// alone is named in 95 % of its draws.
TEST(DiagnosisHiddenEffect, RateOrDelayDraws) {
  if (!long_tests()) GTEST_SKIP() << "set HYSTBENCH_LONG_TESTS=1 for the 960 draws";
  const double rates[] = {100.0, 200.0, 500.0, 1000.0};
  const std::uint64_t first = 5000, draws = 60;
  enum Kind { kDelayAlone, kWideningLaw, kSwitchingFront, kLawAndDelay };
  const char* labels[] = {"delay", "widening law", "switching front", "widening law + delay"};
  int rate_called_delay = 0, delays_named = 0, delay_cases = 0;
  std::printf("%-22s %6s %8s %8s %8s\n", "hidden", "Hz", "delay", "rate", "both");
  for (const Kind kind : {kDelayAlone, kWideningLaw, kSwitchingFront, kLawAndDelay}) {
    for (const double fs : rates) {
      int delay = 0, rate = 0, both = 0;
      for (std::uint64_t seed = first; seed < first + draws; ++seed) {
        HiddenCase c{kind == kDelayAlone ? hc::Cause::kDelay : hc::Cause::kRateDependence, fs,
                     seed};
        c.widening_thresholds = kind != kSwitchingFront && kind != kDelayAlone;
        if (kind == kLawAndDelay) c.also = hc::Cause::kDelay;
        const Outcome o = diagnose_case(make_hidden(c));
        const std::vector<hc::Cause> named = named_causes(o.diagnosis);
        const bool d = names(named, hc::Cause::kDelay),
                   r = names(named, hc::Cause::kRateDependence);
        delay += d ? 1 : 0, rate += r ? 1 : 0, both += d && r ? 1 : 0;
      }
      std::printf("%-22s %6.0f %8d %8d %8d  of %llu\n", labels[kind], fs, delay, rate, both,
                  static_cast<unsigned long long>(draws));
      std::fflush(stdout);
      if (kind == kWideningLaw || kind == kSwitchingFront) rate_called_delay += delay;
      if (kind == kDelayAlone) delays_named += delay, delay_cases += static_cast<int>(draws);
    }
  }
  EXPECT_EQ(rate_called_delay, 0);
  EXPECT_GE(delays_named, 0.95 * delay_cases);
}

}  // namespace hystbench::test::diagnosis
