#pragma once
// The table of compiled-in drivers: a new driver is one class (driver_interface.hpp) and one
// line in drivers/src/driver_registry.cpp, e.g.
//   {"mydaq", "what it is; [driver.mydaq]", make_interface<MyDaqDriver>},
// with wrappers listed after it, innermost first: make_interface<ModbusDaqDriver,
// IoThreadDriver, GpioDriver> is the Modbus driver on an I/O thread with GPIO lines.
// Not real-time (lookups and construction allocate).
#include <memory>
#include <string_view>
#include <vector>

#include "hystbench/drivers/driver_interface.hpp"

namespace hystbench::drivers {

class Driver;

/// One row of the driver table: how to make a backend and what it is.
struct DriverBackend {
  std::string_view type;
  std::string_view description;
  std::unique_ptr<DriverInterface> (*create)();
};

/// `D`, wrapped in each of `Wrappers` in turn (each constructible from the unique_ptr it wraps).
template <typename D, typename... Wrappers>
std::unique_ptr<DriverInterface> make_interface() {
  std::unique_ptr<DriverInterface> d = std::make_unique<D>();
  ((d = std::make_unique<Wrappers>(std::move(d))), ...);
  return d;
}

/// Every compiled-in backend.
const std::vector<DriverBackend>& driver_backends();
/// The backend named `type` in the framework's Driver; throws std::invalid_argument listing the
/// valid names.
std::unique_ptr<Driver> make_driver(std::string_view type);

}  // namespace hystbench::drivers
