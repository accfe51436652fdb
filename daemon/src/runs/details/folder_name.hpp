#pragma once
// The names a client may give for a file in the daemon's folders (models, learned drives):
// letters, digits, '.', '_', '-', at most 128, not starting with '.'; never a path. Any thread.
#include <string>

namespace hystbench::daemon::details {

/// True for a name a client may give for a file in a daemon folder (see above).
bool is_folder_name(const std::string& name);

}  // namespace hystbench::daemon::details
