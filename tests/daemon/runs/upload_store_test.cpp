// UploadStore: chunks in order, bounds named, a connection's uploads are its own and go with it.
#include "hystbench/daemon/runs/upload_store.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "hystbench/common/command_error.hpp"

namespace hd = hystbench::daemon;
namespace common = hystbench::common;
using nlohmann::json;

namespace {

/// The CommandError a call throws: {code, message, detail}; code "ok" when it does not throw.
template <typename F>
std::tuple<std::string, std::string, json> refusal(F&& f) {
  try {
    f();
  } catch (const common::CommandError& e) {
    return {e.code(), e.what(), e.detail()};
  }
  return {"ok", "", json::object()};
}

}  // namespace

TEST(UploadStore, ChunksWithTimesMakeACompleteUploadThatResamples) {
  hd::UploadStore store;
  const json begun = store.begin({{"kind", "reference"}, {"samples", 4}, {"source", "a.csv"}}, 1);
  const std::string name = begun["upload"];
  EXPECT_FALSE(name.empty());
  EXPECT_EQ(begun["max_samples"], store.limits().max_samples);
  json r =
      store.chunk({{"upload", name}, {"offset", 0}, {"t", {1.0, 1.5}}, {"values", {0, 10}}}, 1);
  EXPECT_EQ(r["received"], 2);
  EXPECT_FALSE(r["complete"].get<bool>());
  EXPECT_EQ(std::get<0>(refusal([&] { store.complete(name, 1, hd::UploadKind::kReference); })),
            "upload_incomplete");
  r = store.chunk({{"upload", name}, {"offset", 2}, {"t", {2.0, 3.0}}, {"values", {10, 0}}}, 1);
  EXPECT_TRUE(r["complete"].get<bool>());
  const auto u = store.complete(name, 1, hd::UploadKind::kReference);
  EXPECT_DOUBLE_EQ(u->duration_s(), 2.0);  // times from the first sample
  const std::vector<double> v = u->resampled(0.25);
  ASSERT_EQ(v.size(), 9u);
  EXPECT_DOUBLE_EQ(v[0], 0.0);
  EXPECT_DOUBLE_EQ(v[1], 5.0);  // halfway through the first segment
  EXPECT_DOUBLE_EQ(v[2], 10.0);
  EXPECT_DOUBLE_EQ(v[4], 10.0);
  EXPECT_DOUBLE_EQ(v[6], 5.0);
  EXPECT_DOUBLE_EQ(v[8], 0.0);
  EXPECT_EQ(u->sample_from(1.2), 3u);  // t = 2.2 in the file's time: the next row is t = 3.0
  EXPECT_EQ(u->sample_from(1.0), 2u);  // exactly on row 2
  EXPECT_EQ(u->sample_from(9.0), 3u);
  EXPECT_EQ(std::get<0>(refusal([&] { store.complete(name, 1, hd::UploadKind::kDrive); })),
            "bad_params");
  store.erase(name, 1);
  EXPECT_EQ(store.open(), 0u);
  EXPECT_EQ(store.staged_samples(), 0u);
}

TEST(UploadStore, AUniformUploadCarriesValuesOnly) {
  hd::UploadStore store;
  store.begin({{"kind", "drive"}, {"samples", 3}, {"rate_hz", 10.0}, {"upload", "d1"}}, 1);
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.chunk({{"upload", "d1"}, {"offset", 0}, {"t", {0, 1}}, {"values", {1, 2}}}, 1);
            })),
            "bad_params");
  store.chunk({{"upload", "d1"}, {"offset", 0}, {"values", {1, 2, 4}}}, 1);
  const auto u = store.complete("d1", 1, hd::UploadKind::kDrive);
  EXPECT_DOUBLE_EQ(u->time_of(2), 0.2);
  EXPECT_EQ(u->resampled(0.05), (std::vector<double>{1, 1.5, 2, 3, 4}));
  EXPECT_EQ(u->sample_from(0.15), 2u);
  EXPECT_EQ(u->sample_from(0.1), 1u);
}

