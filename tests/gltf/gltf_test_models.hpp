// Test helpers: a tiny glTF 2.0 writer (JSON document + binary buffer, editable before
// serialising, so tests can break any part of it) and a skinned test model with known
// answers: a centimetre, Z-up column under a conversion node, joints with non-identity
// rest rotations, an intermediate non-joint node, up to 8 influences per vertex.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "common/avatar/avatar_model.hpp"
#include "offline/gltf/gltf_import.hpp"

namespace vistel::test {

class GltfBuilder {
 public:
  GltfBuilder();

  nlohmann::json doc;             // the whole document except "buffers" (added on output)
  std::vector<std::uint8_t> bin;  // buffer 0

  // A buffer view over `size` new bytes (4-byte aligned); returns its index.
  int addView(const void* data, std::size_t size, int stride = 0);
  // An accessor over a new view holding `values` (count = values.size() / components).
  template <typename T>
  int addAccessor(const std::vector<T>& values, int component_type, const std::string& type,
                  bool normalized = false) {
    const std::size_t components = type == "SCALAR" ? 1
                                   : type == "MAT4" ? 16
                                                    : static_cast<std::size_t>(type.back() - '0');
    const int view = addView(values.data(), values.size() * sizeof(T));
    nlohmann::json acc = {{"bufferView", view},
                          {"componentType", component_type},
                          {"count", values.size() / components},
                          {"type", type}};
    if (normalized) acc["normalized"] = true;
    doc["accessors"].push_back(acc);
    return static_cast<int>(doc["accessors"].size()) - 1;
  }
  int addNode(const nlohmann::json& node);

  std::string jsonText(const std::string& buffer_uri = "") const;  // buffer 0 with that uri
  std::vector<std::uint8_t> glb() const;
  std::string gltfEmbedded() const;  // buffer as a base64 data URI
  // Writes dir/stem.gltf and dir/stem.bin; returns the .gltf path.
  std::string writeGltfWithBin(const std::string& dir, const std::string& stem) const;
};

// A node's TRS from a rigid (or rigid + uniform scale) matrix.
nlohmann::json trsOf(const glm::dmat4& m);

struct ChainOptions {
  int joints = 10;
  bool normals = false;             // write NORMAL
  bool mesh_space_ibm = true;       // mesh under the conversion node, IBM = W^-1 * W_mesh;
                                    // else mesh node at the root, vertices pre-transformed
  bool scramble_skin_order = true;  // skin.joints in reverse hierarchy order
  bool eight_influences = true;     // JOINTS_1/WEIGHTS_1 too
  int index_component = 5123;       // 5121/5123/5125, or 0 for no indices
  bool helper_node = true;          // a non-joint node between joints 2 and 3
  std::vector<int> unweighted;      // vertices given all-zero weights
};

struct ChainGltf {
  GltfBuilder file;
  std::vector<glm::dvec3> positions_model;  // expected model-space positions (nvert), metres
  std::vector<glm::dvec3> normals_model;    // expected outward normals (nvert)
  std::vector<glm::dvec3> radial_model;     // model-space outward direction of each vertex
  std::vector<std::string> names;           // joints in hierarchy order
  std::vector<glm::dmat4> joint_model;      // expected rigid model frames (hierarchy order)
  std::vector<std::map<std::string, double>> weights;  // expected normalised weights (nvert)
  std::vector<int> joint_nodes;                        // node of hierarchy joint j
  int mesh_node = -1;
  int triangles = 0;
};

ChainGltf makeChainGltf(const ChainOptions& options = {});

// Weights of vertex v of a skin as joint name -> weight (non-zero only).
std::map<std::string, double> weightsByName(const AvatarModel& avatar, std::size_t v);

// Whether the import reported a warning containing `text`.
inline bool hasWarning(const GltfImportReport& report, std::string_view text) {
  return std::any_of(report.warnings.begin(), report.warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

}  // namespace vistel::test
