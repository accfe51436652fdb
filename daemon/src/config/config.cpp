#include "hystbench/daemon/config/config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <concepts>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <type_traits>
#include <utility>
#include <vector>

#include "config/details/toml_json.hpp"
#include "hystbench/common/fit_families.hpp"
#include "hystbench/compensation/number_text.hpp"
#include "hystbench/sim/simulated_actuator_config.hpp"
#include "hystbench/sim/simulated_stage_config.hpp"

namespace hystbench::daemon {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A figure in a message in its shortest exact form: the value the file gave reads as it was.
using compensation::shortest;

template <typename T>
std::string range_text(T lo, T hi) {
  // Appended piece by piece: "[" + a + ", " + b + "]" trips GCC 12's -Wrestrict false positive.
  std::string s = "[";
  if constexpr (std::is_floating_point_v<T>) {
    s.append(shortest(lo)).append(", ").append(shortest(hi));
  } else {
    s.append(std::to_string(lo)).append(", ").append(std::to_string(hi));
  }
  return s.append("]");
}

std::string number_requirement(double lo, double hi, bool open_low) {
  const bool has_lo = std::isfinite(lo);
  const bool has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    return std::string("must be in ") + (open_low ? "(" : "[") + shortest(lo) + ", " +
           shortest(hi) + "]";
  }
  if (has_lo) return (open_low ? "must be > " : "must be >= ") + shortest(lo);
  if (has_hi) return "must be <= " + shortest(hi);
  return "must be a finite number";
}

std::string join(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

// Formats and throws errors: "origin:line: key: message".
class Context {
 public:
  explicit Context(std::string_view origin) : origin_(origin) {}
  [[noreturn]] void fail(const std::string& key, const std::string& message, int line) const {
    std::string what;
    if (!origin_.empty()) what = origin_ + ":" + (line > 0 ? std::to_string(line) + ":" : "") + " ";
    what += key + ": " + message;
    throw ConfigError(what, key, line);
  }

 private:
  std::string origin_;
};

int line_of(const toml::node* node) {
  return node ? static_cast<int>(node->source().begin.line) : 0;
}

// One [section]: typed getters that check ranges, then finish() refuses unknown keys.
class Section {
 public:
  Section(const Context& ctx, std::string name, const toml::table* table)
      : ctx_(ctx), name_(std::move(name)), table_(table) {}

  std::string path(std::string_view key) const { return name_ + "." + std::string(key); }
  int line(std::string_view key) const { return line_of(table_ ? table_->get(key) : nullptr); }
  [[noreturn]] void fail(std::string_view key, const std::string& message) const {
    ctx_.fail(path(key), message, line(key));
  }

  /// The node for `key` (nullptr when absent); marks the key as known.
  const toml::node* find(std::string_view key) {
    known_.emplace_back(key);
    return table_ ? table_->get(key) : nullptr;
  }

  /// A finite number (integer or float) in [lo, hi], or (lo, hi] with `open_low`; an infinite
  /// bound means no bound.
  void number(std::string_view key, double& out, double lo, double hi, bool open_low = false) {
    std::optional<double> v;
    optional_number(key, v, lo, hi, open_low);
    if (v) out = *v;
  }

  void optional_number(std::string_view key, std::optional<double>& out, double lo, double hi,
                       bool open_low = false) {
    const toml::node* node = find(key);
    if (!node) return;
    double v = 0.0;
    if (const auto* i = node->as_integer()) {
      v = static_cast<double>(i->get());
    } else if (const auto* f = node->as_floating_point()) {
      v = f->get();
    } else {
      fail(key, std::string("must be a number, got ") + details::toml_type_name(*node));
    }
    const bool in_range = std::isfinite(v) && (open_low ? v > lo : v >= lo) && v <= hi;
    if (!in_range) fail(key, number_requirement(lo, hi, open_low) + ", got " + shortest(v));
    out = v;
  }

  template <typename T>
  void integer(std::string_view key, T& out, T lo, T hi) {
    const toml::node* node = find(key);
    if (!node) return;
    const auto* i = node->as_integer();
    if (!i) fail(key, std::string("must be an integer, got ") + details::toml_type_name(*node));
    const std::int64_t v = i->get();
    if (v < static_cast<std::int64_t>(lo) || v > static_cast<std::int64_t>(hi)) {
      fail(key, "must be in " + range_text(lo, hi) + ", got " + std::to_string(v));
    }
    out = static_cast<T>(v);
  }

  void boolean(std::string_view key, bool& out) {
    const toml::node* node = find(key);
    if (!node) return;
    const auto* b = node->as_boolean();
    if (!b) fail(key, std::string("must be true or false, got ") + details::toml_type_name(*node));
    out = b->get();
  }

  /// A string; `allowed` empty = any non-empty string.
  void string(std::string_view key, std::string& out,
              const std::vector<std::string>& allowed = {}) {
    const toml::node* node = find(key);
    if (!node) return;
    const auto* s = node->as_string();
    if (!s) fail(key, std::string("must be a string, got ") + details::toml_type_name(*node));
    const std::string& v = s->get();
    if (v.empty()) fail(key, "must not be empty");
    if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
      fail(key, "must be one of " + join(allowed) + ", got \"" + v + "\"");
    }
    out = v;
  }

  /// Refuses every key no getter asked for.
  void finish() const {
    if (!table_) return;
    for (const auto& [key, node] : *table_) {
      if (std::find(known_.begin(), known_.end(), key.str()) == known_.end()) {
        ctx_.fail(path(key.str()), "unknown key (known: " + join(known_) + ")", line_of(&node));
      }
    }
  }

  const toml::table* table() const { return table_; }

 private:
  const Context& ctx_;
  std::string name_;
  const toml::table* table_;
  std::vector<std::string> known_;
};

