#include "hystbench/drivers/driver.hpp"

#include <stdexcept>

#include "hystbench/drivers/can_amplifier.hpp"
#include "hystbench/drivers/gpio_driver.hpp"
#include "hystbench/drivers/loopback_driver.hpp"
#include "hystbench/drivers/modbus_daq.hpp"

namespace hystbench::drivers {

std::string_view to_string(DriverStatus s) noexcept {
  switch (s) {
    case DriverStatus::kOk:
      return "ok";
    case DriverStatus::kStale:
      return "stale";
    case DriverStatus::kTimeout:
      return "timeout";
    case DriverStatus::kError:
      return "error";
    case DriverStatus::kFault:
      return "fault";
  }
  return "unknown";
}

const std::vector<DriverBackend>& driver_backends() {
  static const std::vector<DriverBackend> table{
      {"loopback", "simulated actuator in the loop (no hardware)",
       []() -> std::unique_ptr<Driver> { return std::make_unique<LoopbackDriver>(); }},
      {"modbus", "Modbus DAQ over TCP or RTU (libmodbus); [driver.modbus], [driver.modbus.gpio]",
       with_gpio<ModbusDaqDriver>},
      {"can", "CAN piezo amplifier over SocketCAN (libsocketcan); [driver.can], [driver.can.gpio]",
       with_gpio<CanAmplifierDriver>},
  };
  return table;
}

std::unique_ptr<Driver> make_driver(std::string_view type) {
  std::string names;
  for (const auto& b : driver_backends()) {
    if (b.type == type) return b.create();
    names += (names.empty() ? "" : ", ") + std::string(b.type);
  }
  throw std::invalid_argument("driver.type: unknown driver '" + std::string(type) +
                              "' (available: " + names + ")");
}

}  // namespace hystbench::drivers
