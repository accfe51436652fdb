// The libgpiod v1 line backend: chip by name, number, path or label (gpiod_chip_open_lookup),
// line by name (gpiod_chip_find_line) or offset (gpiod_chip_get_line).
#include <gpiod.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "hystbench/drivers/gpio_lines.hpp"

namespace hystbench::drivers {

namespace {

class LibgpiodLine final : public GpioLine {
 public:
  LibgpiodLine(gpiod_chip* chip, gpiod_line* line) : chip_(chip), line_(line) {}
  ~LibgpiodLine() override {
    gpiod_line_release(line_);
    gpiod_chip_close(chip_);
  }
  bool set(bool asserted) noexcept override {
    return gpiod_line_set_value(line_, asserted ? 1 : 0) == 0;
  }
  int get() noexcept override { return gpiod_line_get_value(line_); }

 private:
  gpiod_chip* chip_;
  gpiod_line* line_;
};

class LibgpiodBackend final : public GpioBackend {
 public:
  std::unique_ptr<GpioLine> request_output(const GpioLineConfig& c, bool initial,
                                           const std::string& consumer) override {
    auto [chip, line] = open(c);
    const int flags = c.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    if (gpiod_line_request_output_flags(line, consumer.c_str(), flags, initial ? 1 : 0) != 0) {
      const int err = errno;
      gpiod_chip_close(chip);
      throw std::runtime_error("gpio " + c.describe() +
                               ": cannot request as output: " + std::strerror(err));
    }
    return std::make_unique<LibgpiodLine>(chip, line);
  }
  std::unique_ptr<GpioLine> request_input(const GpioLineConfig& c,
                                          const std::string& consumer) override {
    auto [chip, line] = open(c);
    const int flags = c.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    if (gpiod_line_request_input_flags(line, consumer.c_str(), flags) != 0) {
      const int err = errno;
      gpiod_chip_close(chip);
      throw std::runtime_error("gpio " + c.describe() +
                               ": cannot request as input: " + std::strerror(err));
    }
    return std::make_unique<LibgpiodLine>(chip, line);
  }

 private:
  static std::pair<gpiod_chip*, gpiod_line*> open(const GpioLineConfig& c) {
    gpiod_chip* chip = gpiod_chip_open_lookup(c.chip.c_str());
    if (chip == nullptr) {
      throw std::runtime_error("gpio " + c.describe() + ": no GPIO chip '" + c.chip +
                               "': " + std::strerror(errno));
    }
    const bool is_offset =
        !c.line.empty() && std::all_of(c.line.begin(), c.line.end(),
                                       [](unsigned char ch) { return std::isdigit(ch) != 0; });
    gpiod_line* line = is_offset
                           ? gpiod_chip_get_line(chip, static_cast<unsigned>(std::stoul(c.line)))
                           : gpiod_chip_find_line(chip, c.line.c_str());
    if (line == nullptr) {
      const int err = errno;
      gpiod_chip_close(chip);
      throw std::runtime_error("gpio " + c.describe() + ": no line " +
                               (is_offset ? "at offset " : "named ") + c.line + " on " + c.chip +
                               ": " + std::strerror(err));
    }
    return {chip, line};
  }
};

}  // namespace

std::shared_ptr<GpioBackend> make_libgpiod_backend() { return std::make_shared<LibgpiodBackend>(); }

}  // namespace hystbench::drivers
