#include "runs/details/learned_drive.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "hystbench/common/command_error.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "runs/details/folder_name.hpp"

namespace hystbench::daemon::details {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kSuffix = "-learned";
constexpr const char* kHeader = "t,u,u_compensator";

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// RUN-learned from any of the names a client may give; never a path.
std::string drive_name(const std::string& name) {
  if (!is_folder_name(name)) {
    throw common::CommandError(
        "bad_params",
        "learned: a learned drive's name (letters, digits, '.', '_', '-'; not a "
        "path): the run id of the learning run, as its result and `hystbench model "
        "list` show");
  }
  std::string base = name;
  for (const char* ext : {".csv", ".json"}) {
    if (ends_with(base, ext)) base.resize(base.size() - std::string(ext).size());
  }
  return ends_with(base, kSuffix) ? base : base + kSuffix;
}

std::string describe(const LearnedFor& f) {
  using compensation::significant;
  const std::string ticks = std::to_string(f.period_samples) + " ticks";
  const std::string what =
      f.reference == "upload"
          ? "an uploaded trajectory " + f.signature + " (passes of " + ticks + ")"
          : "a " + significant(f.frequency_hz, 6) + " Hz " + f.reference + " (" + ticks + ")";
  return what + " from " + significant(f.min_um, 6) + " to " + significant(f.max_um, 6) +
         " um at " + significant(f.rate_hz, 6) + " Hz";
}

// The u and u_compensator columns of a drive's CSV as save_learned_drive writes it.
void read_drive_csv(const fs::path& path, LearnedDrive& d) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path.filename().string());
  std::string line;
  if (!std::getline(in, line) || line != kHeader) {
    throw std::runtime_error(path.filename().string() + " does not start with the header " +
                             kHeader);
  }
  for (std::size_t number = 2; std::getline(in, line); ++number) {
    double v[3] = {NAN, NAN, NAN};
    const char* at = line.data();
    const char* const end = line.data() + line.size();
    bool ok = true;
    for (int i = 0; i < 3 && ok; ++i) {
      const auto [next, ec] = std::from_chars(at, end, v[i]);
      const bool field_ends = i < 2 ? next < end && *next == ',' : next == end;
      ok = ec == std::errc() && std::isfinite(v[i]) && field_ends;
      at = next + 1;
    }
    if (!ok) {
      throw std::runtime_error(path.filename().string() + " line " + std::to_string(number) +
                               ": not three finite numbers " + kHeader);
    }
    d.u.push_back(v[1]);
    d.compensator.push_back(v[2]);
  }
}

}  // namespace

bool is_learned_drive_file(const std::string& file_name) {
  return ends_with(file_name, std::string(kSuffix) + ".json");
}

std::string save_learned_drive(const std::string& dir, const std::string& run_id,
                               const std::vector<double>& u, const std::vector<double>& compensator,
                               double dt_s, const LearnedFor& f, const json& meta) {
  if (compensator.size() != u.size()) {
    throw common::CommandError(
        "io_error", "cannot keep the learned drive: " + std::to_string(u.size()) + " samples, " +
                        std::to_string(compensator.size()) + " of the compensator's");
  }
  const std::string name = run_id + kSuffix;
  const fs::path csv = fs::path(dir) / (name + ".csv");
  try {
    fs::create_directories(dir);
    std::ofstream rows(csv);
    rows << kHeader << "\n";
    rows.precision(17);
    for (std::size_t j = 0; j < u.size(); ++j) {
      rows << static_cast<double>(j) * dt_s << "," << u[j] << "," << compensator[j] << "\n";
    }
    if (!rows) throw std::runtime_error("cannot write " + csv.string());
    json m = meta;
    m.update({{"drive", csv.filename().string()},
              {"run_id", run_id},
              {"reference", f.reference},
              {"frequency_hz", f.frequency_hz},
              {"rate_hz", f.rate_hz},
              {"period_samples", f.period_samples},
              {"min_um", f.min_um},
              {"max_um", f.max_um}});
    if (!f.signature.empty()) m["signature"] = f.signature;
    std::ofstream out(fs::path(dir) / (name + ".json"));
    out << m.dump(2) << "\n";
    if (!out) throw std::runtime_error("cannot write " + name + ".json in " + dir);
  } catch (const std::exception& e) {
    throw common::CommandError("io_error",
                               std::string("cannot keep the learned drive: ") + e.what());
  }
  return csv.string();
}

LearnedDrive load_learned_drive(const std::string& dir, const std::string& name) {
  LearnedDrive d;
  d.name = drive_name(name);
  const fs::path json_path = fs::path(dir) / (d.name + ".json");
  if (!fs::is_regular_file(fs::symlink_status(json_path))) {
    throw common::CommandError("bad_params",
                               "learned: no learned drive '" + d.name +
                                   "' in the daemon's model folder (hystbench model list)");
  }
  try {
    std::ifstream in(json_path);
    d.meta = json::parse(in);
    LearnedFor& f = d.learned_for;
    f.reference = d.meta.at("reference").get<std::string>();
    f.period_samples = d.meta.at("period_samples").get<std::size_t>();
    f.frequency_hz = d.meta.at("frequency_hz").get<double>();
    f.rate_hz = d.meta.at("rate_hz").get<double>();
    f.min_um = d.meta.at("min_um").get<double>();
    f.max_um = d.meta.at("max_um").get<double>();
    f.signature = d.meta.value("signature", std::string());
    read_drive_csv(fs::path(dir) / (d.name + ".csv"), d);
    if (d.u.size() != f.period_samples) {
      throw std::runtime_error("its CSV holds " + std::to_string(d.u.size()) +
                               " samples, its period " + std::to_string(f.period_samples));
    }
  } catch (const std::exception& e) {
    throw common::CommandError("io_error",
                               "learned: '" + d.name + "' is not a learned drive: " + e.what());
  }
  return d;
}

void check_learned_drive(const LearnedDrive& drive, const LearnedFor& run) {
  const LearnedFor& f = drive.learned_for;
  const double tol = 1e-6 * std::max(std::abs(f.max_um - f.min_um), 1e-9);
  const bool same = f.reference == run.reference && f.period_samples == run.period_samples &&
                    f.rate_hz == run.rate_hz && std::abs(f.min_um - run.min_um) <= tol &&
                    std::abs(f.max_um - run.max_um) <= tol && f.signature == run.signature;
  if (same) return;
  const std::string how =
      f.reference == "upload" || run.reference == "upload"
          ? "upload the same trajectory (the same file, --approach and resampling), or learn "
            "this one"
          : "give its extremes (--min " + compensation::significant(f.min_um, 17) + " --max " +
                compensation::significant(f.max_um, 17) +
                "), or load the model it was learned with, whose range they come from; or "
                "learn this reference";
  throw common::CommandError("bad_params",
                             "learned: '" + drive.name + "' was learned for " + describe(f) +
                                 "; this run asks for " + describe(run) +
                                 ". A learned drive replays only its own reference at its "
                                 "own loop rate: " +
                                 how + " with --learn N");
}

}  // namespace hystbench::daemon::details
