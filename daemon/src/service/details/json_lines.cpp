#include "service/details/json_lines.hpp"

namespace hystbench::daemon::details {

namespace {

bool fail(ProtocolError& error, const char* code, std::string message, nlohmann::json id) {
  error.code = code;
  error.message = std::move(message);
  error.id = std::move(id);
  return false;
}

}  // namespace

bool parse_request(std::string_view line, daemon::Request& request, ProtocolError& error) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(line.begin(), line.end());
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for a number beyond double (1e999): both are bad JSON here,
    // never an exception out of the server's event thread (which would terminate the daemon).
    return fail(error, "bad_json", e.what(), nullptr);
  }
  if (!j.is_object()) return fail(error, "bad_request", "a request must be a JSON object", nullptr);
  nlohmann::json id = nullptr;
  if (const auto it = j.find("id"); it != j.end()) {
    if (!it->is_string() && !it->is_number() && !it->is_null()) {
      return fail(error, "bad_request", "\"id\" must be a string, a number or null", nullptr);
    }
    id = *it;
  }
  for (const auto& [key, value] : j.items()) {
    if (key != "id" && key != "cmd" && key != "params") {
      return fail(error, "bad_request",
                  "unknown key \"" + key + "\" (a request has \"id\", \"cmd\", \"params\")", id);
    }
  }
  const auto cmd = j.find("cmd");
  if (cmd == j.end()) return fail(error, "bad_request", "missing \"cmd\"", id);
  if (!cmd->is_string() || cmd->get_ref<const std::string&>().empty()) {
    return fail(error, "bad_request", "\"cmd\" must be a non-empty string", id);
  }
  nlohmann::json params = nlohmann::json::object();
  if (const auto it = j.find("params"); it != j.end()) {
    if (!it->is_object()) return fail(error, "bad_request", "\"params\" must be an object", id);
    params = std::move(*it);
  }
  request.id = std::move(id);
  request.cmd = cmd->get<std::string>();
  request.params = std::move(params);
  return true;
}

std::string json_line(const nlohmann::json& value) {
  std::string s = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  s += '\n';
  return s;
}

std::string reply_line(const nlohmann::json& id, const Reply& reply) {
  if (!reply.ok) {
    nlohmann::json error = {{"code", reply.error_code.empty() ? "error" : reply.error_code},
                            {"message", reply.error_message}};
    // Details add keys; they never replace the code or the message.
    if (reply.error_detail.is_object()) {
      for (const auto& [key, value] : reply.error_detail.items()) error.emplace(key, value);
    }
    return json_line({{"id", id}, {"ok", false}, {"error", std::move(error)}});
  }
  return json_line({{"id", id}, {"ok", true}, {"result", reply.result}});
}

std::string error_line(const nlohmann::json& id, std::string_view code, std::string_view message) {
  return json_line({{"id", id},
                    {"ok", false},
                    {"error", {{"code", code.empty() ? "error" : code}, {"message", message}}}});
}

}  // namespace hystbench::daemon::details
