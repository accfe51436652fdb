// A user's trajectory or drive read from a file for upload: a missing column is named with the
// option of the command that reads it.
#include "hystbench/cli/remote/remote_commands.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "hystbench/cli/offline/data_table.hpp"
#include "support/temp_dir_test.hpp"

namespace cli = hystbench::cli;

namespace {

class ReadUploadTest : public hystbench::test::TempDirTest {
 protected:
  ReadUploadTest() : TempDirTest("hystbench_read_upload_test") {}
  std::string file() {
    std::string p = path("line.csv");
    std::ofstream(p) << "t,pos\n0,1\n0.001,2\n0.002,3\n";
    return p;
  }
  std::string error_of(const std::string& kind, const std::string& column) {
    try {
      (void)cli::read_upload(file(), kind, "t", column, 1.0, 0.0);
    } catch (const cli::DataFileError& e) {
      return e.what();
    }
    return "no error";
  }
};

// A completed track run's result with its error figures and nothing else.
nlohmann::json track_result(const std::string& run_id) {
  return {{"run_id", run_id},         {"kind", "track"},     {"end", "completed"},
          {"samples", 100},           {"rms_error_um", 0.1}, {"rms_error_percent", 1.0},
          {"range_um", 10.0},         {"max_error_um", 0.3}, {"max_error_percent", 3.0},
          {"hysteresis_percent", 0.5}};
}

}  // namespace

TEST_F(ReadUploadTest, AMissingColumnIsNamedWithTheCommandsOption) {
  EXPECT_NE(error_of("reference", "yr")
                .find("no reference column 'yr' (columns: t, pos); name "
                      "it with --yr-column"),
            std::string::npos)
      << error_of("reference", "yr");
  EXPECT_NE(error_of("drive", "u")
                .find("no drive column 'u' (columns: t, pos); name it with "
                      "--u-column"),
            std::string::npos)
      << error_of("drive", "u");
  const cli::RemoteUpload read = cli::read_upload(file(), "reference", "t", "pos", 2.0, 0.0);
  ASSERT_EQ(read.values.size(), 3u);
  EXPECT_DOUBLE_EQ(read.values[2], 6.0);
  EXPECT_EQ(read.param, "reference_upload");
}

