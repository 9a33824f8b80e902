#include "offline/gltf/gltf_import.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <unordered_set>

#include <fmt/ranges.h>
#include <glm/gtc/quaternion.hpp>

#include "common/base/file.hpp"
#include "offline/gltf/gltf_accessor.hpp"
#include "offline/gltf/gltf_load.hpp"
#include "offline/gltf/gltf_look.hpp"
#include "offline/gltf/gltf_nodes.hpp"
#include "offline/gltf/gltf_vrm.hpp"
#include "offline/gltf/skin_trimesh.hpp"

namespace vistel {
namespace {

// How many joints' bind transforms are tried as the common mesh -> model transform.
constexpr std::size_t kBindCandidates = 32;

// One joint's share of a vertex (joint = index into the skin's joint list).
struct Influence {
  int joint = 0;
  double weight = 0.0;
};

// The merged skinned primitives as the file has them (mesh space, before the bind
// transform is applied).
struct RawMesh {
  std::vector<glm::dvec3> positions;               // (nvert)
  std::vector<glm::dvec3> normals;                 // (nvert), zero where the file has none
  std::vector<std::uint32_t> indices;              // (3 * ntri)
  std::vector<std::vector<Influence>> influences;  // non-zero influences per vertex (nvert)
  std::vector<glm::vec2> uvs;                      // TEXCOORD_0 (nvert), zero where none
  int vertices_without_uvs = 0;                    // in primitives that have no TEXCOORD_0
  std::vector<GltfPrimitiveRun> runs;              // triangles per primitive, in index order
  int negative_weights = 0;
};

// A rigid frame (rotation then translation), double precision.
struct Rigid {
  glm::dvec3 t{0.0};
  glm::dquat r{1.0, 0.0, 0.0, 0.0};
};

std::string nameOf(const GltfNodeGraph& graph, int node) {
  return graph.names[static_cast<std::size_t>(node)];
}

double maxAbs(const glm::dmat4& m) {
  double best = 0.0;
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) best = std::max(best, std::abs(m[c][r]));
  }
  return best;
}

bool closeMatrices(const glm::dmat4& a, const glm::dmat4& b, double tolerance) {
  const double limit = tolerance * (1.0 + maxAbs(b));
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) {
      if (std::abs(a[c][r] - b[c][r]) > limit) return false;
    }
  }
  return true;
}

// The rigid part of an affine matrix: translation, and the rotation of its
// Gram-Schmidt-orthonormalised axes (a mirroring is dropped by flipping x).
Rigid rigidPart(const glm::dmat4& m) {
  glm::dvec3 x(m[0]), y(m[1]), z(m[2]);
  if (glm::dot(glm::cross(x, y), z) < 0.0) x = -x;
  x = glm::normalize(x);
  y = glm::normalize(y - glm::dot(y, x) * x);
  z = glm::cross(x, y);
  Rigid out;
  out.t = glm::dvec3(m[3]);
  out.r = glm::normalize(glm::quat_cast(glm::dmat3(x, y, z)));
  return out;
}

// Makes names unique by appending "_2", "_3", ...
void uniquify(std::vector<std::string>& names, std::vector<std::string>& warnings,
              std::string_view source) {
  std::unordered_set<std::string> seen;
  for (std::string& name : names) {
    if (seen.insert(name).second) continue;
    std::string candidate;
    for (int i = 2;; ++i) {
      candidate = fmt::format("{}_{}", name, i);
      if (!seen.count(candidate)) break;
    }
    warnings.push_back(fmt::format("{}: joint name '{}' appears more than once; renamed to '{}'",
                                   source, name, candidate));
    name = candidate;
    seen.insert(name);
  }
}

class Importer {
 public:
  Importer(const tinygltf::Model& model, std::string_view source, const GltfImportOptions& options,
           GltfImportReport& report)
      : model_(model), source_(source), options_(options), report_(report) {}

  Result<AvatarModel> run();

 private:
  Status pickSkin();
  Status readSkin();
  Status readPrimitive(int mesh, int primitive,
                       std::map<std::map<std::string, int>, std::pair<std::uint32_t, int>>& bases);
  Status readInfluences(const tinygltf::Primitive& prim, const std::string& where,
                        std::size_t first, int count);
  void resolveBind();
  void buildSkeleton(Skeleton& skeleton);
  Status buildSkin(SkinMesh& skin, const Skeleton& skeleton);
  void finishWithOpenMesh(SkinMesh& skin);
  void applyVrm(AvatarModel& avatar);
  void warn(std::string text) { report_.warnings.push_back(fmt::format("{}: {}", source_, text)); }

  const tinygltf::Model& model_;
  std::string source_;
  const GltfImportOptions& options_;
  GltfImportReport& report_;

