// Static files of the spectator web server, embedded into the binary at build time
// (server/web/CMakeLists.txt): the page (web/), and three.js r111 with its GLTFLoader and
// OrbitControls from Debian's libjs-three (/usr/share/javascript/three). Nothing is read
// from disk or fetched at run time.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

namespace vistel::server {

struct WebAsset {
  std::string_view name;          // "spectator.js", "three.min.js", ...
  std::string_view content_type;  // "text/javascript; charset=utf-8", ...
  std::span<const std::uint8_t> bytes;
  std::string_view sha256;  // hex: the ETag
};

// Every embedded asset (generated).
std::span<const WebAsset> webAssets();

// The asset of that name, or null.
const WebAsset* findWebAsset(std::string_view name);

// The Content-Type of a file name by its extension (application/octet-stream when unknown).
constexpr std::string_view contentTypeOf(std::string_view name) {
  if (name.ends_with(".js")) return "text/javascript; charset=utf-8";
  if (name.ends_with(".html")) return "text/html; charset=utf-8";
  if (name.ends_with(".css")) return "text/css; charset=utf-8";
  if (name.ends_with(".json")) return "application/json";
  if (name.ends_with(".txt") || name.ends_with(".md")) return "text/plain; charset=utf-8";
  if (name.ends_with(".png")) return "image/png";
  if (name.ends_with(".svg")) return "image/svg+xml";
  return "application/octet-stream";
}

}  // namespace vistel::server
