#pragma once
// The page's files (daemon/web/), compiled into the daemon by cmake/embed_web_assets.cmake:
// the view serves them from memory and loads nothing from elsewhere.
#include <cstddef>
#include <span>
#include <string_view>

namespace hystbench::daemon::details {

struct WebAsset {
  std::string_view path;          ///< as requested, e.g. "/app.js"; "/" is index.html
  std::string_view content_type;  ///< e.g. "text/javascript; charset=utf-8"
  std::string_view content;
};

/// Every file of the page.
std::span<const WebAsset> web_assets();

}  // namespace hystbench::daemon::details