  GltfNodeGraph graph_;
  int mesh_node_ = -1;
  int skin_index_ = -1;
  std::vector<int> skin_nodes_;          // node of each skin joint (nskin)
  std::vector<int> skin_joint_of_node_;  // skin joint index per node, or -1 (nnode)
  std::vector<glm::dmat4> ibm_;          // inverse bind matrix per skin joint (nskin)
  RawMesh raw_;
  glm::dmat4 bind_{1.0};                // mesh space -> model space in the bind posture
  std::vector<glm::dmat4> bind_world_;  // joint world transform in the bind (nskin)
  std::vector<int> skeleton_of_skin_;   // skeleton joint per skin joint (nskin)
  std::vector<Rigid> joint_model_;      // rigid model frame per skeleton joint (njoint)
  bool flipped_ = false;                // bind transform mirrors: winding reversed
  VrmHumanoid vrm_;                     // the VRM humanoid (empty version: not a VRM)
};

// Rotates a whole avatar half a turn about +Y (model space): vertices, normals and the
// root joint's rest frame; the other joints' frames are relative and stay.
void turnAvatarAround(AvatarModel& avatar) {
  const glm::quat half(0.0f, 0.0f, 1.0f, 0.0f);  // w, x, y, z: 180 degrees about +Y
  for (glm::vec3& p : avatar.skin.positions) p = glm::vec3(-p.x, p.y, -p.z);
  for (glm::vec3& n : avatar.skin.normals) n = glm::vec3(-n.x, n.y, -n.z);
  Transform& root = avatar.skeleton.rest_local[0];
  root.translation = glm::vec3(-root.translation.x, root.translation.y, -root.translation.z);
  root.rotation = glm::quat(canonical(glm::normalize(half * root.rotation)));
  computeInverseBind(avatar.skeleton);
}

// The VRM humanoid as a joint map (canonical <- imported joint name); with
// vrm_canonical_names the joints are renamed to their canonical names (a joint outside
// the humanoid that already has such a name gets a "_vrm" suffix). VRM 0.x models face
// -Z: they are turned to face +Z like every vistel avatar.
void Importer::applyVrm(AvatarModel& avatar) {
  report_.vrm_version = vrm_.version;
  Skeleton& skeleton = avatar.skeleton;
  JointMap map;
  map.name = "vrm-humanoid";
  map.source = source_;
  map.required.assign(std::begin(kDefaultRequiredJoints), std::end(kDefaultRequiredJoints));
  std::vector<int> joints;
  for (const auto& [canonical, node] : vrm_.bones) {
    const int k = skin_joint_of_node_[static_cast<std::size_t>(node)];
    if (k < 0) {
      warn(fmt::format("VRM bone {} is node {} ('{}'), which is not a joint of skin {}; left out",
                       canonical, node, nameOf(graph_, node), skin_index_));
      continue;
    }
    const int j = skeleton_of_skin_[static_cast<std::size_t>(k)];
    map.canonical.push_back(canonical);
    map.joint.push_back(skeleton.names[static_cast<std::size_t>(j)]);
    joints.push_back(j);
  }
  if (!vrm_.ignored.empty()) {
    warn(fmt::format("VRM bones with no vistel joint, left to the skin: {}",
                     fmt::join(vrm_.ignored, ", ")));
  }
  if (options_.vrm_canonical_names) {
    std::vector<bool> mapped(skeleton.names.size(), false);
    for (int j : joints) mapped[static_cast<std::size_t>(j)] = true;
    for (std::size_t j = 0; j < skeleton.names.size(); ++j) {
      if (!mapped[j] && canonicalIndex(skeleton.names[j]) >= 0) skeleton.names[j] += "_vrm";
    }
    for (std::size_t e = 0; e < joints.size(); ++e) {
      skeleton.names[static_cast<std::size_t>(joints[e])] = map.canonical[e];
      map.joint[e] = map.canonical[e];
    }
    uniquify(skeleton.names, report_.warnings, source_);
  }
  report_.humanoid = std::move(map);
  if (vrm_.version == "0.x") turnAvatarAround(avatar);
}

// Picks the first node (scene order, then node order) with both a mesh and a skin.
Status Importer::pickSkin() {
  Result<std::vector<int>> order = sceneNodeOrder(model_, graph_, source_);
  if (!order) return order.error();
  for (std::size_t i = 0; i < model_.nodes.size(); ++i) order->push_back(static_cast<int>(i));
  for (int v : *order) {
    const tinygltf::Node& node = model_.nodes[static_cast<std::size_t>(v)];
    if (node.mesh >= 0 && node.skin >= 0) {
      mesh_node_ = v;
      break;
    }
  }
  if (mesh_node_ < 0)
    return fail("{}: no skinned mesh (no node has both a mesh and a skin)", source_);
  const tinygltf::Node& node = model_.nodes[static_cast<std::size_t>(mesh_node_)];
  if (static_cast<std::size_t>(node.mesh) >= model_.meshes.size()) {
    return fail("{}: node {}: mesh {} does not exist ({} meshes)", source_, mesh_node_, node.mesh,
                model_.meshes.size());
  }
  if (static_cast<std::size_t>(node.skin) >= model_.skins.size()) {
    return fail("{}: node {}: skin {} does not exist ({} skins)", source_, mesh_node_, node.skin,
                model_.skins.size());
  }
  skin_index_ = node.skin;
  report_.skin = skin_index_;
  report_.mesh_node = nameOf(graph_, mesh_node_);
  if (model_.skins.size() > 1) {
    warn(fmt::format("{} skins; importing skin {} (used by node '{}')", model_.skins.size(),
                     skin_index_, report_.mesh_node));
  }
  return {};
}

