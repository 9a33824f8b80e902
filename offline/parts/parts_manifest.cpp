#include "offline/parts/parts_manifest.hpp"

#include <filesystem>

#include "common/base/file.hpp"
#include "common/config/config_table.hpp"

namespace vistel {
namespace {

// A path named in the manifest: absolute as it is, else relative to the manifest's folder.
std::string besideManifest(const std::string& folder, const std::string& path) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || folder.empty()) return path;
  return (std::filesystem::path(folder) / p).string();
}

}  // namespace

Result<PartsManifest> parsePartsManifest(std::string_view text, const std::string& folder,
                                         std::string_view name) {
  Result<toml::table> root = parseConfigText(text, name);
  if (!root) return root.error();
  PartsManifest out;

  // The top level: source and band.
  for (const auto& [key, node] : *root) {
    const std::string_view k = key.str();
    if (k == "source") {
      const auto* s = node.as_string();
      if (s == nullptr) return fail("{}: source: not a string", name);
      out.source = s->get();
    } else if (k == "band_m") {
      const std::optional<double> v = node.value<double>();
      if (!v || !(*v > 0.0 && *v <= 0.5)) return fail("{}: band_m: not a number in (0, 0.5]", name);
      out.band_m = static_cast<float>(*v);
    } else if (k != "part" && k != "joint") {
      return fail("{}: unknown key '{}'", name, k);
    }
  }
  if (!out.source.empty()) {
    std::error_code ec;
    if (!std::filesystem::exists(out.source, ec)) out.source = besideManifest(folder, out.source);
  }

  // [[part]] tables.
  const toml::array* parts = (*root)["part"].as_array();
  if (parts == nullptr || parts->empty()) return fail("{}: no [[part]] tables", name);
  for (std::size_t i = 0; i < parts->size(); ++i) {
    const std::string where = "part " + std::to_string(i + 1);
    ConfigTable t((*parts)[i].as_table(), where, name);
    if ((*parts)[i].as_table() == nullptr)
      return fail("{}: [[part]] {} is not a table", name, i + 1);
    ManifestPart part;
    int count = 0;
    VISTEL_CONFIG_TRY(t.string("file", part.file));
    VISTEL_CONFIG_TRY(t.string("segment", part.segment));
    VISTEL_CONFIG_TRY(t.string("bone", part.bone));
    VISTEL_CONFIG_TRY(t.number("vertices", count, 0, 1e9));
    VISTEL_CONFIG_TRY(t.number("triangles", count, 0, 1e9));
    VISTEL_CONFIG_TRY(t.checkUnknown());
    if (part.file.empty()) return t.error("file", "missing");
    if (part.segment.empty()) return t.error("segment", "missing");
    for (const ManifestPart& other : out.parts) {
      if (other.segment == part.segment) return t.error("segment", "named twice");
    }
    part.file = besideManifest(folder, part.file);
    out.parts.push_back(std::move(part));
  }

  // [[joint]] tables, each between two parts of the manifest.
  if (const toml::array* joints = (*root)["joint"].as_array(); joints != nullptr) {
    for (std::size_t i = 0; i < joints->size(); ++i) {
      const std::string where = "joint " + std::to_string(i + 1);
      if ((*joints)[i].as_table() == nullptr) {
        return fail("{}: [[joint]] {} is not a table", name, i + 1);
      }
      ConfigTable t((*joints)[i].as_table(), where, name);
      ManifestJoint joint;
      VISTEL_CONFIG_TRY(t.string("name", joint.name));
      VISTEL_CONFIG_TRY(t.string("bone", joint.bone));
      VISTEL_CONFIG_TRY(t.vec3("position", joint.position, -1e3, 1e3));
      VISTEL_CONFIG_TRY(t.number("blend_radius_m", joint.blend_radius_m, 1e-4, 1.0));
      const toml::node* between = t.node("between");
      VISTEL_CONFIG_TRY(t.checkUnknown());
      const toml::array* pair = between != nullptr ? between->as_array() : nullptr;
      if (pair == nullptr || pair->size() != 2 || !(*pair)[0].is_string() ||
          !(*pair)[1].is_string()) {
        return t.error("between", "not two segment names");
      }
      joint.parent_segment = (*pair)[0].as_string()->get();
      joint.child_segment = (*pair)[1].as_string()->get();
      for (const std::string* seg : {&joint.parent_segment, &joint.child_segment}) {
        bool found = false;
        for (const ManifestPart& p : out.parts) found = found || p.segment == *seg;
        if (!found) return t.error("between", "'" + *seg + "' is no part's segment");
      }
      if (joint.parent_segment == joint.child_segment) {
        return t.error("between", "a segment joined to itself");
      }
      if (!(joint.blend_radius_m > 0.0f)) return t.error("blend_radius_m", "missing");
      out.joints.push_back(std::move(joint));
    }
  }
  return out;
}

Result<PartsManifest> readPartsManifest(const std::string& path) {
  Result<std::string> text = readFileText(path);
  if (!text) return text.error();
  const std::string folder = std::filesystem::path(path).parent_path().string();
  return parsePartsManifest(*text, folder, path);
}

}  // namespace vistel