const std::vector<std::string> kSections = {"daemon",   "loop",     "limits", "driver",
                                            "actuator", "identify", "pid",    "http"};

const toml::table* section_table(const Context& ctx, const toml::table& root,
                                 const std::string& name) {
  const toml::node* node = root.get(name);
  if (!node) return nullptr;
  if (!node->is_table()) {
    ctx.fail(name,
             std::string("must be a table ([") + name + "]), got " + details::toml_type_name(*node),
             line_of(node));
  }
  return node->as_table();
}

toml::table parse_toml(std::string_view text, std::string_view origin) {
  try {
    return toml::parse(text, origin);
  } catch (const toml::parse_error& e) {
    const int line = static_cast<int>(e.source().begin.line);
    const std::string where = origin.empty() ? "" : std::string(origin) + ":";
    throw ConfigError(where + std::to_string(line) + ":" + std::to_string(e.source().begin.column) +
                          ": " + std::string(e.description()),
                      "", line);
  }
}

// ---- Every key of every section, declared once ----
// visit_<section>(section, visit, ...) names each key with its field and its bounds; the reader
// turns that into checked getters, the writer into JSON, so a new key is one line here (and
// its member in config.hpp). Checks across keys follow in check_<section>().

struct Bounds {
  double lo = -kInf;
  double hi = kInf;
  bool open_low = false;  ///< (lo, hi] instead of [lo, hi]
};

template <class S, class Visit>
void visit_daemon(S& d, Visit&& visit) {
  visit("socket_path", d.socket_path);
  visit("log_dir", d.log_dir);
  visit("model_dir", d.model_dir);
  visit("log_level", d.log_level,
        std::vector<std::string>{"trace", "debug", "info", "warn", "error", "critical", "off"});
}

