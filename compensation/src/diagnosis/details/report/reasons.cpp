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

}  // namespace hystbench::compensation::details::diagnosis
