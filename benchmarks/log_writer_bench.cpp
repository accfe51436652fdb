// Sample log writer throughput: records pushed through the SPSC ring and written as CSV rows to
// a file in the temp folder, until close() has written them all (no record dropped).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <thread>

#include "hystbench/daemon/loop/sample_log_writer.hpp"

namespace hd = hystbench::daemon;

static void BM_SampleLogWriterRows(benchmark::State& state) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("hystbench_logbench_" + std::to_string(::getpid()));
  const auto rows = static_cast<std::uint64_t>(state.range(0));
  int run = 0;
  std::uint64_t written = 0;
  for (auto _ : state) {
    hd::SampleLogOptions o;
    o.log_dir = dir;
    o.run_id = "bench" + std::to_string(run++);
    o.update_latest_link = false;
    hd::SampleLogWriter w(o);
    hd::SampleRecord r;
    for (std::uint64_t k = 0; k < rows; ++k) {
      r.index = k;
      r.scheduled_ns = static_cast<std::int64_t>(k) * 100'000;
      r.wake_ns = r.scheduled_ns + 20'000 + static_cast<std::int64_t>(k % 977);
      r.u_ff = r.u_out = 75.0 + 1e-3 * static_cast<double>(k % 15000);
      r.reference = r.y_measured = 0.3 * r.u_out + 1e-7 * static_cast<double>(k);
      // A full ring counts a drop: keep at most half of it in flight, let the writer catch up.
      while (k - w.written() >= o.ring_capacity / 2) std::this_thread::yield();
      w.push(r);
    }
    const auto counts = w.close();
    written += counts.written;
    if (counts.dropped != 0) state.SkipWithError("records dropped");
  }
  std::filesystem::remove_all(dir);
  state.SetItemsProcessed(static_cast<std::int64_t>(written));
}
BENCHMARK(BM_SampleLogWriterRows)
    ->Arg(1'000'000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2)
    ->UseRealTime();
