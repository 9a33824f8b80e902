#include "offline/parts/avatar_cut.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string_view>

#include <fmt/format.h>

namespace vistel {
namespace {

// The segments, and the canonical joints that belong to each (fingers and toes follow
// their hand and foot by ancestry).
struct SegmentDef {
  std::string_view name;
  std::string_view first;   // the canonical joint the segment starts at
  std::string_view parent;  // the segment it hangs from ("" for the torso)
};
constexpr std::array<SegmentDef, 14> kSegments = {{
    {"torso", "hips", ""},
    {"head", "neck", "torso"},
    {"l_upperarm", "l_upperarm", "torso"},
    {"l_forearm", "l_forearm", "l_upperarm"},
    {"l_hand", "l_hand", "l_forearm"},
    {"r_upperarm", "r_upperarm", "torso"},
    {"r_forearm", "r_forearm", "r_upperarm"},
    {"r_hand", "r_hand", "r_forearm"},
    {"l_thigh", "l_thigh", "torso"},
    {"l_shin", "l_shin", "l_thigh"},
    {"l_foot", "l_foot", "l_shin"},
    {"r_thigh", "r_thigh", "torso"},
    {"r_shin", "r_shin", "r_thigh"},
    {"r_foot", "r_foot", "r_shin"},
}};

int segmentIndex(std::string_view name) {
  for (std::size_t s = 0; s < kSegments.size(); ++s) {
    if (kSegments[s].name == name) return static_cast<int>(s);
  }
  return -1;
}

// The segment of each skeleton joint: a joint that starts a segment (through the map)
// starts it; any other joint takes its parent's; the root's is the torso.
std::vector<int> jointSegments(const Skeleton& skeleton, const JointMap& map) {
  const int nj = skeleton.jointCount();
  std::vector<int> starts(static_cast<std::size_t>(nj), -1);
  for (std::size_t s = 0; s < kSegments.size(); ++s) {
    const std::string_view name = map.jointFor(kSegments[s].first);
    if (name.empty()) continue;
    const int j = skeleton.find(std::string(name));
    if (j >= 0) starts[static_cast<std::size_t>(j)] = static_cast<int>(s);
  }
  std::vector<int> segment(static_cast<std::size_t>(nj), 0);
  for (int j = 0; j < nj; ++j) {  // parents precede children
    const int own = starts[static_cast<std::size_t>(j)];
    const int parent = skeleton.parents[static_cast<std::size_t>(j)];
    segment[static_cast<std::size_t>(j)] =
        own >= 0 ? own : (parent >= 0 ? segment[static_cast<std::size_t>(parent)] : 0);
  }
  return segment;
}

}  // namespace

Result<AvatarCut> cutAvatar(const AvatarModel& avatar, const JointMap& map, float band_m) {
  if (!(band_m > 0.0f && band_m <= 0.5f)) return fail("band {} m outside (0, 0.5]", band_m);
  if (Status st = validateAvatar(avatar); !st) return st.error();
  const Skeleton& skeleton = avatar.skeleton;
  const SkinMesh& skin = avatar.skin;
  for (std::string_view needed : {"hips", "head"}) {
    const std::string_view name = map.jointFor(needed);
    if (name.empty() || skeleton.find(std::string(name)) < 0) {
      return fail("the joint map names no '{}' joint in this skeleton", needed);
    }
  }
  const std::vector<int> joint_segment = jointSegments(skeleton, map);
  const std::size_t nv = skin.positions.size();
  const std::size_t nt = skin.indices.size() / 3;
  const auto k = static_cast<std::size_t>(skin.influences);

  // Each vertex's segment: the one carrying most of its weight.
  std::vector<int> vertex_segment(nv, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    std::array<float, kSegments.size()> weight{};
    for (std::size_t s = 0; s < k; ++s) {
      const float w = skin.weights[v * k + s];
      if (w > 0.0f) weight[static_cast<std::size_t>(joint_segment[skin.joints[v * k + s]])] += w;
    }
    vertex_segment[v] =
        static_cast<int>(std::max_element(weight.begin(), weight.end()) - weight.begin());
  }
  // Each triangle's: the segment of most of its corners (the first corner's on a tie).
  std::vector<int> triangle_segment(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const int a = vertex_segment[skin.indices[3 * t]];
    const int b = vertex_segment[skin.indices[3 * t + 1]];
    const int c = vertex_segment[skin.indices[3 * t + 2]];
    triangle_segment[t] = (b == c && b != a) ? b : a;
  }

  // Seams and bands, joint by joint.
  AvatarCut cut;
  std::vector<char> removed(nt, 0);
  const float half = 0.5f * band_m;
  for (std::size_t s = 1; s < kSegments.size(); ++s) {
    const int child = static_cast<int>(s);
    const int parent = segmentIndex(kSegments[s].parent);
    // Seam vertices: an edge joins the two segments.
    std::vector<char> on_seam(nv, 0);
    for (std::size_t t = 0; t < nt; ++t) {
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = skin.indices[3 * t + e];
        const std::uint32_t b = skin.indices[3 * t + (e + 1) % 3];
        const int sa = vertex_segment[a], sb = vertex_segment[b];
        if ((sa == child && sb == parent) || (sa == parent && sb == child)) {
          on_seam[a] = 1;
          on_seam[b] = 1;
        }
      }
    }
    std::vector<glm::vec3> seam;
    for (std::size_t v = 0; v < nv; ++v) {
      if (on_seam[v] != 0) seam.push_back(skin.positions[v]);
    }
    if (seam.empty()) continue;
    // Vertices of either segment within half the band of the seam.
    std::vector<char> in_band(nv, 0);
    for (std::size_t v = 0; v < nv; ++v) {
      if (vertex_segment[v] != child && vertex_segment[v] != parent) continue;
      float nearest = std::numeric_limits<float>::max();
      for (const glm::vec3& q : seam)
        nearest = std::min(nearest, glm::distance(skin.positions[v], q));
      in_band[v] = nearest < half ? 1 : 0;
    }
    CutJoint joint;
    joint.canonical = std::string(kSegments[s].first);
    joint.joint = std::string(map.jointFor(kSegments[s].first));
    joint.parent_segment = std::string(kSegments[static_cast<std::size_t>(parent)].name);
    joint.child_segment = std::string(kSegments[s].name);
    const int j = skeleton.find(joint.joint);
    if (j >= 0) {
      joint.position =
          glm::vec3(glm::inverse(skeleton.inverse_bind[static_cast<std::size_t>(j)])[3]);
    }
    joint.seam_vertices = static_cast<int>(seam.size());
    for (std::size_t t = 0; t < nt; ++t) {
      if (removed[t] != 0) continue;
      if (in_band[skin.indices[3 * t]] || in_band[skin.indices[3 * t + 1]] ||
          in_band[skin.indices[3 * t + 2]]) {
        removed[t] = 1;
        ++joint.removed_triangles;
      }
    }
    cut.removed_triangles += joint.removed_triangles;
    cut.joints.push_back(std::move(joint));
  }

