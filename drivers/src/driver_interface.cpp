#include "hystbench/drivers/driver_interface.hpp"

#include <iterator>

namespace hystbench::drivers {

std::string_view to_string(DriverStatus s) noexcept {
  constexpr std::string_view kNames[] = {"ok", "stale", "timeout", "error", "fault"};
  const auto i = static_cast<std::size_t>(s);
  return i < std::size(kNames) ? kNames[i] : "unknown";
}

Result DriverInterface::on_deactivate() {
  const DriverStatus s = safe_state();
  if (s == DriverStatus::kOk) return Result::success();
  return Result::failure("driver." + std::string(type()) +
                         ": the safe output at deactivation failed (" + std::string(to_string(s)) +
                         ")");
}

DriverStatus DriverInterface::write_axes(std::span<const double> outputs_v) noexcept {
  return outputs_v.empty() ? DriverStatus::kOk : write(outputs_v.front());
}

DriverStatus DriverInterface::read_axes(std::span<Measurement> out) noexcept {
  Measurement unused;
  return read(out.empty() ? unused : out.front());
}

std::string DriverInterface::describe_fault(int cause, std::int64_t detail) const {
  return std::string(type()) + " driver fault " + std::to_string(cause) + " (detail " +
         std::to_string(detail) + ")";
}

}  // namespace hystbench::drivers
