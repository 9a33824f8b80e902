// Retargeting through canonical joints with rest-pose correction (see retarget.hpp):
// an aligned reference of the target, then world-rotation deltas of the source.
#include "common/motion/retarget.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <span>
#include <string>

#include "common/math/transform.hpp"

namespace vistel {
namespace {

constexpr int kNone = -1;
constexpr int kChord = -2;  // direction_source_: a chord of the source's torso polyline

// The point at arc fraction t (0..1) of a polyline through joint positions.
template <typename PositionOf>
glm::vec3 polylinePoint(std::span<const int> joints, std::span<const float> fraction, float t,
                        const PositionOf& position) {
  std::size_t k = 0;
  while (k + 2 < joints.size() && fraction[k + 1] < t) ++k;
  const float span = fraction[k + 1] - fraction[k];
  const float u = span > 0.0f ? std::clamp((t - fraction[k]) / span, 0.0f, 1.0f) : 0.0f;
  return glm::mix(position(joints[k]), position(joints[k + 1]), u);
}

// Arc fractions (0..1) of a polyline; empty when it is (nearly) a point.
std::vector<float> arcFractions(const std::vector<glm::vec3>& points) {
  std::vector<float> out(points.size(), 0.0f);
  for (std::size_t k = 1; k < points.size(); ++k) {
    out[k] = out[k - 1] + glm::length(points[k] - points[k - 1]);
  }
  if (points.size() < 2 || out.back() <= 1e-6f) return {};
  for (float& f : out) f /= out.back();
  return out;
}

// Canonical index of a name (a compile-time known name: never -1).
int cj(std::string_view name) {
  const int i = canonicalIndex(name);
  assert(i >= 0);
  return i;
}

// Joint of each canonical index on one skeleton through one map (-1 when absent).
std::vector<int> canonicalToJoint(const Skeleton& skeleton, const JointMap& map) {
  const auto names = canonicalJoints();
  std::vector<int> out(names.size(), kNone);
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::string_view name = map.jointFor(names[c]);
    if (!name.empty()) out[c] = skeleton.find(name);
  }
  return out;
}

bool isDescendant(const Skeleton& s, int joint, int ancestor) {
  for (int j = joint; j != kNoParent; j = s.parents[static_cast<std::size_t>(j)]) {
    if (j == ancestor) return joint != ancestor;
  }
  return false;
}

// World rotations (quaternion chain) and positions of a posture.
void worldPose(const Skeleton& s, const Posture& p, std::vector<glm::quat>& rotations,
               std::vector<glm::vec3>& positions) {
  const std::size_t n = s.names.size();
  std::vector<glm::mat4> model(n);
  poseSkeleton(s, p, model);
  rotations.resize(n);
  positions.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const int parent = s.parents[j];
    rotations[j] =
        parent == kNoParent
            ? p.rotations[j]
            : glm::normalize(rotations[static_cast<std::size_t>(parent)] * p.rotations[j]);
    positions[j] = glm::vec3(model[j][3]);
  }
}

// One skeleton in some pose, seen through its canonical joints.
struct Body {
  const Skeleton* skeleton = nullptr;
  std::vector<int> joint_of;         // (ncanonical) joint or -1
  std::vector<glm::quat> rotations;  // (njoint) world rotations
  std::vector<glm::vec3> positions;  // (njoint) world positions, metres

  glm::vec3 at(int c) const {
    return positions[static_cast<std::size_t>(joint_of[static_cast<std::size_t>(c)])];
  }
  bool has(int c) const { return joint_of[static_cast<std::size_t>(c)] >= 0; }
};

// The body's up axis: hips towards the neck (or the head).
glm::vec3 bodyUp(const Body& b) {
  const int top = b.has(cj("neck")) ? cj("neck") : cj("head");
  const glm::vec3 d = b.at(top) - b.at(cj("hips"));
  const float len = glm::length(d);
  return len > 1e-6f ? d / len : glm::vec3(0.0f, 1.0f, 0.0f);
}