// Joint nodes (in range, each once) and inverse bind matrices (identity when absent).
Status Importer::readSkin() {
  const tinygltf::Skin& skin = model_.skins[static_cast<std::size_t>(skin_index_)];
  const std::string where = fmt::format("{}: skin {}", source_, skin_index_);
  if (skin.joints.empty()) return fail("{}: has no joints", where);
  if (skin.joints.size() >= 65535)
    return fail("{}: {} joints (at most 65534)", where, skin.joints.size());
  skin_joint_of_node_.assign(model_.nodes.size(), -1);
  for (std::size_t k = 0; k < skin.joints.size(); ++k) {
    const int node = skin.joints[k];
    if (node < 0 || static_cast<std::size_t>(node) >= model_.nodes.size()) {
      return fail("{}: joint {} refers to node {} of {}", where, k, node, model_.nodes.size());
    }
    if (skin_joint_of_node_[static_cast<std::size_t>(node)] != -1) {
      return fail("{}: node {} is listed twice as a joint", where, node);
    }
    skin_joint_of_node_[static_cast<std::size_t>(node)] = static_cast<int>(k);
    skin_nodes_.push_back(node);
  }
  ibm_.assign(skin.joints.size(), glm::dmat4(1.0));
  if (skin.inverseBindMatrices < 0) return {};
  Result<AccessorData> data =
      readAccessor(model_, skin.inverseBindMatrices, source_, {"MAT4", {kGltfFloat}});
  if (!data) return data.error();
  if (static_cast<std::size_t>(data->count) < skin.joints.size()) {
    return fail("{}: {} inverse bind matrices for {} joints", where, data->count,
                skin.joints.size());
  }
  for (std::size_t k = 0; k < skin.joints.size(); ++k) {
    glm::dmat4 m;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r)
        m[c][r] = data->values[k * 16 + static_cast<std::size_t>(c * 4 + r)];
    }
    if (std::abs(m[0][3]) > 1e-4 || std::abs(m[1][3]) > 1e-4 || std::abs(m[2][3]) > 1e-4 ||
        std::abs(m[3][3] - 1.0) > 1e-4) {
      return fail("{}: inverse bind matrix of joint {} ('{}') is not affine", where, k,
                  nameOf(graph_, skin_nodes_[k]));
    }
    m[0][3] = m[1][3] = m[2][3] = 0.0;
    m[3][3] = 1.0;
    if (!(std::abs(glm::determinant(glm::dmat3(m))) > 1e-18)) {
      return fail("{}: inverse bind matrix of joint {} ('{}') is singular", where, k,
                  nameOf(graph_, skin_nodes_[k]));
    }
    ibm_[k] = m;
  }
  return {};
}

// JOINTS_n / WEIGHTS_n of one primitive into raw_.influences[first .. first + count).
Status Importer::readInfluences(const tinygltf::Primitive& prim, const std::string& where,
                                std::size_t first, int count) {
  const std::size_t njoint = skin_nodes_.size();
  for (int set = 0;; ++set) {
    const auto joints_it = prim.attributes.find(fmt::format("JOINTS_{}", set));
    const auto weights_it = prim.attributes.find(fmt::format("WEIGHTS_{}", set));
    if (joints_it == prim.attributes.end() && weights_it == prim.attributes.end()) {
      if (set == 0) {
        return fail("{}: has no JOINTS_0/WEIGHTS_0 but node {} skins it with skin {}", where,
                    mesh_node_, skin_index_);
      }
      return {};
    }
    if (joints_it == prim.attributes.end() || weights_it == prim.attributes.end()) {
      return fail("{}: JOINTS_{} and WEIGHTS_{} must come together", where, set, set);
    }
    Result<AccessorData> joints = readAccessor(model_, joints_it->second, source_,
                                               {"VEC4", {kGltfUnsignedByte, kGltfUnsignedShort}});
    if (!joints) return joints.error();
    Result<AccessorData> weights =
        readAccessor(model_, weights_it->second, source_,
                     {"VEC4", {kGltfFloat, -kGltfUnsignedByte, -kGltfUnsignedShort}});
    if (!weights) return weights.error();
    if (joints->count != count || weights->count != count) {
      return fail("{}: JOINTS_{} has {} and WEIGHTS_{} {} elements for {} vertices", where, set,
                  joints->count, set, weights->count, count);
    }
    for (std::size_t v = 0; v < static_cast<std::size_t>(count); ++v) {
      for (std::size_t s = 0; s < 4; ++s) {
        double w = weights->values[v * 4 + s];
        const double j = joints->values[v * 4 + s];
        if (w < 0.0) {
          ++raw_.negative_weights;
          w = 0.0;
        }
        if (w == 0.0) continue;
        if (j >= static_cast<double>(njoint)) {
          return fail(
              "{}: accessor {} (JOINTS_{}): vertex {} uses joint index {}, but skin {} has {} "
              "joints",
              source_, joints_it->second, set, v, j, skin_index_, njoint);
        }
        raw_.influences[first + v].push_back({static_cast<int>(j), w});
      }
    }
  }
}

