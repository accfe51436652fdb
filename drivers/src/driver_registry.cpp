#include "hystbench/drivers/driver_registry.hpp"

#include <stdexcept>
#include <string>

#include "hystbench/drivers/can_amplifier.hpp"
#include "hystbench/drivers/driver.hpp"
#include "hystbench/drivers/gpio_driver.hpp"
#include "hystbench/drivers/io_thread_driver.hpp"
#include "hystbench/drivers/loopback_driver.hpp"
#include "hystbench/drivers/modbus_daq.hpp"

namespace hystbench::drivers {

const std::vector<DriverBackend>& driver_backends() {
  static const std::vector<DriverBackend> table{
      {"loopback", "simulated actuator in the loop (no hardware)", make_interface<LoopbackDriver>},
      {"modbus", "Modbus DAQ over TCP or RTU (libmodbus); [driver.modbus], [driver.modbus.gpio]",
       make_interface<ModbusDaqDriver, IoThreadDriver, GpioDriver>},
      {"can", "CAN piezo amplifier over SocketCAN (libsocketcan); [driver.can], [driver.can.gpio]",
       make_interface<CanAmplifierDriver, GpioDriver>},
  };
  return table;
}

std::unique_ptr<Driver> make_driver(std::string_view type) {
  std::string names;
  for (const auto& b : driver_backends()) {
    if (b.type == type) return std::make_unique<Driver>(b.create());
    names += (names.empty() ? "" : ", ") + std::string(b.type);
  }
  throw std::invalid_argument("driver.type: unknown driver '" + std::string(type) +
                              "' (available: " + names + ")");
}

}  // namespace hystbench::drivers