template <class S, class Visit>
void visit_loop(S& l, Visit&& visit) {
  visit("rate_hz", l.rate_hz, Bounds{1.0, 20000.0});
  visit("clock", l.clock, std::vector<std::string>{"wall", "simulated"});
  visit("realtime", l.realtime);
  visit("priority", l.priority, 1, 99);
  visit("cpu", l.cpu, -1, 1023);
  visit("lock_memory", l.lock_memory);
  visit("overrun_budget", l.overrun_budget, std::uint64_t{0}, std::uint64_t{1'000'000'000});
  visit("ring_capacity", l.ring_capacity, std::size_t{1024}, std::size_t{1} << 24);
  visit("stuck_sensor_ms", l.stuck_sensor_ms, Bounds{0.0, 10000.0});
  visit("stuck_sensor_span", l.stuck_sensor_span, Bounds{0.0, 1.0, true});
  visit("feedforward_bandwidth_hz", l.feedforward_bandwidth_hz, Bounds{0.0, 1e6});
}

template <class S, class Visit>
void visit_limits(S& l, Visit&& visit) {
  visit("u_min", l.u_min, Bounds{});
  visit("u_max", l.u_max, Bounds{});
  visit("slew_v_per_s", l.slew_v_per_s, Bounds{0.0, kInf, true});
  visit("fatal_on_limit", l.fatal_on_limit);
  visit("y_min", l.y_min, Bounds{});
  visit("y_max", l.y_max, Bounds{});
}

/// The excitation's bounds depend on the limits, its top frequency on the loop rate.
template <class S, class Visit>
void visit_identify(S& id, Visit&& visit, const LoopSection& loop, const LimitsSection& limits) {
  visit("model", id.model, common::fit_family_name_list());
  visit("operators", id.operators, 0, 100);
  visit("dead_zones", id.dead_zones, -1, 50);
  visit("amplitude_v", id.amplitude_v, Bounds{0.0, limits.u_max - limits.u_min, true});
  visit("offset_v", id.offset_v, Bounds{limits.u_min, limits.u_max});
  visit("frequency_hz", id.frequency_hz, Bounds{0.0, loop.rate_hz / 20.0, true});
  visit("cycles", id.cycles, 1, 1000);
  visit("precondition_s", id.precondition_s, Bounds{0.0, 60.0, true});
  visit("settle_s", id.settle_s, Bounds{0.0, 600.0});
  visit("heldout_fraction", id.heldout_fraction, Bounds{0.0, 0.9});
  visit("fit_rate_hz", id.fit_rate_hz, Bounds{1.0, 20000.0});
  visit("extend", id.extend);
}

template <class S, class Visit>
void visit_pid(S& p, Visit&& visit, const LoopSection& loop) {
  visit("kp", p.kp, Bounds{0.0});
  visit("ki", p.ki, Bounds{0.0});
  visit("kd", p.kd, Bounds{0.0});
  visit("bandwidth_hz", p.bandwidth_hz, Bounds{0.0, loop.rate_hz / 2.0, true});
  visit("output_filter_hz", p.output_filter_hz, Bounds{0.0});
  visit("derivative_filter_hz", p.derivative_filter_hz, Bounds{0.0});
  visit("u_fb_min", p.u_fb_min, Bounds{});
  visit("u_fb_max", p.u_fb_max, Bounds{});
  visit("gain_margin_db", p.gain_margin_db, Bounds{0.0, 40.0});
  visit("phase_margin_deg", p.phase_margin_deg, Bounds{0.0, 89.0});
  visit("peak_sensitivity_db", p.peak_sensitivity_db, Bounds{0.0, 40.0, true});
  visit("force", p.force);
  visit("oscillation_trip", p.oscillation_trip);
}

template <class S, class Visit>
void visit_http(S& h, Visit&& visit) {
  visit("listen", h.listen);
  visit("control", h.control);
  visit("token_file", h.token_file);
  visit("max_clients", h.max_clients, std::int64_t{2}, std::int64_t{64});
  visit("scope_rate_hz", h.scope_rate_hz, Bounds{10.0, 2000.0});
}

/// Reads each visited key from a Section with the checks its type and bounds call for.
class Reader {
 public:
  explicit Reader(Section& s) : s_(s) {}
  void operator()(std::string_view key, double& v, Bounds b) {
    s_.number(key, v, b.lo, b.hi, b.open_low);
  }
  void operator()(std::string_view key, std::optional<double>& v, Bounds b) {
    s_.optional_number(key, v, b.lo, b.hi, b.open_low);
  }
  template <std::integral T>
  void operator()(std::string_view key, T& v, T lo, T hi) {
    s_.integer(key, v, lo, hi);
  }
  void operator()(std::string_view key, bool& v) { s_.boolean(key, v); }
  void operator()(std::string_view key, std::string& v,
                  const std::vector<std::string>& allowed = {}) {
    s_.string(key, v, allowed);
  }

 private:
  Section& s_;
};

/// Writes each visited key into a JSON object (an absent optional as null).
class Writer {
 public:
  explicit Writer(nlohmann::json& j) : j_(j) {}
  template <class T, class... Checks>
  void operator()(std::string_view key, const T& v, const Checks&... /*ignored*/) {
    if constexpr (std::is_same_v<T, std::optional<double>>) {
      j_[std::string(key)] = v ? nlohmann::json(*v) : nlohmann::json(nullptr);
    } else {
      j_[std::string(key)] = v;
    }
  }

 private:
  nlohmann::json& j_;
};

void check_daemon(const Section& s, const DaemonSection& d) {
  if (d.socket_path.size() > 107) s.fail("socket_path", "must be at most 107 bytes long");
}

void check_http(const Section& s, const HttpSection& h) {
  if (!h.listen.empty()) {
    if (const ListenAddress a = parse_listen_address(h.listen); !a.error.empty()) {
      s.fail("listen", a.error);
    }
  }
}

void check_limits(const Section& s, const LimitsSection& l) {
  if (!(l.u_min < l.u_max)) {
    s.fail("u_max", "must be greater than limits.u_min (" + shortest(l.u_min) + "), got " +
                        shortest(l.u_max));
  }
  if (l.y_min.has_value() != l.y_max.has_value()) {
    s.fail(l.y_min ? "y_max" : "y_min", "limits.y_min and limits.y_max must be given together");
  }
  if (l.y_min && !(*l.y_min < *l.y_max)) {
    s.fail("y_max", "must be greater than limits.y_min (" + shortest(*l.y_min) + "), got " +
                        shortest(*l.y_max));
  }
}

void check_identify(const Section& s, const IdentifySection& id, const LimitsSection& limits) {
  const auto [low, high] = id.span_v(limits.u_min, limits.u_max);
  if (low < limits.u_min - 1e-9 || high > limits.u_max + 1e-9) {
    s.fail("amplitude_v", "offset_v +- amplitude_v = " + range_text(low, high) +
                              " V must lie within [limits.u_min, limits.u_max] = " +
                              range_text(limits.u_min, limits.u_max));
  }
}

void check_pid(const Section& s, const PidSection& p, const LoopSection& loop) {
  const double nyquist = loop.rate_hz / 2.0;
  for (const auto& [key, hz] : {std::pair{"output_filter_hz", p.output_filter_hz.value_or(0.0)},
                                std::pair{"derivative_filter_hz", p.derivative_filter_hz}}) {
    if (hz >= nyquist) {
      s.fail(key,
             "must be below loop.rate_hz / 2 = " + shortest(nyquist) + " Hz, got " + shortest(hz));
    }
  }
  if (!(p.u_fb_min <= p.u_fb_max)) {
    s.fail("u_fb_max", "must be at least pid.u_fb_min (" + shortest(p.u_fb_min) + "), got " +
                           shortest(p.u_fb_max));
  }
}

void read_driver(const Context& ctx, const toml::table* table, DriverSection& d) {
  Section s(ctx, "driver", table);
  s.string("type", d.type);
  for (const char c : d.type) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-')) {
      s.fail("type", "must be a driver name of [a-z0-9_-], got \"" + d.type + "\"");
    }
  }
  if (!table) return;
  for (const auto& [key, node] : *table) {
    if (key.str() == "type") continue;
    if (!node.is_table()) {
      ctx.fail("driver." + std::string(key.str()),
               "unknown key (known: type, and one [driver.<name>] table per driver)",
               line_of(&node));
    }
    d.tables[std::string(key.str())] = details::toml_node_to_json(node);
  }
}