  // What remains of each segment.
  const bool with_uvs = avatar.look.uvs.size() == nv;
  for (std::size_t s = 0; s < kSegments.size(); ++s) {
    CutPart part;
    part.segment = std::string(kSegments[s].name);
    part.bone = std::string(map.jointFor(kSegments[s].first));
    std::vector<std::uint32_t> local(nv, UINT32_MAX);
    for (std::size_t t = 0; t < nt; ++t) {
      if (removed[t] != 0 || triangle_segment[t] != static_cast<int>(s)) continue;
      for (int c = 0; c < 3; ++c) {
        const std::uint32_t v = skin.indices[3 * t + c];
        if (local[v] == UINT32_MAX) {
          local[v] = static_cast<std::uint32_t>(part.mesh.positions.size());
          part.mesh.positions.push_back(skin.positions[v]);
          part.source_index.push_back(v);
          if (with_uvs) part.uvs.push_back(avatar.look.uvs[v]);
        }
        part.mesh.indices.push_back(local[v]);
      }
    }
    if (!part.mesh.indices.empty()) cut.parts.push_back(std::move(part));
  }
  if (cut.parts.empty()) return fail("no triangle is left after removing {} m bands", band_m);
  return cut;
}

namespace {

// A TOML basic string: quotes and backslashes escaped, control characters as \uXXXX.
std::string tomlString(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      out += fmt::format("\\u{:04X}", u);
    } else {
      out += c;
    }
  }
  return out + "\"";
}

}  // namespace

std::string partsToml(const AvatarCut& cut, const std::string& source, float band_m,
                      const std::string& extension) {
  std::string out = fmt::format(
      "# Parts of an avatar cut by vistel-avatar cut: a band removed at each joint.\n"
      "source = {}\nband_m = {:.6g}\n",
      tomlString(source), band_m);
  for (const CutPart& p : cut.parts) {
    out += fmt::format(
        "\n[[part]]\nfile = {}\nsegment = {}\nbone = {}\nvertices = {}\ntriangles = {}\n",
        tomlString(p.segment + "." + extension), tomlString(p.segment), tomlString(p.bone),
        p.mesh.positions.size(), p.mesh.indices.size() / 3);
  }
  for (const CutJoint& j : cut.joints) {
    out += fmt::format(
        "\n[[joint]]\nname = {}\nbone = {}\nbetween = [{}, {}]\n"
        "position = [{:.6g}, {:.6g}, {:.6g}]\nblend_radius_m = {:.6g}\n",
        tomlString(j.canonical), tomlString(j.joint), tomlString(j.parent_segment),
        tomlString(j.child_segment), j.position.x, j.position.y, j.position.z, 0.5f * band_m);
  }
  return out;
}

}  // namespace vistel
