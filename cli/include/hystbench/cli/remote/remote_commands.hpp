#pragma once
// The bench commands of the `hystbench` CLI: they talk to hystbenchd over its socket.
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hystbench::cli {

class BenchClient;

/// Socket path: $HYSTBENCH_SOCKET when set, else /run/hystbench/hystbench.sock.
std::string default_socket_path();

/// Samples a command sends ahead of itself in upload.chunk requests (upload_store.hpp): a
/// trajectory for track, a drive for excite, read from the user's file by the CLI.
struct RemoteUpload {
  std::string kind;    ///< "reference" (µm) or "drive" (V)
  std::string param;   ///< the command's key that names the upload: reference_upload, drive_upload
  std::string source;  ///< the file, for messages
  std::vector<double> t, values;  ///< t [s] is not sent when rate_hz > 0
  double rate_hz = 0.0;
  std::vector<std::size_t> lines;  ///< the file's line of each value (may be empty)
};

/// Reads `path`'s time column and one value column (scaled; t = row / rate_hz when rate_hz > 0)
/// as an upload of `kind` ("reference" or "drive"). Throws DataFileError naming the file, column,
/// line and the option that names the column (--yr-column, --u-column).
RemoteUpload read_upload(const std::string& path, const std::string& kind,
                         const std::string& t_column, const std::string& value_column, double scale,
                         double rate_hz);

/// Sends `upload` in chunks on `client`'s connection and returns its name; `progress` (may be
/// empty) gets the fraction sent. Throws ClientError, or std::runtime_error with the daemon's
/// refusal.
std::string send_upload(BenchClient& client, const RemoteUpload& upload,
                        const std::function<void(double)>& progress);

struct RemoteCommand {
  std::string socket_path;
  std::string
      cmd;  ///< status, identify, track, stop, abort, reset, model.get, model.load, config.get
  nlohmann::json params = nlohmann::json::object();
  bool wait = false;  ///< identify/track: follow progress until the run ends, print its result
  bool json_output = false;
  /// track --wait: when the run ends, its log's plots go here (plot_run_log); empty = none.
  std::string plot_dir;
  /// Sent first on the same connection; its name goes into params[upload->param].
  std::optional<RemoteUpload> upload;
  /// track --reference-file, excite --input-file: the file, read once the daemon says what it
  /// drives. One axis: its value column, sent as `upload`. A stage of several axes (status'
  /// "axes"): a column per axis, named as the axis, each sent as its own upload under
  /// params["reference_uploads" or "drive_uploads"][axis]; a file without an axis's column is
  /// refused naming it.
  struct ReferenceFile {
    std::string path, t_column = "t", value_column = "yr";
    double scale = 1.0, rate_hz = 0.0;
    std::string kind = "reference";  ///< "reference" (µm, track) or "drive" (V, excite)
  };
  std::optional<ReferenceFile> reference_file;
};

/// Returns the exit code: 0 ok, 1 refused by the daemon or the run did not complete,
/// 2 cannot reach the daemon.
int run_remote(const RemoteCommand& cmd, std::ostream& out, std::ostream& err);

/// Follows the events of run `run_id` until its run.finished and returns the run's result;
/// `progress` (may be empty) gets each run.progress / fit.progress as (fraction 0..1, what).
/// Throws ClientError when the daemon goes away.
nlohmann::json wait_for_run(BenchClient& client, const std::string& run_id,
                            const std::function<void(double, const std::string&)>& progress);

/// Before a run with feedback (`compensator` inverse+pid or pid): where the bench holds no
/// measured frequency response to design the loop on, says so on `err` and runs frf first
/// (with progress on a terminal). False when frf could not measure one (`err` says why).
bool measure_response_if_missing(BenchClient& client, const std::string& compensator,
                                 std::ostream& err);

/// Draws a progress bar on a terminal line (carriage return, no newline).
void progress_bar(std::ostream& err, double fraction, const std::string& label);

/// Human-readable summary of a run result (as in the run.finished event).
void print_run_result(const nlohmann::json& result, std::ostream& out);

/// Human-readable account of tune's reply: the loop, its margins and limit; on a stage each
/// axis's, then the loops checked together through the coupling.
void print_tune_result(const nlohmann::json& result, std::ostream& out);

}  // namespace hystbench::cli