TEST(UploadStore, BadChunksAreRefusedNamingTheSampleAndChangeNothing) {
  hd::UploadStore store;
  store.begin({{"kind", "reference"}, {"samples", 6}, {"upload", "r"}}, 1);
  store.chunk({{"upload", "r"}, {"offset", 0}, {"t", {0, 1}}, {"values", {0, 1}}}, 1);
  // Out of order, repeated, times not increasing (across the chunk boundary), not finite.
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.chunk({{"upload", "r"}, {"offset", 3}, {"t", {3}}, {"values", {0}}}, 1);
            })),
            "bad_params");
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.chunk({{"upload", "r"}, {"offset", 0}, {"t", {0, 1}}, {"values", {0, 1}}}, 1);
            })),
            "bad_params");
  const auto [code, message, detail] = refusal([&] {
    store.chunk({{"upload", "r"}, {"offset", 2}, {"t", {2, 1.5}}, {"values", {0, 1}}}, 1);
  });
  EXPECT_EQ(code, "bad_params");
  EXPECT_EQ(detail["sample"], 3) << message;
  EXPECT_NE(message.find("sample 3"), std::string::npos) << message;
  const auto nan = refusal([&] {
    store.chunk({{"upload", "r"}, {"offset", 2}, {"t", {2, 3}}, {"values", {0, "x"}}}, 1);
  });
  EXPECT_EQ(std::get<2>(nan)["sample"], 3);
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.chunk({{"upload", "r"}, {"offset", 2}, {"t", {2}}, {"values", {0, 1}}}, 1);
            })),
            "bad_params");
  EXPECT_EQ(store.staged_samples(), 2u);  // nothing of the refused chunks kept
  store.chunk({{"upload", "r"}, {"offset", 2}, {"t", {2, 3}}, {"values", {0, 1}}}, 1);
  EXPECT_EQ(store.staged_samples(), 4u);
  // More than declared.
  EXPECT_EQ(
      std::get<0>(refusal([&] {
        store.chunk({{"upload", "r"}, {"offset", 4}, {"t", {4, 5, 6}}, {"values", {0, 1, 2}}}, 1);
      })),
      "upload_too_large");
}

TEST(UploadStore, TheBoundsAreNamedInTheirErrors) {
  hd::UploadLimits limits;
  limits.max_samples = 100;
  limits.max_chunk_samples = 10;
  limits.max_staged_samples = 15;
  limits.max_open = 2;
  hd::UploadStore store(limits);
  const auto [code, message, detail] = refusal([&] {
    store.begin({{"kind", "reference"}, {"samples", 101}}, 1);
  });
  EXPECT_EQ(code, "upload_too_large");
  EXPECT_NE(message.find("100"), std::string::npos) << message;
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.begin({{"kind", "x"}, {"samples", 10}}, 1);
            })),
            "bad_params");
  EXPECT_EQ(std::get<0>(refusal([&] { store.begin({{"kind", "drive"}}, 1); })), "bad_params");
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.begin({{"kind", "drive"}, {"samples", 10}, {"upload", "../x"}}, 1);
            })),
            "bad_params");

  store.begin({{"kind", "drive"}, {"samples", 50}, {"rate_hz", 1.0}, {"upload", "a"}}, 1);
  const std::vector<double> eleven(11, 1.0), ten(10, 1.0);
  EXPECT_EQ(std::get<0>(refusal([&] {
              store.chunk({{"upload", "a"}, {"offset", 0}, {"values", eleven}}, 1);
            })),
            "upload_too_large");
  store.chunk({{"upload", "a"}, {"offset", 0}, {"values", ten}}, 1);
  const auto staged = refusal([&] {
    store.chunk({{"upload", "a"}, {"offset", 10}, {"values", ten}}, 1);
  });
  EXPECT_EQ(std::get<0>(staged), "upload_too_large");
  EXPECT_NE(std::get<1>(staged).find("15"), std::string::npos) << std::get<1>(staged);

  store.begin({{"kind", "drive"}, {"samples", 5}, {"upload", "b"}}, 2);
  const auto open = refusal([&] { store.begin({{"kind", "drive"}, {"samples", 5}}, 3); });
  EXPECT_EQ(std::get<0>(open), "too_many_uploads");
  EXPECT_NE(std::get<1>(open).find("2"), std::string::npos);
}

TEST(UploadStore, AConnectionsUploadsAreItsOwnAndGoWithIt) {
  hd::UploadStore store;
  store.begin({{"kind", "reference"}, {"samples", 2}, {"upload", "mine"}}, 1);
  store.chunk({{"upload", "mine"}, {"offset", 0}, {"t", {0, 1}}, {"values", {0, 1}}}, 1);
  // Another connection neither sees nor uses it, and may use the same name for its own.
  EXPECT_EQ(std::get<0>(refusal([&] { store.complete("mine", 2, hd::UploadKind::kReference); })),
            "upload_unknown");
  EXPECT_EQ(std::get<0>(refusal([&] { store.cancel({{"upload", "mine"}}, 2); })), "upload_unknown");
  store.begin({{"kind", "reference"}, {"samples", 2}, {"upload", "mine"}}, 2);
  EXPECT_EQ(store.open(), 2u);
  store.drop_client(1);
  EXPECT_EQ(store.open(), 1u);
  EXPECT_EQ(store.staged_samples(), 0u);
  EXPECT_EQ(std::get<0>(refusal([&] { store.complete("mine", 1, hd::UploadKind::kReference); })),
            "upload_unknown");
  EXPECT_EQ(store.cancel({{"upload", "mine"}}, 2)["cancelled"], "mine");
  EXPECT_EQ(store.open(), 0u);
}
