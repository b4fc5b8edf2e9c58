#pragma once
// The field view's page and assets (predictor/web/*.html, *.js, *.css), built into the binary by
// embed_assets.cmake so that ssl-predictor needs no files beside it and the page loads nothing
// from elsewhere.

#include <span>
#include <string_view>

namespace ssl_formation::predictor::web {

struct WebAsset {
  std::string_view path;          // "/index.html", "/field.js", ...
  std::string_view content_type;  // "text/html; charset=utf-8", ...
  std::string_view body;
};

std::span<const WebAsset> web_assets();

// The asset served at `target` ("/" is "/index.html"; a query string is ignored), or nullptr.
const WebAsset* find_web_asset(std::string_view target);

}  // namespace ssl_formation::predictor::web
