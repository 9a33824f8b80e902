#include "server/web/web_assets.hpp"

namespace vistel::server {

const WebAsset* findWebAsset(std::string_view name) {
  for (const WebAsset& asset : webAssets()) {
    if (asset.name == name) return &asset;
  }
  return nullptr;
}

}  // namespace vistel::server
