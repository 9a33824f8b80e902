// BVH export: clip text, and clips built from postures (Euler ZXY channels).
#include <algorithm>
#include <cassert>
#include <cmath>
#include <iterator>

#include <fmt/format.h>
#include <glm/gtc/quaternion.hpp>

#include "common/motion/bvh.hpp"

namespace vistel {
namespace {

std::string_view channelName(BvhChannel c) {
  switch (c) {
    case BvhChannel::kXposition:
      return "Xposition";
    case BvhChannel::kYposition:
      return "Yposition";
    case BvhChannel::kZposition:
      return "Zposition";
    case BvhChannel::kXrotation:
      return "Xrotation";
    case BvhChannel::kYrotation:
      return "Yrotation";
    case BvhChannel::kZrotation:
      return "Zrotation";
  }
  return "?";
}

// Children of every joint, in index order.
std::vector<std::vector<int>> childLists(std::span<const int> parents) {
  std::vector<std::vector<int>> children(parents.size());
  for (std::size_t j = 1; j < parents.size(); ++j) {
    children[static_cast<std::size_t>(parents[j])].push_back(static_cast<int>(j));
  }
  return children;
}

// Depth-first (pre-order) joint order from joint 0.
std::vector<int> depthFirst(const std::vector<std::vector<int>>& children) {
  std::vector<int> order;
  if (children.empty()) return order;
  order.reserve(children.size());
  std::vector<int> stack{0};
  while (!stack.empty()) {
    const int j = stack.back();
    stack.pop_back();
    order.push_back(j);
    const auto& c = children[static_cast<std::size_t>(j)];
    for (auto it = c.rbegin(); it != c.rend(); ++it) stack.push_back(*it);
  }
  return order;
}

void appendVector(std::string& out, const glm::vec3& v) {
  fmt::format_to(std::back_inserter(out), "{} {} {}", v.x, v.y, v.z);
}

// Z, X, Y angles (degrees) with R = Rz(z) * Rx(x) * Ry(y).
glm::vec3 eulerZXY(const glm::quat& q) {
  const glm::dmat3 m = glm::mat3_cast(glm::dquat(glm::normalize(q)));
  // m[column][row]; with R = Rz Rx Ry: R21 = sin x, R01 = -sin z cos x, R11 = cos z cos x,
  // R20 = -cos x sin y, R22 = cos x cos y.
  const double sx = std::clamp(m[1][2], -1.0, 1.0);
  const double x = std::asin(sx);
  double z = 0.0;
  double y = 0.0;
  if (std::abs(sx) < 0.999999) {
    z = std::atan2(-m[1][0], m[1][1]);
    y = std::atan2(-m[0][2], m[2][2]);
  } else {
    // Gimbal lock: only z + y (or z - y) is defined; put it all in z.
    z = std::atan2(m[0][1], m[0][0]);
  }
  return glm::vec3(static_cast<float>(glm::degrees(z)), static_cast<float>(glm::degrees(x)),
                   static_cast<float>(glm::degrees(y)));
}

}  // namespace

std::string writeBvh(const MotionClip& clip) {
  std::string out;
  const std::size_t n = clip.joints.size();
  out.reserve(64 * n + clip.values.size() * 10 + 64);
  std::vector<int> parents(n);
  for (std::size_t j = 0; j < n; ++j) parents[j] = clip.joints[j].parent;
  const std::vector<std::vector<int>> children = childLists(parents);
  const std::vector<int> order = depthFirst(children);

  // Hierarchy: walk depth first, closing braces when going back up.
  out += "HIERARCHY\n";
  std::vector<int> open;  // joints whose block is open, innermost last
  const auto close_until = [&](int parent) {
    while (!open.empty() && open.back() != parent) {
      const BvhJoint& joint = clip.joints[static_cast<std::size_t>(open.back())];
      const std::string indent(open.size(), '\t');
      if (joint.end_site) {
        out += indent + "End Site\n" + indent + "{\n" + indent + "\tOFFSET ";
        appendVector(out, *joint.end_site);
        out += "\n" + indent + "}\n";
      }
      out += std::string(open.size() - 1, '\t') + "}\n";
      open.pop_back();
    }
  };
  for (int j : order) {
    const BvhJoint& joint = clip.joints[static_cast<std::size_t>(j)];
    close_until(joint.parent);
    const std::string indent(open.size(), '\t');
    out += indent + (joint.parent == kNoParent ? "ROOT " : "JOINT ") + joint.name + "\n";
    out += indent + "{\n" + indent + "\tOFFSET ";
    appendVector(out, joint.offset);
    out += "\n" + indent + fmt::format("\tCHANNELS {}", joint.channels.size());
    for (BvhChannel c : joint.channels) {
      out += ' ';
      out += channelName(c);
    }
    out += '\n';
    open.push_back(j);
  }
  close_until(kNoParent);

  // Motion: each frame's values, joint by joint in the written order.
  fmt::format_to(std::back_inserter(out), "MOTION\nFrames: {}\nFrame Time: {}\n", clip.frame_count,
                 clip.frame_time);
  for (int k = 0; k < clip.frame_count; ++k) {
    const std::span<const float> values = clip.frame(k);
    bool first = true;
    for (int j : order) {
      const BvhJoint& joint = clip.joints[static_cast<std::size_t>(j)];
      for (std::size_t c = 0; c < joint.channels.size(); ++c) {
        if (!first) out += ' ';
        first = false;
        fmt::format_to(std::back_inserter(out), "{}",
                       values[static_cast<std::size_t>(joint.first_channel) + c]);
      }
    }
    out += '\n';
  }
  return out;
}

MotionClip clipFromPostures(const Skeleton& skeleton, std::span<const Posture> postures,
                            double frame_time, float unit_scale, std::string source_name) {
  assert(frame_time > 0.0 && unit_scale > 0.0f);
  const std::size_t n = skeleton.names.size();
  const std::vector<std::vector<int>> children = childLists(skeleton.parents);
  const std::vector<int> order = depthFirst(children);
  std::vector<int> new_index(n, kNoParent);
  for (std::size_t i = 0; i < order.size(); ++i) {
    new_index[static_cast<std::size_t>(order[i])] = static_cast<int>(i);
  }
  bool translated = false;
  for (const Posture& p : postures) translated = translated || !p.translations.empty();

  // Hierarchy in depth-first order.
  MotionClip clip;
  clip.source = std::move(source_name);
  clip.unit_scale = unit_scale;
  clip.frame_time = frame_time;
  clip.frame_count = static_cast<int>(postures.size());
  constexpr BvhChannel kPositions[] = {BvhChannel::kXposition, BvhChannel::kYposition,
                                       BvhChannel::kZposition};
  constexpr BvhChannel kRotations[] = {BvhChannel::kZrotation, BvhChannel::kXrotation,
                                       BvhChannel::kYrotation};
  for (int old : order) {
    const auto o = static_cast<std::size_t>(old);
    BvhJoint joint;
    joint.name = skeleton.names[o];
    joint.parent = skeleton.parents[o] == kNoParent
                       ? kNoParent
                       : new_index[static_cast<std::size_t>(skeleton.parents[o])];
    joint.offset = skeleton.rest_local[o].translation / unit_scale;
    if (joint.parent == kNoParent || translated) {
      joint.channels.insert(joint.channels.end(), std::begin(kPositions), std::end(kPositions));
    }
    joint.channels.insert(joint.channels.end(), std::begin(kRotations), std::end(kRotations));
    joint.first_channel = clip.channel_count;
    clip.channel_count += static_cast<int>(joint.channels.size());
    if (children[o].empty()) joint.end_site = joint.offset * 0.5f;
    clip.joints.push_back(std::move(joint));
  }

  // Frames.
  clip.values.reserve(postures.size() * static_cast<std::size_t>(clip.channel_count));
  for (const Posture& p : postures) {
    assert(p.rotations.size() == n);
    for (int old : order) {
      const auto o = static_cast<std::size_t>(old);
      if (old == 0 || translated) {
        glm::vec3 t = skeleton.rest_local[o].translation;
        if (old == 0) {
          t = p.root_translation;
        } else if (!p.translations.empty()) {
          t = p.translations[o];
        }
        t /= unit_scale;
        clip.values.insert(clip.values.end(), {t.x, t.y, t.z});
      }
      const glm::vec3 zxy = eulerZXY(p.rotations[o]);
      clip.values.insert(clip.values.end(), {zxy.x, zxy.y, zxy.z});
    }
  }
  return clip;
}

}  // namespace vistel
