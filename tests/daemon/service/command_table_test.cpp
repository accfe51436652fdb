// The socket commands' table and its one validator, without a bench: every refusal is
// bad_params naming the key (unknown, wrong type, out of range) before any handler runs.
#include "service/details/command_table.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "hystbench/common/command_error.hpp"

namespace hd = hystbench::daemon;
namespace common = hystbench::common;
namespace hdd = hystbench::daemon::details;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::StartsWith;

namespace {

// The refusal of `params` by the row of `cmd`, as "code: message" ("ok" when accepted).
std::string refusal(const std::string& cmd, const json& params) {
  try {
    const hdd::Command& c = hdd::find_command(cmd, params);
    hdd::RequestParams request(params, c.params);
  } catch (const common::CommandError& e) {
    return e.code() + ": " + e.what();
  }
  return "ok";
}

}  // namespace

TEST(CommandTable, AnUnknownKeyIsNamedWithTheValidOnes) {
  EXPECT_EQ(refusal("track", {{"bogus", 1}}),
            "bad_params: unknown parameter 'bogus' (valid: reference, frequency_hz, periods, "
            "duration_s, compensator, range_fraction, min_um, max_um, kp, ki, kd, force_gains, "
            "precondition_s, learn_trials, learn_gain, learn_cutoff_hz, learned, lead_in_max_s, "
            "frequencies_hz, decouple, decoupling)");
  EXPECT_EQ(refusal("status", {{"verbose", true}}),
            "bad_params: unknown parameter 'verbose' (valid: )");
  // An uploaded reference has its own keys: the built-in reference's are unknown there.
  EXPECT_THAT(refusal("track", {{"reference_upload", "r"}, {"frequency_hz", 2}}),
              StartsWith("bad_params: unknown parameter 'frequency_hz' (valid: reference_upload, "
                         "approach_s"));
  EXPECT_THAT(refusal("track", {{"approach_s", 1.0}}),
              StartsWith("bad_params: unknown parameter 'approach_s'"));
}

TEST(CommandTable, AWrongTypeIsNamedWithTheTypeExpected) {
  EXPECT_EQ(refusal("track", {{"frequency_hz", "fast"}}),
            "bad_params: frequency_hz: must be a number, got string");
  EXPECT_EQ(refusal("identify", {{"operators", 2.5}}), "bad_params: operators: must be an integer");
  EXPECT_EQ(refusal("identify", {{"model", 3}}), "bad_params: model: must be a string");
  EXPECT_EQ(refusal("identify", {{"extend", "no"}}), "bad_params: extend: must be true or false");
  EXPECT_EQ(refusal("model.load", {{"model", "text"}}),
            "bad_params: model: must be the model file's JSON object");
  EXPECT_EQ(refusal("upload.chunk", {{"values", 1.0}}), "bad_params: values: must be an array");
  EXPECT_EQ(refusal("track", json::array({1, 2})), "bad_params: params must be an object");
}

TEST(CommandTable, AValueOutOfRangeIsNamedWithTheRange) {
  EXPECT_THAT(refusal("track", {{"kp", -1.0}}),
              StartsWith("bad_params: kp: -1.000000 is out of range [0.000000, 1000000.000000]"));
  EXPECT_THAT(refusal("track", {{"range_fraction", 1.5}}),
              StartsWith("bad_params: range_fraction: 1.500000 is out of range"));
  EXPECT_THAT(refusal("identify", {{"dead_zones", -2}}),
              StartsWith("bad_params: dead_zones: -2 is out of range [-1, 100]"));
  EXPECT_THAT(refusal("identify", {{"operators", 18446744073709551615ull}}),
              StartsWith("bad_params: operators: 18446744073709551615 is out of range"));
  EXPECT_EQ(refusal("track", {{"kp", 2.0}, {"periods", 3}, {"min_um", -5.0}}), "ok");
}

TEST(CommandTable, ARefusedKeySaysWhy) {
  EXPECT_THAT(refusal("model.load", {{"path", "/etc/passwd"}}),
              AllOf(StartsWith("bad_params: path: model.load takes the model document"),
                    HasSubstr("never opens a path")));
  // A refused key is not offered among the valid ones.
  EXPECT_THAT(refusal("model.load", {{"file", "x"}}),
              HasSubstr("(valid: model, models, name, stored)"));
}

TEST(CommandTable, AnUnknownCommandListsEveryCommandOnce) {
  EXPECT_EQ(refusal("fly", json::object()),
            "unknown_command: unknown command 'fly' (status, identify, track, excite, frf, tune, "
            "upload.begin, upload.chunk, upload.cancel, stop, abort, reset, model.get, "
            "model.load, model.delete, model.list, runs, run.get, config.get)");
  for (const hdd::Command& c : hdd::bench_commands()) {
    ASSERT_NE(c.handle, nullptr) << c.name;
    EXPECT_THAT(refusal(c.name, {{"no_such_key", 0}}),
                StartsWith("bad_params: unknown parameter 'no_such_key'"))
        << c.name;
  }
}

