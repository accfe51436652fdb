#include "diagnosis/details/report/reasons.hpp"

#include "diagnosis/details/number_text.hpp"

namespace hystbench::compensation::details::diagnosis {

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  }
  return s;
}

std::string left_out_summary(const CandidateReport& c) {
  std::string s;
  for (const LeftOutScore& l : c.left_out) {
    s += (s.empty() ? "" : ", ") + l.record + " " + num(l.gain);
  }
  return s;
}

std::string within_noise(const std::string& before, double added_rms, double allowance,
                         const std::string& unit) {
  return "within the noise of " + before + ": added to the model holding " + before +
         ", it explains " + num(added_rms) + " " + unit +
         " rms more of the held-out error, less than the " + num(allowance) + " " + unit +
         " the noise allows";
}

std::string not_named_reason(const AddedJudgement& j, const std::string& before,
                             const std::string& unit) {
  using Verdict = AddedJudgement::Verdict;
  switch (j.verdict) {
    case Verdict::kWithinNoise:
      return within_noise(before, j.added_rms, j.allowance, unit);
    case Verdict::kBelowMinGain:
      return "its held-out gain " + num(j.gain) + (j.over_shape ? " over the shape" : "") +
             " is below " + num(j.min_gain) + ", and added to the model holding " + before +
             " it gains " + num(j.added_gain) + ", below " + num(j.needed);
    case Verdict::kMostlyTheirs:
      // Its own gain was mostly the stronger causes' (a rate law widening the loop as a delay
      // does): added to them it explains little.
      return "its held-out gain " + num(j.gain) + (j.over_shape ? " over the shape" : "") +
             " is mostly that of " + before + ": added to the model holding it, " +
             num(j.added_gain) + ", below " + num(j.needed);
    case Verdict::kNamed:
      break;
  }
  return "";
}

}  // namespace hystbench::compensation::details::diagnosis
