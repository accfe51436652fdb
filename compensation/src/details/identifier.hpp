#pragma once
// The search behind fit_model() (identification internals): the delay, then the best of the
// model families the options allow by held-out error, its thresholds refined, creep lags, the
// nesting checks and the fall-back to the classical PI. Not real-time: allocates, fits many
// candidates.
//
// The families are the rows of Identifier::families() (identification/family_table.cpp): each
// names its ModelKind and the member function that fits it, defined in a file of its own
// (identification/<family>_family.cpp). A family is added as that file and a row.
#include <algorithm>
#include <array>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "details/designs.hpp"
#include "details/identification_record.hpp"
#include "hystbench/compensation/identification.hpp"
#include "hystbench/compensation/thresholds_rate_law.hpp"

namespace hystbench::compensation::details::identification {

// Dead zones per side where the order search needs a start (the delay search, the modified PI's
// first play count).
inline constexpr int kDefaultDeadZones = 2;
// A larger model must beat the best smaller one by more than this (relative) to be chosen.
inline constexpr double kParsimony = 0.01;
// Caps of the rate law tried, as fractions of the record's largest smooth rate.
inline constexpr double kRateCapFractions[] = {1.0, 0.8, 0.64, 0.51};

class Identifier {
 public:
  Identifier(std::span<const double> t, std::span<const double> u, std::span<const double> y,
             const FitOptions& options);

  FitResult run();

 private:
  // One model family identify can fit: a row of families().
  struct Family {
    ModelKind kind;
    // Tried when FitOptions::kind is automatic.
    bool in_auto;
    // Fits the family to the record, its order by held-out error.
    Candidate (Identifier::*search)();
    // With in_auto: why the record cannot judge the family in the automatic choice (empty: it
    // is tried). Null: always tried.
    std::string (Identifier::*auto_skip)() const;
    // After refinement and creep: replaces the family's fit by the simpler model it extends
    // when that is as good. Null: none beyond the fall-back to the classical PI, every family's.
    void (Identifier::*check_nesting)(Candidate& best);
  };
  // The families, in the order the automatic choice tries them (the first of equal scores wins).
  static std::span<const Family> families();
  // The row of `kind`; nullptr when identify has no search for it.
  static const Family* family(ModelKind kind);

  // The best of the families the options allow, by held-out error (auto skips rpi on a record
  // of a single excitation rate); throws std::logic_error when none is invertible.
  Candidate search_families();
  // Replaces `best` by the model it nests when that is as good (rpi, cpi over the modified PI).
  void check_nesting(Candidate& best);
  // A family asked for falls back to the classical PI it contains when that scores better; the
  // note and the PI's own delay come with it.
  void fall_back_to_pi(Candidate& best, int& delay, std::vector<std::string>& notes);
  // The FitResult of `best` at `delay` samples, scored on the record (its drift removed from
  // r_.y), with the notes.
  FitResult scored_result(Candidate& best, int delay, std::vector<std::string> notes);
  void progress(double fraction, const std::string& what) const {
    if (o_.progress) o_.progress(fraction, what);
  }
  // Progress within the current stage [stage_begin_, stage_begin_ + stage_span_].
  void stage_progress(double fraction, const std::string& what) const {
    progress(stage_begin_ + stage_span_ * fraction, what);
  }

  ModelStructure structure(ModelKind kind, int plays, int dead_zones) const;
  // Fitted on every stride-th row of the fitted part (fit_design), scored on every sample.
  Candidate evaluate(const ModelStructure& s, std::string method, std::size_t stride = 1);
  // The fit log's row of a candidate evaluated on the record (FitResult::candidates).
  void log_fit(const Candidate& c);
  // evaluate() of each structure, on the machine's cores; the results and the log in the
  // structures' order (the same as evaluated one after another).
  std::vector<Candidate> evaluate_each(const std::vector<ModelStructure>& structures,
                                       const std::string& method, std::size_t stride = 1);
  Candidate& memo(ModelKind kind, int plays, int dead_zones,
                  std::array<double, 3> cp = {1.0, 1.0, 1.0});
  std::vector<int> operator_grid(int extra_unknowns) const;
  std::vector<int> dead_zone_grid() const;
  // Among candidates in increasing complexity, the smallest within kParsimony of the best.
  template <class Key, class Eval>
  Key pick(const std::vector<Key>& keys, Eval eval);

  int choose_delay(ModelKind kind);
  Candidate search(ModelKind kind);
  // The families' searches (identification/<family>_family.cpp).
  Candidate search_pi();
  Candidate search_mpi();
  Candidate search_cpi();
  Candidate search_rpi();
  Candidate search_preisach();
  // The nesting checks of the families that extend the modified PI.
  void check_rpi_nesting(Candidate& best);
  void check_cpi_nesting(Candidate& best);
  // Why the automatic choice skips rpi on this record (empty: it does not).
  std::string rpi_auto_skip() const;
  // The Preisach plane over the fitted input range, its output map and smoothness by held-out
  // error (preisach_identification.hpp), creep lags and a drift beside its cells.
  Candidate plane_fit(const std::vector<double>& creep_time_constants);
  // The plane's relays widening with the rate, over the plane c found (its map and smoothness).
  void add_plane_rate_law(Candidate& c);
  // The rate law over one modified PI's plays and dead zones: its nested self, the joint fits
  // over the rate filters and caps, the paper's rate-group regression; the best by held-out.
  Candidate rpi_over(const Candidate& mpi);
  // search_rpi()'s candidate on the modified PI's own order, when another order scored better.
  std::optional<Candidate> rpi_by_mpi_order_;
  // The plane's rate law as the first plane search found it (its structure), or that it found
  // none (nullopt inside): the plane with creep lags refits it rather than search again. Seeded
  // from FitOptions::preisach_given_rate_law.
  std::optional<std::optional<ThresholdsRateLaw>> plane_law_;
  // The thresholds law over one rate-dependent structure: the widening and the rate filter
  // chosen by the fit's error; empty when the record has no input span or rate.
  Candidate thresholds_law_over(ModelStructure s);
  Candidate nested_rpi(const Candidate& mpi, const ModelStructure& s);
  Candidate nested_cpi(const Candidate& mpi);
  /// Scores a nested model `m` (base with a zero extension) as c, with base's creep and method +
  /// note.
  void finish_nested(Candidate& c, ActuatorModel m, const Candidate& base, const char* note);
  void refine(Candidate& c);
  void add_creep(Candidate& c);
  // What the chosen candidate gets after the search (refinement, creep, as the options ask), for
  // a rival it is compared with.
  void finish(Candidate& c);
  // The modified PI's plays for m dead zones per side, by held-out error.
  int mpi_plays(int m);
  std::vector<double> creep_time_constants() const;

  FitOptions o_;
  Record r_;
  double center_ = 0.0;
  std::map<std::tuple<ModelKind, int, int, std::array<double, 3>>, Candidate> memo_;
  std::optional<Candidate> best_mpi_;
  std::vector<FitCandidate> log_;
  double stage_begin_ = 0.0;
  double stage_span_ = 0.0;
};

template <class Key, class Eval>
Key Identifier::pick(const std::vector<Key>& keys, Eval eval) {
  std::vector<double> scores;
  scores.reserve(keys.size());
  for (const Key& k : keys) scores.push_back(eval(k));
  const double best = *std::min_element(scores.begin(), scores.end());
  const double tolerance = best * kParsimony + 1e-9 * (r_.y_hi - r_.y_lo);
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (scores[i] <= best + tolerance) return keys[i];
  }
  return keys.front();
}

}  // namespace hystbench::compensation::details::identification