// One primitive's vertices (unless an earlier primitive had the very same attributes)
// and triangles.
Status Importer::readPrimitive(
    int mesh, int primitive,
    std::map<std::map<std::string, int>, std::pair<std::uint32_t, int>>& bases) {
  const tinygltf::Primitive& prim =
      model_.meshes[static_cast<std::size_t>(mesh)].primitives[static_cast<std::size_t>(primitive)];
  const std::string where = fmt::format("{}: mesh {} primitive {}", source_, mesh, primitive);
  if (prim.mode != TINYGLTF_MODE_TRIANGLES) {
    return fail("{}: mode {} is not supported (only TRIANGLES, mode 4)", where, prim.mode);
  }
  const auto pos_it = prim.attributes.find("POSITION");
  if (pos_it == prim.attributes.end()) return fail("{}: has no POSITION", where);

  // Vertices: positions, normals, influences.
  std::uint32_t base = 0;
  int count = 0;
  if (auto known = bases.find(prim.attributes); known != bases.end()) {
    base = known->second.first;
    count = known->second.second;
  } else {
    Result<AccessorData> pos =
        readAccessor(model_, pos_it->second, source_, {"VEC3", {kGltfFloat}});
    if (!pos) return pos.error();
    count = pos->count;
    if (raw_.positions.size() + static_cast<std::size_t>(count) > (std::size_t{1} << 31)) {
      return fail("{}: too many vertices", where);
    }
    base = static_cast<std::uint32_t>(raw_.positions.size());
    const std::size_t first = raw_.positions.size();
    raw_.positions.resize(first + static_cast<std::size_t>(count));
    raw_.normals.resize(first + static_cast<std::size_t>(count), glm::dvec3(0.0));
    raw_.influences.resize(first + static_cast<std::size_t>(count));
    for (std::size_t v = 0; v < static_cast<std::size_t>(count); ++v) {
      raw_.positions[first + v] =
          glm::dvec3(pos->values[3 * v], pos->values[3 * v + 1], pos->values[3 * v + 2]);
    }
    if (auto nrm_it = prim.attributes.find("NORMAL"); nrm_it != prim.attributes.end()) {
      Result<AccessorData> nrm =
          readAccessor(model_, nrm_it->second, source_, {"VEC3", {kGltfFloat}});
      if (!nrm) return nrm.error();
      if (nrm->count != count) {
        return fail("{}: NORMAL has {} elements for {} vertices", where, nrm->count, count);
      }
      for (std::size_t v = 0; v < static_cast<std::size_t>(count); ++v) {
        raw_.normals[first + v] =
            glm::dvec3(nrm->values[3 * v], nrm->values[3 * v + 1], nrm->values[3 * v + 2]);
      }
    }
    if (Status s = readInfluences(prim, where, first, count); !s) return s;
    raw_.uvs.resize(first + static_cast<std::size_t>(count), glm::vec2(0.0f));
    if (auto uv_it = prim.attributes.find("TEXCOORD_0"); uv_it != prim.attributes.end()) {
      Result<AccessorData> uv =
          readAccessor(model_, uv_it->second, source_,
                       {"VEC2", {kGltfFloat, -kGltfUnsignedByte, -kGltfUnsignedShort}});
      if (!uv) return uv.error();
      if (uv->count != count) {
        return fail("{}: TEXCOORD_0 has {} elements for {} vertices", where, uv->count, count);
      }
      for (std::size_t v = 0; v < static_cast<std::size_t>(count); ++v) {
        raw_.uvs[first + v] = glm::vec2(static_cast<float>(uv->values[2 * v]),
                                        static_cast<float>(uv->values[2 * v + 1]));
      }
    } else {
      raw_.vertices_without_uvs += count;
    }
    bases.emplace(prim.attributes, std::make_pair(base, count));
  }

  // Triangles (indices in range, or consecutive vertices when there are none).
  const std::size_t first_index = raw_.indices.size();
  if (prim.indices >= 0) {
    Result<AccessorData> idx =
        readAccessor(model_, prim.indices, source_,
                     {"SCALAR", {kGltfUnsignedByte, kGltfUnsignedShort, kGltfUnsignedInt}});
    if (!idx) return idx.error();
    if (idx->count % 3 != 0) {
      return fail("{}: accessor {}: {} indices is not a multiple of 3", source_, prim.indices,
                  idx->count);
    }
    for (std::size_t i = 0; i < idx->values.size(); ++i) {
      const double v = idx->values[i];
      if (v >= static_cast<double>(count)) {
        return fail("{}: accessor {}: index {} at position {} exceeds the primitive's {} vertices",
                    source_, prim.indices, v, i, count);
      }
      raw_.indices.push_back(base + static_cast<std::uint32_t>(v));
    }
  } else {
    if (count % 3 != 0) {
      return fail("{}: {} vertices without indices is not a multiple of 3", where, count);
    }
    for (int v = 0; v < count; ++v) raw_.indices.push_back(base + static_cast<std::uint32_t>(v));
  }
  if (raw_.indices.size() > first_index) {
    raw_.runs.push_back({static_cast<std::uint32_t>(first_index),
                         static_cast<std::uint32_t>(raw_.indices.size() - first_index),
                         prim.material});
  }
  ++report_.primitives;
  return {};
}