/// The TOML node a key path of sim's messages names ("creep.gains_um_per_v[2]", "dynamcs"),
/// under `table`: the deepest node of the path that exists (a missing key: its table).
const toml::node* node_at(const toml::table& table, std::string_view path) {
  const toml::node* node = &table;
  std::size_t pos = 0;
  while (pos < path.size()) {
    const std::size_t end = std::min(path.find_first_of(".[", pos), path.size());
    if (end > pos) {  // a key
      const toml::table* t = node->as_table();
      const toml::node* child = t ? t->get(path.substr(pos, end - pos)) : nullptr;
      if (!child) return node;
      node = child;
    }
    pos = end;
    if (pos < path.size() && path[pos] == '[') {  // an array element
      const std::size_t close = path.find(']', pos);
      if (close == std::string_view::npos) return node;
      std::size_t index = 0;
      const auto [p, ec] = std::from_chars(path.data() + pos + 1, path.data() + close, index);
      const toml::array* a = node->as_array();
      if (ec != std::errc() || p != path.data() + close || !a || index >= a->size()) return node;
      node = a->get(index);
      pos = close + 1;
    }
    if (pos < path.size() && path[pos] == '.') ++pos;
  }
  return node;
}

/// Checks a simulated actuator table (`key` = its dotted path) with sim::from_json; its errors
/// ("<key path>: <what>") become "<key>.<key path>: <what>" at the offending node's line.
/// `parse` is sim::from_json or sim::stage_from_json.
template <typename Parse>
void check_simulated(const Context& ctx, const std::string& key, const toml::table& table,
                     Parse parse) {
  try {
    (void)parse(details::toml_node_to_json(table));
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    const std::size_t colon = message.find(": ");
    if (colon == std::string::npos) ctx.fail(key, message, line_of(&table));
    const std::string path = message.substr(0, colon);
    const toml::node* node = node_at(table, path);
    int line = line_of(node);
    if (line == 0) line = line_of(&table);
    ctx.fail(key + "." + path, message.substr(colon + 2), line);
  }
}