// Hips height over the ankles: the hips-to-thigh drop along the body's up axis plus thigh
// and shin lengths, averaged over both legs (pose-independent but for the drop).
float hipHeight(const Body& b) {
  const glm::vec3 up = bodyUp(b);
  float sum = 0.0f;
  int legs = 0;
  for (std::string_view side : {"l_", "r_"}) {
    const std::string s(side);
    const int thigh = cj(s + "thigh");
    const int shin = cj(s + "shin");
    const int foot = cj(s + "foot");
    if (!b.has(thigh) || !b.has(shin)) continue;
    const float drop = std::max(0.0f, -glm::dot(b.at(thigh) - b.at(cj("hips")), up));
    const float upper = glm::length(b.at(shin) - b.at(thigh));
    const float lower = b.has(foot) ? glm::length(b.at(foot) - b.at(shin)) : upper;
    sum += drop + upper + lower;
    ++legs;
  }
  return legs > 0 ? sum / static_cast<float>(legs) : 1.0f;
}

// Canonical joints whose direction from canonical joint c defines c's bone, best first.
std::vector<int> directionCandidates(int c) {
  const std::string name(canonicalJoints()[static_cast<std::size_t>(c)]);
  std::vector<int> out;
  if (name.ends_with("hand")) {
    const std::string side = name.substr(0, 2);
    for (const char* f : {"middle1", "index1", "ring1", "pinky1"}) out.push_back(cj(side + f));
    return out;
  }
  const auto parents = canonicalParents();
  for (std::size_t k = 0; k < parents.size(); ++k) {
    if (parents[k] == c) out.push_back(static_cast<int>(k));
  }
  if (!out.empty()) {
    // Then the first child's children (a mapped grandchild when the child is unmapped).
    const int first = out.front();
    for (std::size_t k = 0; k < parents.size(); ++k) {
      if (parents[k] == first) out.push_back(static_cast<int>(k));
    }
  }
  return out;
}

bool isTorso(int c) {
  return c == cj("hips") || c == cj("spine") || c == cj("chest") || c == cj("upper_chest");
}

// Rotation taking orthonormal frame (u_from, l_from) onto (u_to, l_to).
glm::quat frameRotation(glm::vec3 u_from, glm::vec3 l_from, glm::vec3 u_to, glm::vec3 l_to) {
  const glm::mat3 from(u_from, l_from, glm::cross(u_from, l_from));
  const glm::mat3 to(u_to, l_to, glm::cross(u_to, l_to));
  return glm::normalize(glm::quat_cast(to * glm::transpose(from)));
}

// Component of v orthogonal to unit u, normalized; false when (nearly) parallel.
bool orthogonalize(glm::vec3 v, glm::vec3 u, glm::vec3& out) {
  const glm::vec3 w = v - glm::dot(v, u) * u;
  const float len = glm::length(w);
  if (len < 1e-3f * std::max(glm::length(v), 1e-9f) || len < 1e-9f) return false;
  out = w / len;
  return true;
}

// Swing taking unit `from` onto unit `to`; a half turn goes about `hint` (projected).
glm::quat swing(glm::vec3 from, glm::vec3 to, glm::vec3 hint, glm::vec3 hint2) {
  if (glm::dot(from, to) > -0.9999f) return rotationBetween(from, to);
  glm::vec3 axis;
  if (!orthogonalize(hint, from, axis) && !orthogonalize(hint2, from, axis)) {
    return rotationBetween(from, to);
  }
  return glm::angleAxis(glm::pi<float>(), axis);
}

}  // namespace