TEST(CommandTable, RequestGettersGiveTheFallbackOrTheCheckedValue) {
  const hdd::Command& track = hdd::find_command("track", json::object());
  const json params = {{"frequency_hz", 40.0}, {"compensator", "pid"}};
  const hdd::RequestParams r(params, track.params);
  EXPECT_TRUE(r.has("frequency_hz"));
  EXPECT_FALSE(r.has("periods"));
  EXPECT_DOUBLE_EQ(r.number("periods", 5.0), 5.0);
  EXPECT_EQ(r.string("compensator", "none"), "pid");
  // A range known at run time (a twentieth of a 500 Hz loop) names the key too.
  try {
    (void)r.number("frequency_hz", 1.0, 1e-3, 25.0);
    ADD_FAILURE() << "40 Hz accepted above 25 Hz";
  } catch (const common::CommandError& e) {
    EXPECT_EQ(e.code(), "bad_params");
    EXPECT_THAT(e.what(), StartsWith("frequency_hz: 40.000000 is out of range"));
  }
  const hdd::RequestParams none(json(), track.params);
  EXPECT_DOUBLE_EQ(none.number("kp", 0.5), 0.5);
}

TEST(CommandTable, OnlyTheCommandsThatReadAreMarkedSo) {
  for (const char* reads : {"status", "runs", "run.get", "model.get", "model.list", "config.get"}) {
    EXPECT_TRUE(hdd::command_reads_only(reads)) << reads;
  }
  for (const char* changes : {"identify", "track", "excite", "frf", "tune", "stop", "abort",
                              "reset", "model.load", "model.delete", "upload.begin"}) {
    EXPECT_FALSE(hdd::command_reads_only(changes)) << changes;
  }
  EXPECT_FALSE(hdd::command_reads_only("fly"));
}

TEST(CommandTable, EveryKeyHasAMeaningAndEveryConstantDefaultIsAValueItAccepts) {
  for (const hdd::Command& c : hdd::bench_commands()) {
    for (const hdd::ParamSpec& p : c.params) {
      const std::string where = std::string(c.name) + "." + p.key;
      EXPECT_STRNE(p.doc, "") << where << ": no meaning for the protocol page";
      if (p.fallback == nullptr) continue;
      switch (p.type) {
        case hdd::ParamType::kNumber:
        case hdd::ParamType::kInteger: {
          const double v = hdd::default_number(p);
          EXPECT_GE(v, p.lo) << where;
          EXPECT_LE(v, p.hi) << where;
          if (p.type == hdd::ParamType::kInteger) {
            EXPECT_EQ(v, std::floor(v)) << where;
          }
          break;
        }
        case hdd::ParamType::kBoolean:
          EXPECT_TRUE(std::string(p.fallback) == "true" || std::string(p.fallback) == "false")
              << where;
          break;
        case hdd::ParamType::kString:
          EXPECT_STRNE(p.fallback, "") << where;
          break;
        default:
          ADD_FAILURE() << where << ": an object or array has no constant default";
      }
    }
  }
}

TEST(CommandTable, AKeyInTwoRowsOfACommandIsDefinedOnce) {
  const auto same = [](const hdd::ParamSpec& a, const hdd::ParamSpec& b) {
    const auto text = [](const char* s) { return std::string(s == nullptr ? "" : s); };
    return a.type == b.type && a.lo == b.lo && a.hi == b.hi && text(a.doc) == text(b.doc) &&
           text(a.fallback) == text(b.fallback) && text(a.fallback_doc) == text(b.fallback_doc);
  };
  const auto commands = hdd::bench_commands();
  for (std::size_t i = 0; i < commands.size(); ++i) {
    for (std::size_t j = i + 1; j < commands.size(); ++j) {
      if (std::string(commands[i].name) != commands[j].name) continue;
      for (const hdd::ParamSpec& a : commands[i].params) {
        for (const hdd::ParamSpec& b : commands[j].params) {
          if (std::string(a.key) == b.key) {
            EXPECT_TRUE(same(a, b)) << commands[i].name << "." << a.key << " differs by row";
          }
        }
      }
    }
  }
}

TEST(CommandTable, AGetterWithoutAFallbackGivesTheTablesDefault) {
  const hdd::Command& track = hdd::find_command("track", json::object());
  const json empty = json::object();
  const hdd::RequestParams none(empty, track.params);
  EXPECT_EQ(none.string("reference"), "triangle");
  EXPECT_DOUBLE_EQ(none.number("range_fraction"), 0.8);
  EXPECT_EQ(none.integer("learn_trials"), 0);
  EXPECT_TRUE(none.boolean("decouple"));
  // A key whose default depends on the bench has no constant: the builder must give it.
  EXPECT_THROW((void)none.number("kp"), std::logic_error);
  const json given = {{"range_fraction", 0.3}};
  EXPECT_DOUBLE_EQ(hdd::RequestParams(given, track.params).number("range_fraction"), 0.3);
}
