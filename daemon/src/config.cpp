#include "hystbench/daemon/config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "details/toml_json.hpp"

namespace hystbench::daemon {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string number_text(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

template <typename T>
std::string range_text(T lo, T hi) {
  if constexpr (std::is_floating_point_v<T>) {
    return "[" + number_text(lo) + ", " + number_text(hi) + "]";
  } else {
    return "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  }
}

std::string number_requirement(double lo, double hi, bool open_low) {
  const bool has_lo = std::isfinite(lo);
  const bool has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    return std::string("must be in ") + (open_low ? "(" : "[") + number_text(lo) + ", " +
           number_text(hi) + "]";
  }
  if (has_lo) return (open_low ? "must be > " : "must be >= ") + number_text(lo);
  if (has_hi) return "must be <= " + number_text(hi);
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
    if (!in_range) fail(key, number_requirement(lo, hi, open_low) + ", got " + number_text(v));
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
                                            "actuator", "identify", "pid"};

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

void read_daemon(Section s, DaemonSection& d) {
  s.string("socket_path", d.socket_path);
  if (d.socket_path.size() > 107) s.fail("socket_path", "must be at most 107 bytes long");
  s.string("log_dir", d.log_dir);
  s.string("model_dir", d.model_dir);
  s.string("log_level", d.log_level,
           {"trace", "debug", "info", "warn", "error", "critical", "off"});
  s.finish();
}

void read_loop(Section s, LoopSection& l) {
  s.number("rate_hz", l.rate_hz, 1.0, 20000.0);
  s.boolean("realtime", l.realtime);
  s.integer("priority", l.priority, 1, 99);
  s.integer("cpu", l.cpu, -1, 1023);
  s.boolean("lock_memory", l.lock_memory);
  s.integer<std::uint64_t>("overrun_budget", l.overrun_budget, 0, 1'000'000'000);
  s.integer<std::size_t>("ring_capacity", l.ring_capacity, 1024, std::size_t{1} << 24);
  s.number("stuck_sensor_ms", l.stuck_sensor_ms, 0.0, 10000.0);
  s.number("stuck_sensor_span", l.stuck_sensor_span, 0.0, 1.0, true);
  s.number("feedforward_bandwidth_hz", l.feedforward_bandwidth_hz, 0.0, 1e6);
  s.finish();
}

void read_limits(Section s, LimitsSection& l) {
  s.number("u_min", l.u_min, -kInf, kInf);
  s.number("u_max", l.u_max, -kInf, kInf);
  if (!(l.u_min < l.u_max)) {
    s.fail("u_max", "must be greater than limits.u_min (" + number_text(l.u_min) + "), got " +
                        number_text(l.u_max));
  }
  s.number("slew_v_per_s", l.slew_v_per_s, 0.0, kInf, true);
  s.boolean("fatal_on_limit", l.fatal_on_limit);
  s.optional_number("y_min", l.y_min, -kInf, kInf);
  s.optional_number("y_max", l.y_max, -kInf, kInf);
  if (l.y_min.has_value() != l.y_max.has_value()) {
    s.fail(l.y_min ? "y_max" : "y_min", "limits.y_min and limits.y_max must be given together");
  }
  if (l.y_min && !(*l.y_min < *l.y_max)) {
    s.fail("y_max", "must be greater than limits.y_min (" + number_text(*l.y_min) + "), got " +
                        number_text(*l.y_max));
  }
  s.finish();
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

void read_identify(Section s, IdentifySection& id, const LoopSection& loop,
                   const LimitsSection& limits) {
  s.string("model", id.model, {"pi", "mpi", "cpi", "rpi", "auto"});
  s.integer("operators", id.operators, 0, 100);
  s.integer("dead_zones", id.dead_zones, -1, 50);
  // Default excitation: the whole output range.
  id.offset_v = 0.5 * (limits.u_min + limits.u_max);
  id.amplitude_v = 0.5 * (limits.u_max - limits.u_min);
  s.number("offset_v", id.offset_v, limits.u_min, limits.u_max);
  s.number("amplitude_v", id.amplitude_v, 0.0, limits.u_max - limits.u_min, true);
  const double low = id.offset_v - id.amplitude_v;
  const double high = id.offset_v + id.amplitude_v;
  if (low < limits.u_min - 1e-9 || high > limits.u_max + 1e-9) {
    s.fail("amplitude_v", "offset_v +- amplitude_v = " + range_text(low, high) +
                              " V must lie within [limits.u_min, limits.u_max] = " +
                              range_text(limits.u_min, limits.u_max));
  }
  s.number("frequency_hz", id.frequency_hz, 0.0, loop.rate_hz / 20.0, true);
  s.integer("cycles", id.cycles, 1, 1000);
  s.number("precondition_s", id.precondition_s, 0.0, 60.0, true);
  s.number("settle_s", id.settle_s, 0.0, 600.0);
  s.number("heldout_fraction", id.heldout_fraction, 0.0, 0.9);
  s.number("fit_rate_hz", id.fit_rate_hz, 1.0, 20000.0);
  s.finish();
}

void read_pid(Section s, PidSection& p, const LoopSection& loop) {
  s.optional_number("kp", p.kp, 0.0, kInf);
  s.optional_number("ki", p.ki, 0.0, kInf);
  s.optional_number("kd", p.kd, 0.0, kInf);
  s.optional_number("bandwidth_hz", p.bandwidth_hz, 0.0, loop.rate_hz / 20.0, true);
  s.optional_number("output_filter_hz", p.output_filter_hz, 0.0, kInf);
  if (p.output_filter_hz && *p.output_filter_hz >= loop.rate_hz / 2.0) {
    s.fail("output_filter_hz",
           "must be below loop.rate_hz / 2 = " + number_text(loop.rate_hz / 2.0) + " Hz, got " +
               number_text(*p.output_filter_hz));
  }
  s.number("derivative_filter_hz", p.derivative_filter_hz, 0.0, kInf);
  if (p.derivative_filter_hz >= loop.rate_hz / 2.0) {
    s.fail("derivative_filter_hz",
           "must be below loop.rate_hz / 2 = " + number_text(loop.rate_hz / 2.0) + " Hz, got " +
               number_text(p.derivative_filter_hz));
  }
  s.number("u_fb_min", p.u_fb_min, -kInf, kInf);
  s.number("u_fb_max", p.u_fb_max, -kInf, kInf);
  if (!(p.u_fb_min <= p.u_fb_max)) {
    s.fail("u_fb_max", "must be at least pid.u_fb_min (" + number_text(p.u_fb_min) + "), got " +
                           number_text(p.u_fb_max));
  }
  s.finish();
}

}  // namespace

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
  read_daemon(Section(ctx, "daemon", section_table(ctx, root, "daemon")), c.daemon);
  read_loop(Section(ctx, "loop", section_table(ctx, root, "loop")), c.loop);
  read_limits(Section(ctx, "limits", section_table(ctx, root, "limits")), c.limits);
  read_driver(ctx, section_table(ctx, root, "driver"), c.driver);
  if (const toml::table* actuator = section_table(ctx, root, "actuator")) {
    c.actuator = details::toml_node_to_json(*actuator);
  }
  read_identify(Section(ctx, "identify", section_table(ctx, root, "identify")), c.identify, c.loop,
                c.limits);
  read_pid(Section(ctx, "pid", section_table(ctx, root, "pid")), c.pid, c.loop);
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
  const auto optional = [](const std::optional<double>& v) -> nlohmann::json {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  nlohmann::json driver = c.driver.tables;
  driver["type"] = c.driver.type;
  return {
      {"daemon",
       {{"socket_path", c.daemon.socket_path},
        {"log_dir", c.daemon.log_dir},
        {"model_dir", c.daemon.model_dir},
        {"log_level", c.daemon.log_level}}},
      {"loop",
       {{"rate_hz", c.loop.rate_hz},
        {"realtime", c.loop.realtime},
        {"priority", c.loop.priority},
        {"cpu", c.loop.cpu},
        {"lock_memory", c.loop.lock_memory},
        {"overrun_budget", c.loop.overrun_budget},
        {"ring_capacity", c.loop.ring_capacity},
        {"stuck_sensor_ms", c.loop.stuck_sensor_ms},
        {"stuck_sensor_span", c.loop.stuck_sensor_span},
        {"feedforward_bandwidth_hz", c.loop.feedforward_bandwidth_hz}}},
      {"limits",
       {{"u_min", c.limits.u_min},
        {"u_max", c.limits.u_max},
        {"slew_v_per_s", c.limits.slew_v_per_s},
        {"fatal_on_limit", c.limits.fatal_on_limit},
        {"y_min", optional(c.limits.y_min)},
        {"y_max", optional(c.limits.y_max)}}},
      {"driver", driver},
      {"actuator", c.actuator},
      {"identify",
       {{"model", c.identify.model},
        {"operators", c.identify.operators},
        {"dead_zones", c.identify.dead_zones},
        {"amplitude_v", c.identify.amplitude_v},
        {"offset_v", c.identify.offset_v},
        {"frequency_hz", c.identify.frequency_hz},
        {"cycles", c.identify.cycles},
        {"precondition_s", c.identify.precondition_s},
        {"settle_s", c.identify.settle_s},
        {"heldout_fraction", c.identify.heldout_fraction},
        {"fit_rate_hz", c.identify.fit_rate_hz}}},
      {"pid",
       {{"kp", optional(c.pid.kp)},
        {"ki", optional(c.pid.ki)},
        {"kd", optional(c.pid.kd)},
        {"bandwidth_hz", optional(c.pid.bandwidth_hz)},
        {"output_filter_hz", optional(c.pid.output_filter_hz)},
        {"derivative_filter_hz", c.pid.derivative_filter_hz},
        {"u_fb_min", c.pid.u_fb_min},
        {"u_fb_max", c.pid.u_fb_max}}},
  };
}

nlohmann::json toml_to_json(std::string_view toml_text) {
  return details::toml_node_to_json(parse_toml(toml_text, {}));
}

}  // namespace hystbench::daemon