// The bind posture. Each joint's world * IBM is the mesh-space -> model-space transform
// it implies; normally all agree. The transform that most joints, and more than half of
// them, agree on is used, else the mesh node's world transform (which also wins ties);
// disagreeing joints are placed by their IBMs.
void Importer::resolveBind() {
  const std::size_t n = skin_nodes_.size();
  std::vector<glm::dmat4> implied(n);
  for (std::size_t k = 0; k < n; ++k) {
    implied[k] = graph_.world[static_cast<std::size_t>(skin_nodes_[k])] * ibm_[k];
  }
  const double tol = options_.bind_tolerance;
  auto agreeing = [&](const glm::dmat4& candidate) {
    std::size_t count = 0;
    for (const glm::dmat4& m : implied) count += closeMatrices(m, candidate, tol) ? 1 : 0;
    return count;
  };
  bind_ = graph_.world[static_cast<std::size_t>(mesh_node_)];
  std::size_t best = agreeing(bind_);
  // (At most kBindCandidates joints' transforms are tried: O(n) whatever the skin size.)
  for (std::size_t k = 0; k < std::min(n, kBindCandidates) && best < n; ++k) {
    const std::size_t c = agreeing(implied[k]);
    if (c > best && 2 * c > n) {
      best = c;
      bind_ = implied[k];
    }
  }
  bind_world_.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const bool agrees = closeMatrices(implied[k], bind_, tol);
    bind_world_[k] = agrees ? graph_.world[static_cast<std::size_t>(skin_nodes_[k])]
                            : bind_ * glm::inverse(ibm_[k]);
  }
  if (best < n) {
    report_.rest_from_inverse_bind = true;
    warn(fmt::format(
        "{} of {} joints' rest transforms disagree with their inverse bind matrices; the rest "
        "posture is taken from the inverse bind matrices (the bind posture)",
        n - best, n));
  }
  flipped_ = glm::determinant(glm::dmat3(bind_)) < 0.0;
}

