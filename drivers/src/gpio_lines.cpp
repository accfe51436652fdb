#include "hystbench/drivers/gpio_lines.hpp"

#include <atomic>
#include <stdexcept>

#include "details/json_params.hpp"

namespace hystbench::drivers {

using details::ParamError;
using details::Params;

// ---- in-memory backend ----

struct MemoryGpioBackend::Pin {
  std::atomic<bool> level{false};
  std::atomic<int> rising{0};
  std::atomic<int> requests{0};
};

namespace {

class MemoryLine final : public GpioLine {
 public:
  MemoryLine(std::shared_ptr<MemoryGpioBackend::Pin> pin, bool active_low)
      : pin_(std::move(pin)), active_low_(active_low) {
    ++pin_->requests;
  }
  ~MemoryLine() override { --pin_->requests; }
  bool set(bool asserted) noexcept override {
    const bool high = asserted != active_low_;
    if (high && !pin_->level.exchange(high)) ++pin_->rising;
    pin_->level = high;
    return true;
  }
  int get() noexcept override { return pin_->level.load() != active_low_ ? 1 : 0; }

 private:
  std::shared_ptr<MemoryGpioBackend::Pin> pin_;
  bool active_low_;
};

}  // namespace

std::shared_ptr<MemoryGpioBackend::Pin> MemoryGpioBackend::pin(const std::string& chip_line) {
  std::lock_guard lock(m_);
  auto& p = pins_[chip_line];
  if (!p) p = std::make_shared<Pin>();
  return p;
}

std::unique_ptr<GpioLine> MemoryGpioBackend::request_output(const GpioLineConfig& c, bool initial,
                                                            const std::string&) {
  auto p = pin(c.describe());
  if (p->requests > 0) throw std::runtime_error("gpio " + c.describe() + ": line busy");
  auto line = std::make_unique<MemoryLine>(p, c.active_low);
  line->set(initial);
  return line;
}

std::unique_ptr<GpioLine> MemoryGpioBackend::request_input(const GpioLineConfig& c,
                                                           const std::string&) {
  auto p = pin(c.describe());
  if (p->requests > 0) throw std::runtime_error("gpio " + c.describe() + ": line busy");
  return std::make_unique<MemoryLine>(p, c.active_low);
}

bool MemoryGpioBackend::level(const std::string& chip_line) const {
  std::lock_guard lock(m_);
  auto it = pins_.find(chip_line);
  return it != pins_.end() && it->second->level.load();
}

void MemoryGpioBackend::set_level(const std::string& chip_line, bool high) {
  pin(chip_line)->level = high;
}

int MemoryGpioBackend::rising_edges(const std::string& chip_line) const {
  std::lock_guard lock(m_);
  auto it = pins_.find(chip_line);
  return it == pins_.end() ? 0 : it->second->rising.load();
}

int MemoryGpioBackend::requested() const {
  std::lock_guard lock(m_);
  int n = 0;
  for (const auto& [name, p] : pins_) n += p->requests.load();
  return n;
}

// ---- config ----

GpioConfig parse_gpio_config(const nlohmann::json& table, const std::string& path) {
  try {
    const Params p(table, path);
    p.allow_only({"chip", "consumer", "sync_pulse_ticks", "sync_every_ticks", "enable", "estop",
                  "run_active", "sync_pulse"});
    GpioConfig c;
    const std::string chip = p.string("chip", "gpiochip0");
    c.consumer = p.string("consumer", c.consumer);
    c.sync_pulse_ticks = static_cast<std::uint32_t>(p.integer("sync_pulse_ticks", 1, 1, 1000000));
    c.sync_every_ticks =
        static_cast<std::uint64_t>(p.integer("sync_every_ticks", 0, 0, 1000000000));
    // One line's table `j` at `where`.
    const auto one_line = [&](const nlohmann::json& j, const std::string& where,
                              bool active_low_default) {
      const Params t(j, where);
      t.allow_only({"chip", "line", "active_low"});
      GpioLineConfig l;
      l.chip = t.string("chip", chip);
      if (!t.has("line")) throw ParamError(t.key_path("line") + ": required (name or offset)");
      const nlohmann::json& v = j["line"];
      if (v.is_number_unsigned() || (v.is_number_integer() && v.get<std::int64_t>() >= 0)) {
        l.line = std::to_string(v.get<std::int64_t>());
      } else if (v.is_string() && !v.get<std::string>().empty()) {
        l.line = v.get<std::string>();
      } else {
        throw ParamError(t.key_path("line") + ": must be a line name or a non-negative offset");
      }
      l.active_low = t.boolean("active_low", active_low_default);
      return l;
    };
    const auto line = [&](const char* key,
                          bool active_low_default) -> std::optional<GpioLineConfig> {
      if (!p.has(key)) return std::nullopt;
      return one_line(table[key], p.key_path(key), active_low_default);
    };
    if (p.has("enable") && table["enable"].is_array()) {
      const nlohmann::json& lines = table["enable"];
      if (lines.empty()) {
        throw ParamError(p.key_path("enable") + ": an array of one line table per axis, got none");
      }
      for (std::size_t i = 0; i < lines.size(); ++i) {
        c.enable.push_back(
            one_line(lines[i], p.key_path("enable") + "[" + std::to_string(i) + "]", false));
      }
    } else if (auto enable = line("enable", false)) {
      c.enable.push_back(*enable);
    }
    c.estop = line("estop", true);
    c.run_active = line("run_active", false);
    c.sync_pulse = line("sync_pulse", false);
    return c;
  } catch (const ParamError& e) {
    throw std::invalid_argument(e.what());
  }
}

// ---- the lines ----

void GpioLines::request(const GpioConfig& config, GpioBackend& backend) {
  release();
  config_ = config;
  try {
    if (config.estop) estop_ = backend.request_input(*config.estop, config.consumer);
    for (const GpioLineConfig& l : config.enable) {
      enable_.push_back(backend.request_output(l, false, config.consumer));
    }
    if (config.run_active) {
      run_active_line_ = backend.request_output(*config.run_active, false, config.consumer);
    }
    if (config.sync_pulse)
      sync_ = backend.request_output(*config.sync_pulse, false, config.consumer);
  } catch (...) {
    release();
    throw;
  }
}

void GpioLines::release() noexcept {
  safe();
  enable_.clear();
  estop_.reset();
  run_active_line_.reset();
  sync_.reset();
}

void GpioLines::set_run_active(bool active) noexcept {
  run_active_ = active;
  run_ticks_ = 0;
  for (const auto& enable : enable_) enable->set(active);
  if (run_active_line_) run_active_line_->set(active);
  if (sync_) sync_->set(active);  // high for sample 0 and the next sync_pulse_ticks - 1
  pulse_off_at_ = config_.sync_pulse_ticks;
}

void GpioLines::tick() noexcept {
  if (!run_active_ || !sync_) return;
  const std::uint64_t k = run_ticks_++;  // the sample this tick writes
  if (k == pulse_off_at_) sync_->set(false);
  if (config_.sync_every_ticks > 0 && k > 0 && k % config_.sync_every_ticks == 0) {
    sync_->set(true);
    pulse_off_at_ = k + config_.sync_pulse_ticks;
  }
}

bool GpioLines::estop_asserted() noexcept { return estop_ && estop_->get() != 0; }

void GpioLines::safe() noexcept {
  for (const auto& enable : enable_) enable->set(false);
  if (run_active_line_) run_active_line_->set(false);
  if (sync_) sync_->set(false);
  run_active_ = false;
}

}  // namespace hystbench::drivers
