// The node hierarchy of a glTF 2.0 file, checked (child indices in range, one parent per
// node, no cycles, well-formed finite transforms) and with every node's world transform.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <tiny_gltf.h>
#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

struct GltfNodeGraph {
  std::vector<int> parents;        // parent node per node (nnode), -1 for roots
  std::vector<glm::dmat4> local;   // node transform relative to its parent (nnode)
  std::vector<glm::dmat4> world;   // node transform in the scene's world space (nnode)
  std::vector<std::string> names;  // node name, or "node N" when it has none (nnode)
};

// Builds the graph; the error names the source, the node and the reason ("node 4: child
// 9 does not exist", "node 2 has two parents (0 and 1)", "node graph has a cycle through
// node 3", "node 5: rotation has 3 values"). Cost: O(nodes + children).
Result<GltfNodeGraph> buildNodeGraph(const tinygltf::Model& model, std::string_view source);

// Nodes of the scene to show (the default scene, else scene 0, else every root node),
// depth first, parents before children. Invalid scene entries give an Error.
Result<std::vector<int>> sceneNodeOrder(const tinygltf::Model& model, const GltfNodeGraph& graph,
                                        std::string_view source);

}  // namespace vistel