// Joints parents first (skin order kept where it allows), rigid model frames, rest
// transforms relative to the parent, inverse bind matrices.
void Importer::buildSkeleton(Skeleton& skeleton) {
  const std::size_t n = skin_nodes_.size();

  // Skeleton parent of each skin joint: the joint of its nearest ancestor node that is
  // one (memoised per node, so long chains of non-joint nodes cost O(nodes) in all).
  std::vector<int> joint_above(graph_.parents.size(), -2);  // -2 unknown, -1 none
  std::vector<int> path;
  auto jointAbove = [&](int node) {
    path.clear();
    int p = graph_.parents[static_cast<std::size_t>(node)];
    while (p != -1 && skin_joint_of_node_[static_cast<std::size_t>(p)] == -1 &&
           joint_above[static_cast<std::size_t>(p)] == -2) {
      path.push_back(p);
      p = graph_.parents[static_cast<std::size_t>(p)];
    }
    const int found = p == -1 ? -1
                      : skin_joint_of_node_[static_cast<std::size_t>(p)] != -1
                          ? skin_joint_of_node_[static_cast<std::size_t>(p)]
                          : joint_above[static_cast<std::size_t>(p)];
    for (int q : path) joint_above[static_cast<std::size_t>(q)] = found;
    return found;
  };
  std::vector<int> skin_parent(n, -1);
  int roots = 0;
  for (std::size_t k = 0; k < n; ++k) {
    skin_parent[k] = jointAbove(skin_nodes_[k]);
    roots += skin_parent[k] == -1 ? 1 : 0;
  }

  // Order: a synthetic root when there are several roots, then each joint after its
  // ancestors.
  std::vector<int> order;  // skin joint per skeleton joint (-1: synthetic root)
  if (roots > 1) {
    order.push_back(-1);
    report_.synthetic_root = true;
    warn(fmt::format("skin {} has {} root joints; added a root joint at the origin", skin_index_,
                     roots));
  }
  skeleton_of_skin_.assign(n, -1);
  std::vector<int> chain;
  for (std::size_t k = 0; k < n; ++k) {
    chain.clear();
    for (int j = static_cast<int>(k);
         j != -1 && skeleton_of_skin_[static_cast<std::size_t>(j)] == -1;
         j = skin_parent[static_cast<std::size_t>(j)]) {
      chain.push_back(j);
    }
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      skeleton_of_skin_[static_cast<std::size_t>(*it)] = static_cast<int>(order.size());
      order.push_back(*it);
    }
  }

  // Names, parents and rigid frames.
  const std::size_t count = order.size();
  skeleton.names.resize(count);
  skeleton.parents.resize(count);
  joint_model_.resize(count);
  for (std::size_t j = 0; j < count; ++j) {
    const int k = order[j];
    if (k < 0) {
      skeleton.names[j] = "root";
      skeleton.parents[j] = kNoParent;
      joint_model_[j] = Rigid{};
      continue;
    }
    skeleton.names[j] = nameOf(graph_, skin_nodes_[static_cast<std::size_t>(k)]);
    const int sp = skin_parent[static_cast<std::size_t>(k)];
    skeleton.parents[j] =
        sp >= 0 ? skeleton_of_skin_[static_cast<std::size_t>(sp)] : (roots > 1 ? 0 : kNoParent);
    joint_model_[j] = rigidPart(bind_world_[static_cast<std::size_t>(k)]);
  }
  uniquify(skeleton.names, report_.warnings, source_);

  // Rest transforms relative to the parent (rigid), then the inverse bind matrices.
  skeleton.rest_local.resize(count);
  for (std::size_t j = 0; j < count; ++j) {
    const Rigid& f = joint_model_[j];
    Rigid local = f;
    if (skeleton.parents[j] != kNoParent) {
      const Rigid& p = joint_model_[static_cast<std::size_t>(skeleton.parents[j])];
      const glm::dquat inv = glm::conjugate(p.r);
      local.t = inv * (f.t - p.t);
      local.r = glm::normalize(inv * f.r);
    }
    Transform& t = skeleton.rest_local[j];
    t.translation = glm::vec3(local.t);
    t.rotation = glm::quat(canonical(glm::quat(local.r)));
    t.scale = glm::vec3(1.0f);
  }
  computeInverseBind(skeleton);
}

