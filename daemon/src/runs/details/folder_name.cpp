#include "runs/details/folder_name.hpp"

#include <algorithm>
#include <cctype>

namespace hystbench::daemon::details {

bool is_folder_name(const std::string& name) {
  return !name.empty() && name.size() <= 128 && name.front() != '.' &&
         std::all_of(name.begin(), name.end(), [](unsigned char c) {
           return std::isalnum(c) || c == '.' || c == '_' || c == '-';
         });
}

}  // namespace hystbench::daemon::details