Result<Retargeter> Retargeter::create(const Skeleton& source, const JointMap& source_map,
                                      const Skeleton& target, const JointMap& target_map,
                                      const RetargetOptions& options) {
  if (Status s = validateSkeleton(source); !s) return withContext("retarget source", s.error());
  if (Status s = validateSkeleton(target); !s) return withContext("retarget target", s.error());
  const auto ns = static_cast<std::size_t>(source.jointCount());
  const auto nt = static_cast<std::size_t>(target.jointCount());
  const auto names = canonicalJoints();
  const std::size_t nc = names.size();

  // Canonical joints on both sides; the required ones must exist on both.
  Body src;
  Body tgt;
  src.skeleton = &source;
  tgt.skeleton = &target;
  src.joint_of = canonicalToJoint(source, source_map);
  tgt.joint_of = canonicalToJoint(target, target_map);
  for (std::string_view r : kDefaultRequiredJoints) {
    const auto c = static_cast<std::size_t>(cj(r));
    for (const auto& [body, map, role] :
         {std::tuple{&src, &source_map, "source"}, std::tuple{&tgt, &target_map, "target"}}) {
      if (body->joint_of[c] >= 0) continue;
      const std::string_view joint = map->jointFor(r);
      if (joint.empty()) {
        return fail("retarget: the {} map '{}' does not name required joint '{}'", role, map->name,
                    r);
      }
      return fail("retarget: the {} skeleton has no joint '{}' (canonical '{}' in map '{}')", role,
                  joint, r, map->name);
    }
  }
  std::vector<bool> paired(nc);
  for (std::size_t c = 0; c < nc; ++c) paired[c] = src.joint_of[c] >= 0 && tgt.joint_of[c] >= 0;

  // Source reference pose (world), target rest pose (world).
  const Posture reference =
      options.source_reference ? *options.source_reference : restPosture(source);
  if (reference.rotations.size() != ns ||
      (!reference.translations.empty() && reference.translations.size() != ns)) {
    return fail(
        "retarget: the source reference posture has {} rotations and {} translations "
        "for {} source joints",
        reference.rotations.size(), reference.translations.size(), ns);
  }
  worldPose(source, reference, src.rotations, src.positions);
  worldPose(target, restPosture(target), tgt.rotations, tgt.positions);

  Retargeter r;
  r.source_ = source;
  r.target_parents_ = target.parents;
  r.target_rest_rotation_.resize(nt);
  for (std::size_t j = 0; j < nt; ++j) r.target_rest_rotation_[j] = target.rest_local[j].rotation;
  r.source_of_target_.assign(nt, kNone);
  r.offset_.assign(nt, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  r.direction_source_.assign(nt, kNone);
  r.direction_rest_.assign(nt, glm::vec3(0.0f));
  r.chord_.assign(nt, glm::vec2(0.0f));
  std::vector<int> canonical_of_target(nt, kNone);
  for (std::size_t c = 0; c < nc; ++c) {
    if (!paired[c]) continue;
    const auto t = static_cast<std::size_t>(tgt.joint_of[c]);
    r.source_of_target_[t] = src.joint_of[c];
    canonical_of_target[t] = static_cast<int>(c);
  }

  // Body axes of the source reference, for half-turn swings.
  const int hips = cj("hips");
  const glm::vec3 src_up = bodyUp(src);
  glm::vec3 src_left(1.0f, 0.0f, 0.0f);
  if (!orthogonalize(src.at(cj("l_thigh")) - src.at(cj("r_thigh")), src_up, src_left)) {
    src_left = glm::vec3(1.0f, 0.0f, 0.0f);
  }
  const glm::vec3 src_forward = glm::cross(src_left, src_up);
  const float scale_hint = std::max(hipHeight(src), 1e-6f);
  const float target_height = std::max(hipHeight(tgt), 1e-6f);

  // Aligned reference of the target (world rotations), parents first.
  std::vector<glm::quat> aligned(nt);
  for (std::size_t j = 0; j < nt; ++j) {
    const int parent = target.parents[j];
    aligned[j] = parent == kNoParent ? tgt.rotations[j]
                                     : glm::normalize(aligned[static_cast<std::size_t>(parent)] *
                                                      target.rest_local[j].rotation);
    const int c = canonical_of_target[j];
    if (c == kNone) continue;
    const auto sj = src.joint_of[static_cast<std::size_t>(c)];
    // The target's rest offsets below j, carried rigidly by j's aligned rotation.
    const glm::quat carry = aligned[j] * glm::inverse(tgt.rotations[j]);
    const auto target_vector = [&](int from_c, int to_c) {
      return carry * (tgt.at(to_c) - tgt.at(from_c));
    };
    const auto source_vector = [&](int from_c, int to_c) { return src.at(to_c) - src.at(from_c); };
    // A canonical joint usable as a direction from c: paired, below c on both sides, and
    // not (nearly) at c's position on either.
    const auto usable = [&](int d) {
      const auto du = static_cast<std::size_t>(d);
      if (!paired[du]) return false;
      if (!isDescendant(source, src.joint_of[du], sj) ||
          !isDescendant(target, tgt.joint_of[du], static_cast<int>(j))) {
        return false;
      }
      return glm::length(source_vector(c, d)) > 1e-3f * scale_hint &&
             glm::length(tgt.at(d) - tgt.at(c)) > 1e-3f * target_height;
    };

    glm::quat correction(1.0f, 0.0f, 0.0f, 0.0f);
    if (isTorso(c)) {
      // Hips and spine: whole frame, up towards the neck (or what is mapped above), left-right
      // across (thighs for the hips, shoulders for the spine).
      int up = kNone;
      for (const char* name : {"neck", "head", "upper_chest", "chest", "spine"}) {
        if (cj(name) > c && usable(cj(name))) {
          up = cj(name);
          break;
        }
      }
      if (up == kNone) continue;
      const glm::vec3 ut = glm::normalize(target_vector(c, up));
      const glm::vec3 us = glm::normalize(source_vector(c, up));
      bool have_lateral = false;
      glm::vec3 lt, ls;
      const auto sides =
          c == hips ? std::array<const char*, 4>{"thigh", "shin", "foot", "toes"}
                    : std::array<const char*, 4>{"clavicle", "upperarm", "forearm", "hand"};
      for (const char* part : sides) {
        const int l = cj(std::string("l_") + part);
        const int rr = cj(std::string("r_") + part);
        if (!usable(l) || !usable(rr)) continue;
        if (orthogonalize(target_vector(rr, l), ut, lt) &&
            orthogonalize(source_vector(rr, l), us, ls)) {
          have_lateral = true;
          break;
        }
      }
      if (c == hips || c == cj("spine")) {
        correction =
            have_lateral ? frameRotation(ut, lt, us, ls) : swing(ut, us, src_forward, src_left);
      } else if (glm::vec3 ls_plane; have_lateral && orthogonalize(ls, ut, ls_plane)) {
        // Higher up the spine only the twist about the bone towards the neck is matched,
        // so each spine keeps its own curvature and the neck stays where the spine put it.
        const float angle =
            std::atan2(glm::dot(glm::cross(lt, ls_plane), ut), glm::dot(lt, ls_plane));
        correction = glm::angleAxis(angle, ut);
      }
    } else {
      // Swing the bone towards the next mapped joint down the chain.
      for (int d : directionCandidates(c)) {
        if (!usable(d)) continue;
        const glm::vec3 dt = glm::normalize(target_vector(c, d));
        const glm::vec3 ds = glm::normalize(source_vector(c, d));
        correction = swing(dt, ds, src_forward, src_left);
        break;
      }
    }
    aligned[j] = glm::normalize(correction * aligned[j]);

    // The bone followed per posture: towards the next mapped joint down the chain.
    if (c != hips) {
      std::vector<int> next = directionCandidates(c);
      if (isTorso(c)) {
        next.clear();
        for (const char* name : {"chest", "upper_chest", "neck", "head"}) {
          if (cj(name) > c) next.push_back(cj(name));
        }
      }
      for (int d : next) {
        if (!usable(d)) continue;
        r.direction_source_[j] = src.joint_of[static_cast<std::size_t>(d)];
        r.direction_rest_[j] = glm::normalize(
            glm::inverse(src.rotations[static_cast<std::size_t>(sj)]) * source_vector(c, d));
        break;
      }
    }
  }

  // Torso joints follow chords of the source's spine polyline (spine to neck) taken at
  // their own arc fractions along the target's spine, so that differently divided spines
  // bend alike (the chord from spine to neck is the same on both).
  const int end = paired[static_cast<std::size_t>(cj("neck"))] ? cj("neck") : cj("head");
  std::vector<int> chain;  // canonical joints of the target's spine chain, paired
  for (int c = cj("spine"); c < end; ++c) {
    if (paired[static_cast<std::size_t>(c)]) chain.push_back(c);
  }
  chain.push_back(end);
  std::vector<glm::vec3> source_points, target_points;
  for (int c = cj("spine"); c <= end; ++c) {
    if (!src.has(c)) continue;
    const int sj = src.joint_of[static_cast<std::size_t>(c)];
    if (!r.torso_source_.empty() && !isDescendant(source, sj, r.torso_source_.back())) break;
    r.torso_source_.push_back(sj);
    source_points.push_back(src.at(c));
  }
  for (int c : chain) target_points.push_back(tgt.at(c));
  r.torso_fraction_ = arcFractions(source_points);
  const std::vector<float> target_fraction = arcFractions(target_points);
  if (r.torso_fraction_.empty() || target_fraction.empty() ||
      src.joint_of[static_cast<std::size_t>(end)] != r.torso_source_.back()) {
    r.torso_source_.clear();
    r.torso_fraction_.clear();
  } else {
    const auto reference_point = [&](float t) {
      return polylinePoint(r.torso_source_, r.torso_fraction_, t,
                           [&](int sj) { return src.positions[static_cast<std::size_t>(sj)]; });
    };
    for (std::size_t k = 0; k + 1 < chain.size(); ++k) {
      const auto c = static_cast<std::size_t>(chain[k]);
      const auto j = static_cast<std::size_t>(tgt.joint_of[c]);
      const glm::vec2 chord(target_fraction[k], target_fraction[k + 1]);
      const glm::vec3 v = reference_point(chord.y) - reference_point(chord.x);
      if (glm::length(v) < 1e-3f * scale_hint) continue;
      r.direction_source_[j] = kChord;
      r.chord_[j] = chord;
      r.direction_rest_[j] = glm::normalize(
          glm::inverse(src.rotations[static_cast<std::size_t>(src.joint_of[c])]) * v);
    }
  }

  for (std::size_t j = 0; j < nt; ++j) {
    const int s = r.source_of_target_[j];
    if (s == kNone) continue;
    r.offset_[j] =
        glm::normalize(glm::inverse(src.rotations[static_cast<std::size_t>(s)]) * aligned[j]);
  }

  // Hips: nothing above the target hips may be mapped (it keeps its rest pose there).
  r.source_hips_ = src.joint_of[static_cast<std::size_t>(hips)];
  r.target_hips_ = tgt.joint_of[static_cast<std::size_t>(hips)];
  for (int j = target.parents[static_cast<std::size_t>(r.target_hips_)]; j != kNoParent;
       j = target.parents[static_cast<std::size_t>(j)]) {
    if (r.source_of_target_[static_cast<std::size_t>(j)] != kNone) {
      return fail("retarget: target joint '{}' (above the hips '{}') is mapped",
                  target.names[static_cast<std::size_t>(j)],
                  target.names[static_cast<std::size_t>(r.target_hips_)]);
    }
  }
  r.source_reference_hips_ = src.positions[static_cast<std::size_t>(r.source_hips_)];
  r.target_rest_hips_ = tgt.positions[static_cast<std::size_t>(r.target_hips_)];
  r.root_to_hips_ = r.target_rest_hips_ - tgt.positions[0];
  r.translation_scale_ = target_height / scale_hint;
  // Planted ankles: the target's at rest over its floor, the source's as given or scaled.
  float target_floor = std::numeric_limits<float>::max();
  if (options.target_floor) {
    target_floor = *options.target_floor;
  } else {
    for (const glm::vec3& p : tgt.positions) target_floor = std::min(target_floor, p.y);
  }
  float target_ankle = std::numeric_limits<float>::max();
  for (const char* foot : {"l_foot", "r_foot"}) {
    if (tgt.has(cj(foot))) target_ankle = std::min(target_ankle, tgt.at(cj(foot)).y);
  }
  if (target_ankle == std::numeric_limits<float>::max()) target_ankle = target_floor;
  const float target_ankle_height = target_ankle - target_floor;
  r.target_ground_ = target_ankle;
  r.source_ground_ = options.source_floor + options.source_ankle_height.value_or(
                                                target_ankle_height / r.translation_scale_);

  r.scratch_source_model_.resize(ns);
  r.scratch_source_world_.resize(ns);
  r.scratch_target_world_.resize(nt);
  return r;
}

Result<Retargeter> Retargeter::forClip(const MotionClip& clip, const JointMap& clip_map,
                                       const Skeleton& target, const JointMap& target_map,
                                       RetargetOptions options) {
  const Skeleton skeleton = clipSkeleton(clip);
  if (!options.source_reference && clip.frame_count > 0) {
    Posture reference;
    clipReferencePosture(clip, clip_map, reference);
    options.source_reference = std::move(reference);
  }
  // The clip's planted ankle: its lowest ankle over all frames.
  const int feet[] = {skeleton.find(clip_map.jointFor("l_foot")),
                      skeleton.find(clip_map.jointFor("r_foot"))};
  if (!options.source_ankle_height && clip.frame_count > 0 && feet[0] >= 0 && feet[1] >= 0) {
    Posture p;
    std::vector<glm::mat4> model(skeleton.names.size());
    float lowest = std::numeric_limits<float>::max();
    for (int k = 0; k < clip.frame_count; ++k) {
      samplePosture(clip, k, p);
      poseSkeleton(skeleton, p, model);
      for (int f : feet) lowest = std::min(lowest, model[static_cast<std::size_t>(f)][3].y);
    }
    options.source_ankle_height = lowest - options.source_floor;
  }
  return create(skeleton, clip_map, target, target_map, options);
}

void Retargeter::apply(const Posture& source, Posture& out) const {
  const std::size_t ns = source_.names.size();
  const std::size_t nt = target_parents_.size();
  assert(source.rotations.size() == ns);

  // Source world rotations and the hips' position.
  poseSkeleton(source_, source, scratch_source_model_);
  for (std::size_t j = 0; j < ns; ++j) {
    const int parent = source_.parents[j];
    scratch_source_world_[j] =
        parent == kNoParent
            ? source.rotations[j]
            : scratch_source_world_[static_cast<std::size_t>(parent)] * source.rotations[j];
  }

  // Target world rotations, then local ones.
  out.rotations.resize(nt);
  out.translations.clear();
  for (std::size_t j = 0; j < nt; ++j) {
    const int parent = target_parents_[j];
    const int s = source_of_target_[j];
    glm::quat world;
    if (s != kNone) {
      const glm::quat& source_world = scratch_source_world_[static_cast<std::size_t>(s)];
      world = source_world * offset_[j];
      // Bends of unmapped source joints along the bone (e.g. a lower neck between the
      // chest and the neck) turn the bone too: swing it onto the source's direction.
      const int d = direction_source_[j];
      if (d != kNone) {
        const auto position = [&](int joint) {
          return glm::vec3(scratch_source_model_[static_cast<std::size_t>(joint)][3]);
        };
        const glm::vec3 from = source_world * direction_rest_[j];
        const glm::vec3 to =
            d == kChord ? polylinePoint(torso_source_, torso_fraction_, chord_[j].y, position) -
                              polylinePoint(torso_source_, torso_fraction_, chord_[j].x, position)
                        : position(d) - position(s);
        const float length = glm::length(to);
        if (length > 0.0f) world = rotationBetween(glm::normalize(from), to / length) * world;
      }
    } else if (parent == kNoParent) {
      world = target_rest_rotation_[j];
    } else {
      world = scratch_target_world_[static_cast<std::size_t>(parent)] * target_rest_rotation_[j];
    }
    world = glm::normalize(world);
    scratch_target_world_[j] = world;
    out.rotations[j] =
        parent == kNoParent
            ? world
            : glm::normalize(glm::inverse(scratch_target_world_[static_cast<std::size_t>(parent)]) *
                             world);
  }

  // Hips: displacement across the floor, height above it, scaled.
  const glm::vec3 hips(scratch_source_model_[static_cast<std::size_t>(source_hips_)][3]);
  const float k = translation_scale_;
  const glm::vec3 target_hips(target_rest_hips_.x + k * (hips.x - source_reference_hips_.x),
                              target_ground_ + k * (hips.y - source_ground_),
                              target_rest_hips_.z + k * (hips.z - source_reference_hips_.z));
  out.root_translation = target_hips - root_to_hips_;
  out.time = source.time;
}

void clipReferencePosture(const MotionClip& clip, const JointMap& clip_map, Posture& out) {
  const Skeleton skeleton = clipSkeleton(clip);
  Body body;
  body.skeleton = &skeleton;
  body.joint_of = canonicalToJoint(skeleton, clip_map);
  const Posture rest = restPosture(skeleton);
  worldPose(skeleton, rest, body.rotations, body.positions);

  // Natural: torso up along +Y, legs down along -Y.
  bool natural = true;
  const glm::vec3 y(0.0f, 1.0f, 0.0f);
  if (body.has(cj("hips")) && (body.has(cj("neck")) || body.has(cj("head")))) {
    natural = glm::dot(bodyUp(body), y) >= std::cos(glm::radians(30.0f));
  }
  for (std::string_view side : {"l_", "r_"}) {
    const std::string s(side);
    const int thigh = cj(s + "thigh");
    const int end = body.has(cj(s + "foot")) ? cj(s + "foot") : cj(s + "shin");
    if (!body.has(thigh) || !body.has(end)) continue;
    const glm::vec3 leg = body.at(end) - body.at(thigh);
    const float len = glm::length(leg);
    if (len > 0.0f && glm::dot(leg / len, -y) < std::cos(glm::radians(45.0f))) natural = false;
  }
  if (natural || clip.frame_count == 0) {
    out = rest;
    return;
  }
  samplePosture(clip, 0, out);
}

}  // namespace vistel
