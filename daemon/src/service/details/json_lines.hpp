#pragma once
// The JSON-lines protocol of SocketServer without the I/O: request validation and the
// serialization of replies and events (each returned line ends with '\n').
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "hystbench/daemon/service/socket_server.hpp"

namespace hystbench::daemon::details {

/// A request line that could not be accepted: its protocol error code and message, and the id
/// to answer with (null when unreadable).
struct ProtocolError {
  std::string code;  ///< "bad_json" | "bad_request"
  std::string message;
  nlohmann::json id;
};

/// Validates one line (without '\n'). Returns false and fills `error` for a protocol error.
bool parse_request(std::string_view line, daemon::Request& request, ProtocolError& error);

/// One JSON value as a single line; invalid UTF-8 in strings is replaced, never thrown.
std::string json_line(const nlohmann::json& value);
std::string reply_line(const nlohmann::json& id, const Reply& reply);
std::string error_line(const nlohmann::json& id, std::string_view code, std::string_view message);

}  // namespace hystbench::daemon::details