// A tracking run's printed result says where its largest errors fell (the log's index), and a
// result without the index (an older daemon's) prints without it.
TEST(PrintRunResult, SaysWhereTheLargestErrorsFell) {
  nlohmann::json r = {{"run_id", "r1"},
                      {"kind", "track"},
                      {"end", "completed"},
                      {"samples", 100},
                      {"rms_error_um", 0.1},
                      {"rms_error_percent", 1.0},
                      {"range_um", 10.0},
                      {"max_error_um", 0.3},
                      {"max_error_percent", 3.0},
                      {"max_error_index", 41},
                      {"hysteresis_percent", 0.5},
                      {"model_rms_error_um", 0.2},
                      {"model_rms_error_percent", 2.0},
                      {"model_max_error_um", 0.9},
                      {"model_max_error_percent", 9.0},
                      {"model_max_error_index", 17}};
  std::ostringstream out;
  cli::print_run_result(r, out);
  EXPECT_NE(out.str().find("0.3000 um (3.000 %, at index 41)"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("0.9000 um (9.000 %, at index 17)"), std::string::npos) << out.str();
  r.erase("max_error_index");
  std::ostringstream older;
  cli::print_run_result(r, older);
  EXPECT_NE(older.str().find("0.3000 um (3.000 %)"), std::string::npos) << older.str();
}

// A learning run's printed result gives the bench's floor, and where a trial at it had its drive
// played again, that pair's floor beside the first; where the best drive's replays did not
// repeat its error, a line says so.
TEST(PrintRunResult, GivesTheLearningsFloorAndWhereItWasMeasuredAgain) {
  nlohmann::json r = track_result("r2");
  r["learning"] = {
      {"trials", nlohmann::json::array()},
      {"frequency_hz", 50.0},
      {"cutoff_hz", 200.0},
      {"why", "every trial asked for was played"},
      {"best_trial", 11},
      {"floor",
       {{"rms_error_percent", 0.020}, {"first_rms_error_percent", 0.039}, {"trials", {8, 9}}}}};
  std::ostringstream again;
  cli::print_run_result(r, again);
  EXPECT_NE(again.str().find("floor           0.020 % rms (trials 8 and 9, the same drive); "
                             "0.039 % on trials 0 and 1"),
            std::string::npos)
      << again.str();
  r["learning"]["floor"]["trials"] = {0, 1};
  std::ostringstream first;
  cli::print_run_result(r, first);
  EXPECT_NE(first.str().find("floor           0.020 % rms (trials 0 and 1, the same drive)\n"),
            std::string::npos)
      << first.str();
  // The best drive's replays: a line only where they did not repeat its error.
  EXPECT_EQ(first.str().find("best replayed"), std::string::npos) << first.str();
  r["learning"]["best_replayed"] = {{"trial", 3},
                                    {"rms_error_percent", 0.114},
                                    {"replays_rms_percent", {0.374, 0.543}},
                                    {"held", false},
                                    {"meaning", "it does not repeat"}};
  std::ostringstream replayed;
  cli::print_run_result(r, replayed);
  EXPECT_NE(replayed.str().find("best replayed   trial 3's drive: rms % 0.374 0.543 (its own "
                                "0.114): it does not repeat\n"),
            std::string::npos)
      << replayed.str();
  r["learning"]["best_replayed"]["held"] = true;
  std::ostringstream held;
  cli::print_run_result(r, held);
  EXPECT_EQ(held.str().find("best replayed"), std::string::npos) << held.str();
}

// A periodic reference's run names the resonators its loop ran beside, or says it ran none.
TEST(PrintRunResult, NamesTheResonatorsAtTheReferencesHarmonics) {
  nlohmann::json r = track_result("r4");
  r["feedback"] = {{"gains", "designed"},
                   {"structure", "integral"},
                   {"margins", nlohmann::json::array()},
                   {"harmonics",
                    {{"fundamental_hz", 50.0},
                     {"resonators", 2},
                     {"kept", {{{"frequency_hz", 100.0}}, {{"frequency_hz", 150.0}}}},
                     {"settle_s", 0.32}}}};
  std::ostringstream kept;
  cli::print_run_result(r, kept);
  EXPECT_NE(kept.str().find("harmonics       resonators at 2 of the reference's harmonics (100, "
                            "150 Hz), settled in about 0.320 s"),
            std::string::npos)
      << kept.str();
  r["feedback"]["harmonics"] = {{"fundamental_hz", 1.0}, {"resonators", 0}};
  std::ostringstream none;
  cli::print_run_result(r, none);
  EXPECT_NE(none.str().find("harmonics       no resonator"), std::string::npos) << none.str();
}

// Without an active model the daemon predicts y with the straight line of the configured
// limits: the report leaves out the model's error then (it measures the line), on one axis and
// on each axis of a stage, and gives it where a model predicted.
TEST(PrintRunResult, GivesTheModelErrorOnlyWhereAModelPredicted) {
  nlohmann::json r = {{"run_id", "r3"},
                      {"kind", "identify"},
                      {"end", "completed"},
                      {"samples", 100},
                      {"model_rms_error_um", 2.55},
                      {"model_rms_error_percent", 4.2},
                      {"model_max_error_um", 16.3},
                      {"model_max_error_percent", 26.861},
                      {"y_model", "linear map of limits.y_min..y_max, stepped with u"},
                      {"y_model_from", "limits"}};
  std::ostringstream line;
  cli::print_run_result(r, line);
  EXPECT_EQ(line.str().find("model vs bench"), std::string::npos) << line.str();
  r["y_model"] = "the model active before this identification";
  r["y_model_from"] = "model";
  std::ostringstream model;
  cli::print_run_result(r, model);
  EXPECT_NE(model.str().find("model vs bench  rms 2.5500 um (4.200 %)   max"), std::string::npos)
      << model.str();
  // With its mean, the rms about it: sqrt(2.55^2 - 2.4^2) = 0.8617.
  r["model_mean_error_um"] = 2.4;
  std::ostringstream offset;
  cli::print_run_result(r, offset);
  EXPECT_NE(offset.str().find("rms 2.5500 um (4.200 %), mean 2.4000 um and 0.8617 um about it"),
            std::string::npos)
      << offset.str();
  const nlohmann::json stage = {{"run_id", "r4"},
                                {"end", "completed"},
                                {"axes", {{"x", {{"model_rms_error_um", 2.55}}}}},
                                {"y_model", "linear map of limits.y_min..y_max, stepped with u"},
                                {"y_model_from", "limits"}};
  std::ostringstream axes;
  cli::print_run_result(stage, axes);
  EXPECT_EQ(axes.str().find("model vs bench"), std::string::npos) << axes.str();
}

namespace {
// What `hystbench identify` prints for a completed identify whose model carries `extension`.
std::string identify_text(const nlohmann::json& extension) {
  const nlohmann::json r = {{"run_id", "r2"},
                            {"kind", "identify"},
                            {"end", "completed"},
                            {"model", {{"type", "mpi"}, {"extension", extension}}}};
  std::ostringstream out;
  cli::print_run_result(r, out);
  return out.str();
}
}  // namespace

// identify's extension adopted in part: its model's check, and its fast parts alone with their
// verified figures and the decision, one line each.
TEST(PrintRunResult, SaysWhichPartsOfTheExtensionWereAdopted) {
  const nlohmann::json extension = {
      {"parts",
       {{{"cause", "delay"}, {"heldout_gain", 1.36}, {"adopted", true}},
        {{"cause", "creep"}, {"heldout_gain", 1.01}, {"adopted", false}}}},
      {"adopted", true},
      {"why", "its fast parts alone track better on the bench; the whole extension does not"},
      {"check", {{"passed", true}, {"inverse_rms_percent", 0.0004}}},
      {"fast_parts",
       {{"parts", {"delay"}},
        {"left_out", {"creep"}},
        {"adopted", true},
        {"why", "they track better on the bench"},
        {"verified",
         {{"triangle_rms_percent", {{"model", 0.165}, {"extended", 0.107}}},
          {"fast_hz", 500.0},
          {"fast_rms_percent", {{"model", 15.78}, {"extended", 0.555}}}}}}}};
  const std::string text = identify_text(extension);
  EXPECT_NE(text.find("delay (held-out gain 1.36x) + creep (held-out gain 1.01x): adopted, its "
                      "fast parts alone track better"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("extension model checked: driven by its inverse it tracks a triangle over "
                      "90 % of its range at 0.000 % rms"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("extension fast  delay alone (without creep): triangle rms 0.165 -> 0.107 "
                      "%, 500 Hz sine rms 15.780 -> 0.555 %: adopted, they track better"),
            std::string::npos)
      << text;
}

// The whole extension failed its check; its mode alone failed it too, by no more than the model
// it extends (their static part is the same), so it was played: both figures are printed.
TEST(PrintRunResult, SaysWhenAModeWasPlayedThoughItsCheckFailedAsItsBasesDoes) {
  const nlohmann::json accepted = {
      {"passed", false},
      {"inverse_rms_percent", 25.793},
      {"base", {{"passed", false}, {"inverse_rms_percent", 25.793}}},
      {"accepted", "its inverse misses no more than its base's, which identify keeps without it"}};
  const nlohmann::json extension = {
      {"parts", {{{"cause", "dynamics"}, {"heldout_gain", 1.39}, {"adopted", true}}}},
      {"adopted", true},
      {"why", "its fast parts alone track better on the bench; the whole extension does not"},
      {"check", {{"passed", false}, {"inverse_rms_percent", 0.743}}},
      {"fast_parts",
       {{"parts", {"dynamics"}},
        {"left_out", {"rate_dependence"}},
        {"adopted", true},
        {"why", "they track better on the bench"},
        {"check", accepted}}}};
  const std::string text = identify_text(extension);
  EXPECT_NE(text.find("extension fast checked: driven by its inverse it misses a triangle over 90 "
                      "% of its range by 25.793 % rms, its base by 25.793 %: played, as its "
                      "inverse misses no more than its base's"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("extension model checked"), std::string::npos) << text;
}

// The steps timed the mode and the delay off the diagnosis's: what the record named when diagnosed
// again on them is said, and so is nothing.
TEST(PrintRunResult, SaysWhatTheDiagnosisOnTheTimedModeNamed) {
  nlohmann::json extension = {
      {"parts",
       {{{"cause", "dynamics"}, {"heldout_gain", 1.33}, {"adopted", true}},
        {{"cause", "loop_shape"}, {"heldout_gain", 1.83}, {"adopted", true}}}},
      {"adopted", true},
      {"why", "it tracks better on the bench"},
      {"after_timing", {{"named", {"loop_shape", "creep"}}, {"verdict", "loop_shape: ..."}}}};
  EXPECT_NE(identify_text(extension).find(
                "extension diagnosed again on the timed mode and delay: named loop_shape + "
                "creep\n"),
            std::string::npos)
      << identify_text(extension);
  extension["after_timing"]["named"] = nlohmann::json::array();
  EXPECT_NE(identify_text(extension).find("on the timed mode and delay: nothing more named"),
            std::string::npos)
      << identify_text(extension);
}

// tune on a stage: each axis's loop, then the loops together, with the factor they were lowered
// by where the coupling asked for it.
TEST(PrintTuneResult, OnAStageGivesEachAxisAndTheLoopsTogether) {
  const nlohmann::json axis = {{"responses_from", "r1-frf"},
                               {"structure", "integral, notch at 2930 Hz"},
                               {"gains", "designed"},
                               {"crossover_hz", 271.0},
                               {"limited_by", "coupling"},
                               {"limit", "lowered x0.592 from its design alone"},
                               {"margins", nlohmann::json::array()}};
  nlohmann::json r = {{"compensator", "inverse+pid"},
                      {"axes", {{"x", axis}, {"y", axis}}},
                      {"feedback_interaction",
                       {{"peak", 0.7},
                        {"peak_hz", 1490.0},
                        {"dominant", true},
                        {"designed_together", {{"peak_alone", 1.62}, {"lowered_by", 0.592}}}}}};
  std::ostringstream out;
  cli::print_tune_result(r, out);
  const std::string text = out.str();
  EXPECT_NE(text.find("axis x (responses of r1-frf)"), std::string::npos) << text;
  EXPECT_NE(text.find("axis y (responses of r1-frf)"), std::string::npos) << text;
  EXPECT_NE(text.find("coupling: lowered x0.592"), std::string::npos) << text;
  EXPECT_NE(text.find("0.70 at 1490 Hz (below 1: stable together); each loop lowered by 0.59 "
                      "from 1.62"),
            std::string::npos)
      << text;
  // Loops that needed no lowering, and no cross responses: nothing said of either.
  r["feedback_interaction"]["designed_together"]["lowered_by"] = 1.0;
  std::ostringstream unlowered;
  cli::print_tune_result(r, unlowered);
  EXPECT_EQ(unlowered.str().find("lowered by"), std::string::npos) << unlowered.str();
  r.erase("feedback_interaction");
  std::ostringstream alone;
  cli::print_tune_result(r, alone);
  EXPECT_EQ(alone.str().find("together"), std::string::npos) << alone.str();
}