// Positions and normals into model space, triangles, weights per skeleton joint.
Status Importer::buildSkin(SkinMesh& skin, const Skeleton& skeleton) {
  const std::size_t nvert = raw_.positions.size();
  const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(glm::dmat3(bind_)));

  // Positions and file normals (zero where missing or unusable).
  skin.positions.resize(nvert);
  skin.normals.assign(nvert, glm::vec3(0.0f));
  std::size_t missing_normals = 0;
  for (std::size_t v = 0; v < nvert; ++v) {
    skin.positions[v] = glm::vec3(glm::dvec3(bind_ * glm::dvec4(raw_.positions[v], 1.0)));
    const glm::dvec3 nrm = normal_matrix * raw_.normals[v];
    const double len = glm::length(nrm);
    if (len > 1e-12 && !options_.recompute_normals) {
      skin.normals[v] = glm::vec3(nrm / len);
    } else {
      ++missing_normals;
    }
  }
  if (missing_normals > 0) {
    std::vector<glm::vec3> computed(nvert);
    skin.indices = raw_.indices;  // for the computation below (winding fixed later)
    if (flipped_) {
      for (std::size_t t = 0; t + 2 < skin.indices.size(); t += 3)
        std::swap(skin.indices[t + 1], skin.indices[t + 2]);
    }
    computeVertexNormals(skin.positions, skin.indices, computed);
    for (std::size_t v = 0; v < nvert; ++v) {
      if (skin.normals[v] == glm::vec3(0.0f)) skin.normals[v] = computed[v];
    }
    report_.normals_computed = true;
    if (missing_normals < nvert) {
      warn(fmt::format("{} of {} vertices had no usable normal; computed from the triangles",
                       missing_normals, nvert));
    }
  }

  // Triangles, keeping them counter-clockwise when the bind transform mirrors.
  skin.indices = raw_.indices;
  if (flipped_) {
    for (std::size_t t = 0; t + 2 < skin.indices.size(); t += 3)
      std::swap(skin.indices[t + 1], skin.indices[t + 2]);
    warn("the bind transform mirrors the mesh; triangle winding reversed");
  }

  // Fallback joint for unweighted vertices: the mesh node's own joint (it or an ancestor).
  int node_joint = -1;
  for (int p = mesh_node_; p != -1; p = graph_.parents[static_cast<std::size_t>(p)]) {
    if (skin_joint_of_node_[static_cast<std::size_t>(p)] != -1) {
      node_joint = skeleton_of_skin_[static_cast<std::size_t>(
          skin_joint_of_node_[static_cast<std::size_t>(p)])];
      break;
    }
  }

  // Influences per vertex: merged per joint, strongest first, at most kMaxInfluences.
  std::vector<std::vector<std::pair<int, double>>> per_vertex(nvert);
  int used_max = 1;
  int truncated = 0;
  for (std::size_t v = 0; v < nvert; ++v) {
    auto& list = per_vertex[v];
    for (const Influence& in : raw_.influences[v]) {
      const int j = skeleton_of_skin_[static_cast<std::size_t>(in.joint)];
      auto it = std::find_if(list.begin(), list.end(), [j](const auto& e) { return e.first == j; });
      if (it == list.end()) {
        list.emplace_back(j, in.weight);
      } else {
        it->second += in.weight;
      }
    }
    std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    if (list.size() > static_cast<std::size_t>(kMaxInfluences)) {
      list.resize(kMaxInfluences);
      ++truncated;
    }
    if (list.empty()) {
      int j = node_joint;
      if (j < 0) {  // nearest joint origin
        double best = 0.0;
        for (std::size_t i = 0; i < joint_model_.size(); ++i) {
          if (skeleton.names.size() > 1 && i == 0 && report_.synthetic_root) continue;
          const double d = glm::distance(glm::dvec3(skin.positions[v]), joint_model_[i].t);
          if (j < 0 || d < best) {
            best = d;
            j = static_cast<int>(i);
          }
        }
      }
      list.emplace_back(j, 1.0);
      ++report_.unweighted_vertices;
    }
    used_max = std::max(used_max, static_cast<int>(list.size()));
  }
  if (truncated > 0) {
    warn(fmt::format("{} vertices had more than {} influences; the weakest were dropped", truncated,
                     kMaxInfluences));
  }
  if (raw_.negative_weights > 0) {
    warn(fmt::format("{} negative weights were set to 0", raw_.negative_weights));
  }
  if (report_.unweighted_vertices > 0) {
    warn(fmt::format("{} vertices have zero total weight; bound to {}", report_.unweighted_vertices,
                     node_joint >= 0
                         ? fmt::format("the mesh node's joint '{}'",
                                       skeleton.names[static_cast<std::size_t>(node_joint)])
                         : std::string("their nearest joint")));
  }

  // Flat slots, normalised (in float, so that each vertex sums to 1 to rounding).
  const int k = used_max <= 4 ? 4 : kMaxInfluences;
  skin.influences = k;
  skin.joints.assign(nvert * static_cast<std::size_t>(k), 0);
  skin.weights.assign(nvert * static_cast<std::size_t>(k), 0.0f);
  for (std::size_t v = 0; v < nvert; ++v) {
    const auto& list = per_vertex[v];
    double total = 0.0;
    for (const auto& e : list) total += e.second;
    float sum = 0.0f;
    for (std::size_t s = 0; s < list.size(); ++s) {
      const std::size_t slot = v * static_cast<std::size_t>(k) + s;
      skin.joints[slot] = static_cast<std::uint16_t>(list[s].first);
      skin.weights[slot] = static_cast<float>(list[s].second / total);
      sum += skin.weights[slot];
    }
    float& strongest = skin.weights[v * static_cast<std::size_t>(k)];  // absorbs the rounding
    strongest = std::min(1.0f, strongest + (1.0f - sum));
  }
  return {};
}

// The skin through OpenMesh: topology checks (as warnings), then flattened back.
void Importer::finishWithOpenMesh(SkinMesh& skin) {
  SkinTriMesh mesh;
  const SkinTopology topo = buildSkinTriMesh(skin, mesh);
  report_.boundary_edges = topo.boundary_edges;
  report_.non_manifold_vertices = topo.non_manifold_vertices;
  report_.rejected_triangles = topo.rejected_triangles;
  if (topo.boundary_edges > 0) {
    warn(fmt::format("skin has {} boundary edges (holes or seams)", topo.boundary_edges));
  }
  if (topo.non_manifold_vertices > 0) {
    warn(fmt::format("skin has {} non-manifold vertices", topo.non_manifold_vertices));
  }
  if (topo.rejected_triangles > 0) {
    warn(fmt::format(
        "{} triangles make complex (non-manifold) edges; kept, but OpenMesh refused them",
        topo.rejected_triangles));
  }
  if (topo.degenerate_triangles > 0) {
    warn(fmt::format("{} degenerate triangles (a repeated vertex)", topo.degenerate_triangles));
  }
  if (topo.isolated_vertices > 0) {
    warn(fmt::format("{} vertices are used by no triangle", topo.isolated_vertices));
  }
  flattenSkinTriMesh(mesh, skin);
}

