#pragma once
// The schema of hystbenchd's requests, shared by the daemon (which checks and reads every request
// through it) and the CLI (whose options take their ranges and defaults from it): one
// ParamSpec per parameter, one table per request (run_requests.hpp). Data only, constexpr;
// safe anywhere.
#include <array>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace hystbench::common {

/// What a parameter's value must be (the daemon's errors word them in this order).
enum class ParamType { kNumber, kInteger, kString, kObject, kArray, kBoolean };

/// One parameter of a command, the one place it is defined: key, type, the range a number or
/// integer must lie in (a range known only at run time, such as the loop rate's, is checked by
/// RequestParams::number's overloads), what it means and its default. The command table's rows
/// point at these, RequestParams reads requests through them, and docs/reference/protocol.md's
/// parameter tables are made from them (the daemon's service/details/protocol_tables.hpp).
struct ParamSpec {
  const char* key;
  ParamType type;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  /// What the key means, as the protocol page's table says it.
  const char* doc = "";
  /// The value an absent key takes when it is one constant: a number or integer as written,
  /// "true" or "false", a string as it is. The getters without a fallback return it.
  const char* fallback = nullptr;
  /// The default in words where it depends on the bench, the config or other keys (after
  /// `fallback` where both are given): the run builder passes that fallback itself.
  const char* fallback_doc = nullptr;
  /// Names the expected value in errors ("a number" and so on by default).
  const char* what = nullptr;
  /// Refuses the key with this reason (a key a client might expect, never accepted).
  const char* refusal = nullptr;
  /// The values a string takes, where the program lists them (the page adds them to `doc`).
  std::vector<std::string> (*values)() = nullptr;
};

/// The key's constant default as written (ParamSpec::fallback), and as a number or integer;
/// std::logic_error without one (a programming error: the caller must give the fallback).
std::string_view default_constant(const ParamSpec& spec);
double default_number(const ParamSpec& spec);

/// The key's entry in `table`; std::logic_error when it has none (a programming error).
const ParamSpec& find_param(std::span<const ParamSpec> table, std::string_view key);

/// The default as the docs say it: the constant (in backticks where `markdown`) and then what it
/// depends on; empty for none.
std::string default_text(const ParamSpec& spec, bool markdown);

namespace request_fields {

/// The tables given, one after the other.
template <std::size_t N, std::size_t M>
constexpr std::array<ParamSpec, N + M> join(const std::array<ParamSpec, N>& a,
                                            const std::array<ParamSpec, M>& b) {
  return [&]<std::size_t... I, std::size_t... J>(std::index_sequence<I...>,
                                                 std::index_sequence<J...>) {
    return std::array<ParamSpec, N + M>{a[I]..., b[J]...};
  }
  (std::make_index_sequence<N>{}, std::make_index_sequence<M>{});
}
template <std::size_t N, std::size_t M, typename... More>
constexpr auto join(const std::array<ParamSpec, N>& a, const std::array<ParamSpec, M>& b,
                    const More&... more) {
  return join(join(a, b), more...);
}

}  // namespace request_fields

}  // namespace hystbench::common
