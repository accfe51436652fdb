#pragma once
// The protocol page's parameter tables, made from the command table (command_table.hpp) and the
// requests' parameter tables (hystbench/common/run_requests.hpp): docs/reference/protocol.md holds
// each between markers, scripts/protocol-reference.sh writes them there and
// protocol_reference_test holds the page to them. Not real-time safe.
#include <string>
#include <string_view>
#include <vector>

namespace hystbench::daemon::details {

/// The commands that take parameters, in the command table's order, each once.
std::vector<std::string> commands_with_parameters();

/// Command `name`'s parameters as a Markdown table (parameter, type, range, default, meaning):
/// the keys of every row of the command, the row without a condition first, each key once.
/// Empty for a command without parameters.
std::string parameter_table(std::string_view name);

/// The marker lines a table sits between on the page.
std::string table_begin_marker(std::string_view name);
inline constexpr std::string_view kTableEndMarker = "<!-- end of the generated table -->";

/// `page` with every marked table replaced by the one made now; `missing` gets the commands
/// with parameters that have no marked table on the page.
std::string with_parameter_tables(const std::string& page, std::vector<std::string>* missing);

}  // namespace hystbench::daemon::details
