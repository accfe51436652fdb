#include "hystbench/common/model_file_io.hpp"

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "hystbench/common/request_limits.hpp"

namespace hystbench::common {

namespace hc = compensation;
using nlohmann::json;

namespace {

// A model file's text, read once (at most max_bytes when given).
std::string read_model_text(const std::string& path, std::uintmax_t max_bytes = 0) {
  if (max_bytes > 0) {
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (ec) throw std::runtime_error(path + ": cannot open model file (" + ec.message() + ")");
    if (bytes > max_bytes) {
      throw std::runtime_error(path + ": " + std::to_string(bytes) +
                               " bytes is too large for a model file (at most " +
                               std::to_string(max_bytes) + ")");
    }
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open model file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

hc::ModelFile parse_model_text(const std::string& path, const std::string& text) {
  try {
    return hc::parse_model_file(text);
  } catch (const hc::ModelFileError& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

}  // namespace

hc::ModelFile load_model_file(const std::string& path) {
  return parse_model_text(path, read_model_text(path));
}

nlohmann::json read_model_document(const std::string& path) {
  const std::string text = read_model_text(path, kMaxModelFileBytes);
  // Checked here as the daemon will check it, so the error comes at once and names the file;
  // the file's own document is what travels (not a re-serialisation of the parsed model).
  (void)parse_model_text(path, text);
  return json::parse(text);
}

void save_json_document(const std::string& path, const json& doc) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot write the file");
    out << std::setw(2) << doc << "\n";
    if (!out) throw std::runtime_error(path + ": write failed");
  }
  std::filesystem::rename(tmp, path);
}

void save_model_file(const std::string& path, const hc::ModelFile& file) {
  save_json_document(path, hc::to_json(file));
}

std::optional<hc::MimoModelFile> load_mimo_model_file(const std::string& path) {
  const std::string text = read_model_text(path);
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    throw std::runtime_error(path + ": not JSON (" + e.what() + ")");
  }
  if (!hc::is_mimo_model_file(doc)) return std::nullopt;
  try {
    return hc::mimo_model_file_from_json(doc);
  } catch (const hc::ModelFileError& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

void save_mimo_model_file(const std::string& path, const hc::MimoModelFile& file) {
  save_json_document(path, hc::to_json(file));
}

}  // namespace hystbench::common
