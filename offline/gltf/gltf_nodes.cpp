#include "offline/gltf/gltf_nodes.hpp"

#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/quaternion.hpp>

namespace vistel {
namespace {

bool allFinite(const std::vector<double>& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

// The node's local matrix: `matrix` (column-major) or T * R * S.
Result<glm::dmat4> localTransform(const tinygltf::Node& node, std::string_view where) {
  if (!node.matrix.empty()) {
    if (node.matrix.size() != 16)
      return fail("{}: matrix has {} values, not 16", where, node.matrix.size());
    if (!allFinite(node.matrix)) return fail("{}: matrix has a non-finite value", where);
    glm::dmat4 m(1.0);
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[static_cast<std::size_t>(c * 4 + r)];
    }
    if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0) {
      return fail("{}: matrix is not affine (last row must be 0 0 0 1)", where);
    }
    return m;
  }
  glm::dvec3 t(0.0), s(1.0);
  glm::dquat r(1.0, 0.0, 0.0, 0.0);
  if (!node.translation.empty()) {
    if (node.translation.size() != 3) {
      return fail("{}: translation has {} values, not 3", where, node.translation.size());
    }
    if (!allFinite(node.translation)) return fail("{}: translation has a non-finite value", where);
    t = glm::dvec3(node.translation[0], node.translation[1], node.translation[2]);
  }
  if (!node.rotation.empty()) {
    if (node.rotation.size() != 4) {
      return fail("{}: rotation has {} values, not 4", where, node.rotation.size());
    }
    if (!allFinite(node.rotation)) return fail("{}: rotation has a non-finite value", where);
    // glTF stores x, y, z, w; glm's constructor takes w first.
    r = glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    const double len = glm::length(r);
    if (!(len > 1e-6)) return fail("{}: rotation is a zero quaternion", where);
    r = r / len;
  }
  if (!node.scale.empty()) {
    if (node.scale.size() != 3)
      return fail("{}: scale has {} values, not 3", where, node.scale.size());
    if (!allFinite(node.scale)) return fail("{}: scale has a non-finite value", where);
    s = glm::dvec3(node.scale[0], node.scale[1], node.scale[2]);
  }
  const glm::dmat3 rm = glm::mat3_cast(r);
  glm::dmat4 m(1.0);
  m[0] = glm::dvec4(rm[0] * s.x, 0.0);
  m[1] = glm::dvec4(rm[1] * s.y, 0.0);
  m[2] = glm::dvec4(rm[2] * s.z, 0.0);
  m[3] = glm::dvec4(t, 1.0);
  return m;
}

}  // namespace

Result<GltfNodeGraph> buildNodeGraph(const tinygltf::Model& model, std::string_view source) {
  const std::size_t n = model.nodes.size();
  GltfNodeGraph g;
  g.parents.assign(n, -1);
  g.local.resize(n);
  g.world.resize(n);
  g.names.resize(n);

  // Names, local transforms and parent links (each node at most one parent).
  for (std::size_t i = 0; i < n; ++i) {
    const tinygltf::Node& node = model.nodes[i];
    g.names[i] = node.name.empty() ? fmt::format("node {}", i) : node.name;
    const std::string where = fmt::format("{}: node {}", source, i);
    Result<glm::dmat4> local = localTransform(node, where);
    if (!local) return local.error();
    g.local[i] = *local;
    for (int c : node.children) {
      if (c < 0 || static_cast<std::size_t>(c) >= n) {
        return fail("{}: child {} does not exist ({} nodes)", where, c, n);
      }
      if (static_cast<std::size_t>(c) == i) return fail("{}: lists itself as a child", where);
      const auto cu = static_cast<std::size_t>(c);
      if (g.parents[cu] != -1) {
        return fail("{}: node {} has two parents ({} and {})", source, c, g.parents[cu], i);
      }
      g.parents[cu] = static_cast<int>(i);
    }
  }

  // Cycles: walk up from every node; 1 = on the current path, 2 = done.
  std::vector<char> state(n, 0);
  std::vector<int> path;
  for (std::size_t start = 0; start < n; ++start) {
    path.clear();
    int v = static_cast<int>(start);
    while (v != -1 && state[static_cast<std::size_t>(v)] == 0) {
      state[static_cast<std::size_t>(v)] = 1;
      path.push_back(v);
      v = g.parents[static_cast<std::size_t>(v)];
    }
    if (v != -1 && state[static_cast<std::size_t>(v)] == 1) {
      return fail("{}: node graph has a cycle through node {}", source, v);
    }
    // World transforms down the path (its top's parent, if any, is done).
    for (auto it = path.rbegin(); it != path.rend(); ++it) {
      const auto u = static_cast<std::size_t>(*it);
      const int p = g.parents[u];
      g.world[u] = p == -1 ? g.local[u] : g.world[static_cast<std::size_t>(p)] * g.local[u];
      state[u] = 2;
    }
  }
  return g;
}

Result<std::vector<int>> sceneNodeOrder(const tinygltf::Model& model, const GltfNodeGraph& graph,
                                        std::string_view source) {
  const std::size_t n = model.nodes.size();
  std::vector<int> roots;
  int scene = model.defaultScene;
  if (scene < 0 && !model.scenes.empty()) scene = 0;
  if (scene >= 0) {
    if (static_cast<std::size_t>(scene) >= model.scenes.size()) {
      return fail("{}: default scene {} does not exist ({} scenes)", source, scene,
                  model.scenes.size());
    }
    for (int r : model.scenes[static_cast<std::size_t>(scene)].nodes) {
      if (r < 0 || static_cast<std::size_t>(r) >= n) {
        return fail("{}: scene {}: node {} does not exist ({} nodes)", source, scene, r, n);
      }
      roots.push_back(r);
    }
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      if (graph.parents[i] == -1) roots.push_back(static_cast<int>(i));
    }
  }

  // Depth first from the roots (the graph is a checked forest, so this terminates).
  std::vector<int> order;
  std::vector<char> seen(n, 0);
  std::vector<int> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back(*it);
  while (!stack.empty()) {
    const int v = stack.back();
    stack.pop_back();
    if (seen[static_cast<std::size_t>(v)] != 0) continue;
    seen[static_cast<std::size_t>(v)] = 1;
    order.push_back(v);
    const auto& children = model.nodes[static_cast<std::size_t>(v)].children;
    for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back(*it);
  }
  return order;
}

}  // namespace vistel
