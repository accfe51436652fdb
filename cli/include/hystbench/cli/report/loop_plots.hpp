#pragma once
// Pictures of the stage's measured frequency responses and of the feedback loop designed on
// them, written as PNGs by gnuplot (their data and script beside them):
//   response.png     each measured response: magnitude [um/V] and phase [deg] against frequency
//                    (log axis), its coherence below (`frf --wait --plot DIR`)
//   loop-bode.png    the loop L = C z^-1 P on each response the loop sees: |L| and arg L, the
//                    crossover and the phase margin marked, and the -180 degree line
//   nyquist.png      L in the complex plane, the -1 point, the circle |1 + L| = 1/|S|max that
//                    the peak-sensitivity target keeps L outside of
//   sensitivity.png  |S| and |T| against frequency, the -3 dB and +6 dB lines
// (`tune --plot DIR`). Not real-time.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <vector>

namespace hystbench::cli {

/// `measured`: the stage's responses as model files keep them (frequency_response). Throws
/// std::runtime_error naming the cause (no response, gnuplot missing or failing).
std::vector<std::filesystem::path> plot_responses(const nlohmann::json& measured,
                                                  const std::filesystem::path& dir);

/// `design`: tune's reply (its curves, margins and targets).
std::vector<std::filesystem::path> plot_loop(const nlohmann::json& design,
                                             const std::filesystem::path& dir);

}  // namespace hystbench::cli
