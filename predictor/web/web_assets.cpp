#include "web_assets.hpp"

namespace ssl_formation::predictor::web {

const WebAsset* find_web_asset(std::string_view target) {
  const auto query = target.find_first_of("?#");
  if (query != std::string_view::npos) target = target.substr(0, query);
  if (target == "/") target = "/index.html";
  for (const WebAsset& asset : web_assets()) {
    if (asset.path == target) return &asset;
  }
  return nullptr;
}

}  // namespace ssl_formation::predictor::web