void check_actuator(const Context& ctx, const std::string& key, const toml::table& table) {
  check_simulated(ctx, key, table, [](const nlohmann::json& j) { return sim::from_json(j); });
}

/// The simulated actuator's tables, for the loopback driver; refused with another one.
void check_actuators(const Context& ctx, const toml::table& root, const DaemonConfig& c) {
  const toml::table* actuator = section_table(ctx, root, "actuator");
  if (c.driver.type != "loopback") {
    if (actuator && !actuator->empty()) {
      // A table made only by its sub-tables ([actuator.creep]) has no line of its own.
      int line = line_of(actuator);
      if (line == 0) line = line_of(&actuator->cbegin()->second);
      ctx.fail("actuator",
               "only the loopback driver simulates an actuator, driver.type is \"" + c.driver.type +
                   "\" (remove the table or leave it empty)",
               line);
    }
    return;
  }
  // A stage of several axes simulates each axis's actuator in its own table: one [actuator]
  // beside it would be a second truth.
  if (const toml::node* stage = root.at_path("driver.loopback.stage").node()) {
    if (!stage->is_table()) ctx.fail("driver.loopback.stage", "must be a table", line_of(stage));
    if (actuator && !actuator->empty()) {
      int line = line_of(actuator);
      if (line == 0) line = line_of(&actuator->cbegin()->second);
      ctx.fail("actuator",
               "[driver.loopback.stage] simulates each axis's actuator (axes[i].actuator): "
               "remove [actuator] or the stage",
               line);
    }
    check_simulated(ctx, "driver.loopback.stage", *stage->as_table(),
                    [](const nlohmann::json& j) { return sim::stage_from_json(j); });
    return;
  }
  if (actuator) check_actuator(ctx, "actuator", *actuator);
  const toml::node* own = root.at_path("driver.loopback.actuator").node();
  if (own && own->is_table()) check_actuator(ctx, "driver.loopback.actuator", *own->as_table());
}

}  // namespace

std::string clock_conflict(std::string_view clock, std::string_view driver_type) {
  if (clock != "simulated" || driver_type == "loopback") return {};
  return "\"simulated\" needs driver.type = \"loopback\" (the simulated actuator is the only "
         "plant that can follow a virtual clock), got driver.type = \"" +
         std::string(driver_type) + "\"";
}

nlohmann::json DriverSection::params() const {
  const auto it = tables.find(type);
  return it != tables.end() ? *it : nlohmann::json::object();
}

