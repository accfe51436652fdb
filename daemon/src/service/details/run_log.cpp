#include "service/details/run_log.hpp"

#include <exception>
#include <memory>
#include <string>
#include <utility>

#include "hystbench/common/command_error.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"
#include "hystbench/daemon/loop/sample_log_writer.hpp"

namespace hystbench::daemon::details {

void open_run_log(RunProgram& p, nlohmann::json header, const BenchSettings& settings) {
  const char* clock = to_string(settings.loop.clock);
  if (header.contains("run") && header["run"].is_object()) header["run"]["clock"] = clock;
  p.summary["clock"] = clock;
  SampleLogOptions opt;
  opt.log_dir = settings.log_dir;
  opt.run_id = p.run_id;
  opt.header = std::move(header);
  opt.ring_capacity = settings.log_ring_capacity;
  if (p.axes() > 1) opt.axes.assign(settings.axes.begin(), settings.axes.begin() + p.axes());
  try {
    p.log = std::make_unique<SampleLogWriter>(std::move(opt));
  } catch (const std::exception& e) {
    throw common::CommandError("log_error", std::string("cannot open the run log: ") + e.what());
  }
}

}  // namespace hystbench::daemon::details