Result<AvatarModel> Importer::run() {
  Result<GltfNodeGraph> graph = buildNodeGraph(model_, source_);
  if (!graph) return graph.error();
  graph_ = std::move(*graph);
  if (Status s = pickSkin(); !s) return s.error();
  if (Status s = readSkin(); !s) return s.error();
  Result<VrmHumanoid> vrm = readVrmHumanoid(model_, source_);
  if (!vrm) return vrm.error();
  vrm_ = std::move(*vrm);

  // Every primitive of every mesh node that uses the skin (the picked node first).
  std::vector<int> nodes{mesh_node_};
  for (std::size_t i = 0; i < model_.nodes.size(); ++i) {
    const tinygltf::Node& node = model_.nodes[i];
    if (static_cast<int>(i) != mesh_node_ && node.skin == skin_index_ && node.mesh >= 0) {
      if (static_cast<std::size_t>(node.mesh) >= model_.meshes.size()) {
        return fail("{}: node {}: mesh {} does not exist ({} meshes)", source_, i, node.mesh,
                    model_.meshes.size());
      }
      nodes.push_back(static_cast<int>(i));
    }
  }
  std::map<std::map<std::string, int>, std::pair<std::uint32_t, int>> bases;
  std::unordered_set<int> meshes_done;
  for (int node : nodes) {
    const int mesh = model_.nodes[static_cast<std::size_t>(node)].mesh;
    if (!meshes_done.insert(mesh).second) continue;
    const auto& prims = model_.meshes[static_cast<std::size_t>(mesh)].primitives;
    for (std::size_t p = 0; p < prims.size(); ++p) {
      if (Status s = readPrimitive(mesh, static_cast<int>(p), bases); !s) return s.error();
    }
  }
  if (raw_.positions.empty() || raw_.indices.empty()) {
    return fail("{}: the skinned mesh has no triangles", source_);
  }

  resolveBind();
  AvatarModel avatar;
  avatar.name = std::filesystem::path(source_).stem().string();
  if (avatar.name.empty()) avatar.name = "avatar";
  buildSkeleton(avatar.skeleton);
  if (Status s = buildSkin(avatar.skin, avatar.skeleton); !s) return s.error();
  finishWithOpenMesh(avatar.skin);
  if (!vrm_.version.empty()) applyVrm(avatar);
  // The look: texture coordinates, materials and their textures.
  if (raw_.vertices_without_uvs == static_cast<int>(raw_.uvs.size())) raw_.uvs.clear();
  if (!raw_.uvs.empty() && raw_.vertices_without_uvs > 0) {
    warn(fmt::format("{} of {} vertices have no TEXCOORD_0; they sample the texture at (0, 0)",
                     raw_.vertices_without_uvs, raw_.uvs.size()));
  }
  Result<AvatarLook> look =
      importGltfLook(model_, source_, raw_.runs, std::move(raw_.uvs), options_, report_.warnings);
  if (!look) return look.error();
  avatar.look = std::move(*look);
  report_.materials = static_cast<int>(avatar.look.materials.size());
  report_.textures = static_cast<int>(avatar.look.textures.size());
  if (Status s = validateAvatar(avatar); !s) return withContext(source_, s.error());
  if (options_.max_avatar_bytes > 0) {
    const std::size_t allowance = implicitModelAllowance(avatar.skin.positions.size());
    const std::size_t target = options_.max_avatar_bytes > 2 * allowance
                                   ? options_.max_avatar_bytes - allowance
                                   : options_.max_avatar_bytes;
    Result<int> fitted = fitAvatarTextures(avatar, target, report_.warnings);
    if (!fitted) return withContext(source_, fitted.error());
    report_.textures_downscaled = *fitted;
  }
  return avatar;
}

}  // namespace

Result<AvatarModel> importGltfAvatarFromMemory(std::span<const std::uint8_t> bytes,
                                               std::string_view source_name,
                                               const std::string& base_dir,
                                               const GltfImportOptions& options,
                                               GltfImportReport* report) {
  GltfImportReport local;
  GltfImportReport& out = report != nullptr ? *report : local;
  out = GltfImportReport{};
  try {
    Result<tinygltf::Model> model =
        loadGltfModel(bytes, source_name, base_dir, options.max_file_bytes, out.warnings);
    if (!model) return model.error();
    Importer importer(*model, source_name, options, out);
    return importer.run();
  } catch (const std::bad_alloc&) {
    return fail("{}: out of memory while importing", source_name);
  } catch (const std::exception& e) {
    return fail("{}: import failed: {}", source_name, e.what());
  }
}

Result<AvatarModel> importGltfAvatar(const std::string& path, const GltfImportOptions& options,
                                     GltfImportReport* report) {
  Result<std::vector<std::uint8_t>> bytes = readFileBytes(path, options.max_file_bytes);
  if (!bytes) return bytes.error();
  const std::filesystem::path p(path);
  return importGltfAvatarFromMemory(*bytes, path, p.parent_path().string(), options, report);
}

}  // namespace vistel