DaemonConfig parse_config(std::string_view toml_text, std::string_view origin) {
  const Context ctx(origin);
  const toml::table root = parse_toml(toml_text, origin);
  for (const auto& [key, node] : root) {
    if (std::find(kSections.begin(), kSections.end(), key.str()) == kSections.end()) {
      ctx.fail(std::string(key.str()), "unknown section (known: " + join(kSections) + ")",
               line_of(&node));
    }
  }
  DaemonConfig c;
  // Each section: its keys read and checked one by one, then across keys, then unknown keys.
  auto section = [&](const char* name) {
    return Section(ctx, name, section_table(ctx, root, name));
  };
  {
    Section s = section("daemon");
    visit_daemon(c.daemon, Reader(s));
    check_daemon(s, c.daemon);
    s.finish();
  }
  {
    Section s = section("loop");
    visit_loop(c.loop, Reader(s));
    s.finish();
  }
  {
    Section s = section("limits");
    visit_limits(c.limits, Reader(s));
    check_limits(s, c.limits);
    s.finish();
  }
  read_driver(ctx, section_table(ctx, root, "driver"), c.driver);
  if (const std::string why = clock_conflict(c.loop.clock, c.driver.type); !why.empty()) {
    Section(ctx, "loop", section_table(ctx, root, "loop")).fail("clock", why);
  }
  if (const toml::table* actuator = section_table(ctx, root, "actuator")) {
    c.actuator = details::toml_node_to_json(*actuator);
  }
  check_actuators(ctx, root, c);
  {
    Section s = section("identify");
    visit_identify(c.identify, Reader(s), c.loop, c.limits);
    check_identify(s, c.identify, c.limits);
    s.finish();
  }
  {
    Section s = section("pid");
    visit_pid(c.pid, Reader(s), c.loop);
    check_pid(s, c.pid, c.loop);
    s.finish();
  }
  {
    Section s = section("http");
    visit_http(c.http, Reader(s));
    check_http(s, c.http);
    s.finish();
  }
  return c;
}

DaemonConfig load_config(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string() + ": cannot open the configuration file", "", 0);
  std::ostringstream text;
  text << in.rdbuf();
  return parse_config(text.str(), path.string());
}

nlohmann::json to_json(const DaemonConfig& c) {
  nlohmann::json j = nlohmann::json::object();
  visit_daemon(c.daemon, Writer(j["daemon"]));
  visit_loop(c.loop, Writer(j["loop"]));
  visit_limits(c.limits, Writer(j["limits"]));
  j["driver"] = c.driver.tables;
  j["driver"]["type"] = c.driver.type;
  j["actuator"] = c.actuator;
  visit_identify(c.identify, Writer(j["identify"]), c.loop, c.limits);
  // The excitation as it will run: absent offset and amplitude are the whole output range.
  const auto [low, high] = c.identify.span_v(c.limits.u_min, c.limits.u_max);
  j["identify"]["offset_v"] = 0.5 * (low + high);
  j["identify"]["amplitude_v"] = 0.5 * (high - low);
  visit_pid(c.pid, Writer(j["pid"]), c.loop);
  visit_http(c.http, Writer(j["http"]));
  return j;
}

ListenAddress parse_listen_address(std::string_view text) {
  ListenAddress a;
  const std::size_t colon = text.rfind(':');
  if (colon == std::string_view::npos || colon == 0) {
    a.error = "must be HOST:PORT (e.g. 127.0.0.1:8080), got '" + std::string(text) + "'";
    return a;
  }
  a.host = std::string(text.substr(0, colon));
  if (a.host.size() > 2 && a.host.front() == '[' && a.host.back() == ']') {
    a.host = a.host.substr(1, a.host.size() - 2);  // [::1]:8080
  }
  const std::string_view port = text.substr(colon + 1);
  const auto r = std::from_chars(port.data(), port.data() + port.size(), a.port);
  if (port.empty() || r.ec != std::errc() || r.ptr != port.data() + port.size() || a.port < 0 ||
      a.port > 65535) {
    a.error =
        "the port must be a number in [0, 65535] (0: a free one), got '" + std::string(port) + "'";
  }
  return a;
}

nlohmann::json toml_to_json(std::string_view toml_text) {
  return details::toml_node_to_json(parse_toml(toml_text, {}));
}

}  // namespace hystbench::daemon
