// The default avatar's proportions. Every length below is given for a 1.75 m adult and
// scaled by height / 1.75 m; trunk and limb radii are scaled by the girth option too.
// Left-side parts are laid out once and mirrored (x -> -x) for the right side.
#include "offline/synth/body_plan.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace vistel::synth {
namespace {

constexpr float kReferenceHeight = 1.75f;
// Trunk and limb radii below are multiplied by this and the girth option (an average
// adult build: about 0.068 m^3 at 1.75 m).
constexpr float kBuild = 1.04f;
constexpr glm::vec3 kForward{0.0f, 0.0f, 1.0f};

float radians(float degrees) { return degrees * std::numbers::pi_v<float> / 180.0f; }

// Rotation model -> local whose local +Y is `axis` and local +X lies along `hint`
// (made orthogonal to the axis).
glm::mat3 frameAlong(const glm::vec3& axis, const glm::vec3& hint) {
  const glm::vec3 y = glm::normalize(axis);
  glm::vec3 x = hint - glm::dot(hint, y) * y;
  if (glm::length(x) < 1e-6f) x = std::abs(y.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  x = glm::normalize(x - glm::dot(x, y) * y);
  const glm::vec3 z = glm::cross(x, y);
  return glm::transpose(glm::mat3(x, y, z));
}

// The hand's own axes: along the fingers, towards the thumb, towards the palm side.
struct HandFrame {
  glm::vec3 wrist;
  glm::vec3 u, w, n;
  glm::vec3 at(float along, float thumbward, float palmward) const {
    return wrist + along * u + thumbward * w + palmward * n;
  }
};

// One finger's layout in the hand frame: knuckle (MCP) position, spread angle in units of
// the spread option, segment lengths (the last to the skin tip) and radii at the knuckle,
// the two inner joints and the tip.
struct FingerLayout {
  const char* name;
  float base_along, base_thumbward;
  float spread_units;
  std::array<float, 3> lengths;
  std::array<float, 4> radii;
};

// clang-format off
constexpr std::array<FingerLayout, 4> kFingers{{
    {"index",  0.097f,  0.033f,  1.5f, {0.046f, 0.027f, 0.024f}, {0.0088f, 0.0081f, 0.0073f, 0.0064f}},
    {"middle", 0.100f,  0.011f,  0.5f, {0.050f, 0.031f, 0.025f}, {0.0091f, 0.0084f, 0.0076f, 0.0066f}},
    {"ring",   0.096f, -0.011f, -0.5f, {0.047f, 0.029f, 0.024f}, {0.0085f, 0.0079f, 0.0071f, 0.0062f}},
    {"pinky",  0.088f, -0.032f, -1.5f, {0.037f, 0.022f, 0.021f}, {0.0076f, 0.0070f, 0.0063f, 0.0055f}},
}};
// clang-format on

// Cumulative flexion of the finger segments towards the palm (a relaxed hand), degrees.
constexpr std::array<float, 3> kFingerFlexDeg{5.0f, 13.0f, 18.0f};

class Builder {
 public:
  explicit Builder(const DefaultAvatarOptions& options)
      : s_(options.height / kReferenceHeight), g_(kBuild * options.girth), options_(options) {
    plan_.scale = s_;
  }

  BodyPlan build() {
    buildTrunkAndHead();
    for (const float side : {1.0f, -1.0f}) buildArm(side);
    for (const float side : {1.0f, -1.0f}) buildLeg(side);
    finish();
    return std::move(plan_);
  }

 private:
  // --- skeleton -------------------------------------------------------------------------
  int joint(const std::string& name, int parent, const glm::vec3& p_ref) {
    plan_.joint_names.push_back(name);
    plan_.joint_parents.push_back(parent);
    plan_.joint_positions.push_back(s_ * p_ref);
    plan_.bone_tips.push_back(s_ * p_ref);  // set by tip()
    return static_cast<int>(plan_.joint_names.size()) - 1;
  }
  void tip(int j, const glm::vec3& p_ref) {
    plan_.bone_tips[static_cast<std::size_t>(j)] = s_ * p_ref;
  }

  // --- parts and shapes (all arguments in reference metres) -------------------------------
  int part(int parent, float blend, float attach_blend) {
    Part p;
    p.parent = parent;
    p.blend = s_ * blend;
    p.attach_blend = s_ * attach_blend;
    plan_.parts.push_back(p);
    return static_cast<int>(plan_.parts.size()) - 1;
  }
  void add(int part_index, Shape shape) {
    plan_.parts[static_cast<std::size_t>(part_index)].shapes.push_back(
        static_cast<int>(plan_.shapes.size()));
    plan_.shapes.push_back(shape);
  }
  void ellipsoid(int part_index, int j, const glm::vec3& c, const glm::vec3& radii, float girth) {
    Shape e;
    e.kind = ShapeKind::kEllipsoid;
    e.origin = s_ * c;
    e.size = s_ * girth * radii;
    e.joint = j;
    add(part_index, e);
  }
  void cone(int part_index, int j, const glm::vec3& a, const glm::vec3& b, float ra, float rb,
            float girth, const glm::vec3& flat_axis = kForward, float flatten = 1.0f) {
    // Local z (the squeezed axis) along flat_axis, made orthogonal to the cone's axis.
    Shape c;
    c.kind = ShapeKind::kRoundCone;
    c.origin = s_ * a;
    c.to_local = frameAlong(b - a, glm::cross(b - a, flat_axis));
    c.size = glm::vec3(s_ * glm::length(b - a), s_ * girth * ra, s_ * girth * rb);
    c.stretch = glm::vec3(1.0f, 1.0f, flatten);
    c.joint = j;
    add(part_index, c);
  }
  void roundBox(int part_index, int j, const glm::vec3& c, const glm::mat3& to_local,
                const glm::vec3& half, float rounding) {
    Shape b;
    b.kind = ShapeKind::kRoundBox;
    b.origin = s_ * c;
    b.to_local = to_local;
    b.size = s_ * half;
    b.rounding = s_ * rounding;
    b.joint = j;
    add(part_index, b);
  }

  // --- body --------------------------------------------------------------------------------
  void buildTrunkAndHead() {
    const int hips = joint("hips", -1, {0.0f, 0.965f, 0.0f});
    const int spine = joint("spine", hips, {0.0f, 1.065f, -0.005f});
    const int chest = joint("chest", spine, {0.0f, 1.185f, -0.010f});
    const int upper_chest = joint("upper_chest", chest, {0.0f, 1.315f, -0.015f});
    const int neck = joint("neck", upper_chest, {0.0f, 1.465f, -0.025f});
    const int head = joint("head", neck, {0.0f, 1.575f, -0.010f});
    tip(hips, {0.0f, 1.065f, -0.005f});
    tip(spine, {0.0f, 1.185f, -0.010f});
    tip(chest, {0.0f, 1.315f, -0.015f});
    tip(upper_chest, {0.0f, 1.465f, -0.025f});
    tip(neck, {0.0f, 1.575f, -0.010f});
    tip(head, {0.0f, 1.75f, -0.010f});
    upper_chest_ = upper_chest;
    hips_ = hips;

    // Trunk: pelvis, buttocks, belly, rib cage, shoulder girdle, blended generously.
    trunk_ = part(-1, 0.08f, 0.0f);
    ellipsoid(trunk_, hips, {0.0f, 0.955f, -0.005f}, {0.160f, 0.115f, 0.112f}, g_);
    for (const float side : {1.0f, -1.0f}) {
      ellipsoid(trunk_, hips, {side * 0.068f, 0.905f, -0.050f}, {0.082f, 0.095f, 0.072f}, g_);
    }
    ellipsoid(trunk_, spine, {0.0f, 1.085f, 0.008f}, {0.142f, 0.125f, 0.105f}, g_);
    ellipsoid(trunk_, chest, {0.0f, 1.245f, 0.0f}, {0.158f, 0.165f, 0.112f}, g_);
    ellipsoid(trunk_, upper_chest, {0.0f, 1.365f, -0.018f}, {0.172f, 0.085f, 0.095f}, g_);

    // Neck and head (the head keeps its size when the girth changes).
    const int neck_part = part(trunk_, 0.0f, 0.05f);
    cone(neck_part, neck, {0.0f, 1.40f, -0.025f}, {0.0f, 1.60f, -0.010f}, 0.056f, 0.050f, g_);
    const int head_part = part(neck_part, 0.04f, 0.03f);
    ellipsoid(head_part, head, {0.0f, 1.655f, -0.008f}, {0.077f, 0.095f, 0.094f}, 1.0f);
    ellipsoid(head_part, head, {0.0f, 1.600f, 0.028f}, {0.058f, 0.062f, 0.072f}, 1.0f);
    const int nose_part = part(head_part, 0.0f, 0.012f);
    ellipsoid(nose_part, head, {0.0f, 1.628f, 0.093f}, {0.012f, 0.020f, 0.016f}, 1.0f);
    for (const float side : {1.0f, -1.0f}) {
      const int ear_part = part(head_part, 0.0f, 0.010f);
      ellipsoid(ear_part, head, {side * 0.074f, 1.640f, -0.012f}, {0.011f, 0.029f, 0.018f}, 1.0f);
    }
  }

  void buildArm(float side) {
    const std::string pre = side > 0.0f ? "l_" : "r_";
    const auto m = [side](glm::vec3 v) { return glm::vec3(side * v.x, v.y, v.z); };

    // Joints: clavicle, shoulder, elbow (bent 10 degrees forward), wrist.
    const float a = radians(options_.arm_angle_deg);
    const glm::vec3 shoulder{0.175f, 1.425f, -0.020f};
    const glm::vec3 d{std::cos(a), -std::sin(a), 0.0f};
    const glm::vec3 elbow = shoulder + 0.290f * d;
    const float bend = radians(10.0f);
    const glm::vec3 d2 = glm::normalize(std::cos(bend) * d + std::sin(bend) * kForward);
    const glm::vec3 wrist = elbow + 0.255f * d2;

    const int clavicle = joint(pre + "clavicle", upper_chest_, m({0.022f, 1.425f, 0.030f}));
    const int upperarm = joint(pre + "upperarm", clavicle, m(shoulder));
    const int forearm = joint(pre + "forearm", upperarm, m(elbow));
    const int hand = joint(pre + "hand", forearm, m(wrist));
    tip(clavicle, m(shoulder));
    tip(upperarm, m(elbow));
    tip(forearm, m(wrist));

    // Shoulder girdle (trapezius) in the trunk; upper arm, forearm as a chain of parts.
    cone(trunk_, clavicle, m({0.0f, 1.44f, -0.035f}), m({0.150f, 1.425f, -0.025f}), 0.055f, 0.042f,
         g_);
    const int upper_part = part(trunk_, 0.03f, 0.045f);
    ellipsoid(upper_part, upperarm, m(shoulder + 0.012f * d), glm::vec3(0.052f), g_);
    cone(upper_part, upperarm, m(shoulder), m(elbow), 0.047f, 0.037f, g_);
    const int fore_part = part(upper_part, 0.02f, 0.025f);

    // Hand frame: along the fingers, towards the thumb (forward), towards the palm.
    HandFrame hf;
    hf.wrist = wrist;
    hf.u = d2;
    hf.w = glm::normalize(kForward - glm::dot(kForward, d2) * d2);
    hf.n = glm::cross(hf.u, hf.w);
    cone(fore_part, forearm, m(elbow), m(wrist), 0.040f, 0.028f, g_, m(hf.n), 0.8f);

    // Palm: a wider distal box (knuckles) and a narrower proximal one (heel of the hand).
    const glm::mat3 palm_frame = glm::transpose(glm::mat3(m(hf.u), m(hf.w), m(hf.n)));
    const int palm_part = part(fore_part, 0.012f, 0.02f);
    roundBox(palm_part, hand, m(hf.at(0.068f, 0.0f, 0.001f)), palm_frame, {0.031f, 0.041f, 0.0135f},
             0.011f);
    roundBox(palm_part, hand, m(hf.at(0.030f, -0.002f, 0.001f)), palm_frame,
             {0.026f, 0.034f, 0.0135f}, 0.011f);

    // Thumb: metacarpal (thenar), proximal and distal phalanges.
    const int thumb_part = part(palm_part, 0.008f, 0.014f);
    const glm::vec3 t0 = glm::normalize(0.62f * hf.u + 0.62f * hf.w + 0.40f * hf.n);
    const glm::vec3 t1 = glm::normalize(0.80f * hf.u + 0.42f * hf.w + 0.42f * hf.n);
    const glm::vec3 t2 = glm::normalize(0.88f * hf.u + 0.30f * hf.w + 0.38f * hf.n);
    const glm::vec3 th1 = hf.at(0.020f, 0.020f, 0.009f);
    const glm::vec3 th2 = th1 + 0.046f * t0;
    const glm::vec3 th3 = th2 + 0.034f * t1;
    const glm::vec3 th_end = th3 + (0.028f - 0.0080f) * t2;
    const int thumb1 = joint(pre + "thumb1", hand, m(th1));
    const int thumb2 = joint(pre + "thumb2", thumb1, m(th2));
    const int thumb3 = joint(pre + "thumb3", thumb2, m(th3));
    tip(thumb1, m(th2));
    tip(thumb2, m(th3));
    tip(thumb3, m(th_end + 0.0080f * t2));
    cone(thumb_part, thumb1, m(th1), m(th2), 0.0170f, 0.0115f, 1.0f, m(hf.n));
    cone(thumb_part, thumb2, m(th2), m(th3), 0.0108f, 0.0098f, 1.0f, m(hf.n));
    cone(thumb_part, thumb3, m(th3), m(th_end), 0.0098f, 0.0080f, 1.0f, m(hf.n));

    // Fingers: three cone-spheres each, fanned out in the palm plane, slightly flexed.
    int first_knuckle = -1;
    for (const FingerLayout& f : kFingers) {
      const float spread = radians(f.spread_units * options_.finger_spread_deg);
      const glm::vec3 fan = std::cos(spread) * hf.u + std::sin(spread) * hf.w;
      std::array<glm::vec3, 4> p;
      p[0] = hf.at(f.base_along, f.base_thumbward, 0.0f);
      std::array<glm::vec3, 3> dir;
      for (std::size_t k = 0; k < 3; ++k) {
        const float flex = radians(kFingerFlexDeg[k]);
        dir[k] = std::cos(flex) * fan + std::sin(flex) * hf.n;
        const float length = k == 2 ? f.lengths[k] - f.radii[3] : f.lengths[k];
        p[k + 1] = p[k] + length * dir[k];
      }
      const int finger_part = part(palm_part, 0.004f, 0.014f);
      int parent = hand;
      for (std::size_t k = 0; k < 3; ++k) {
        const int j = joint(pre + f.name + std::to_string(k + 1), parent, m(p[k]));
        if (first_knuckle < 0) first_knuckle = j;
        tip(j, m(k == 2 ? p[3] + f.radii[3] * dir[2] : p[k + 1]));
        cone(finger_part, j, m(p[k]), m(p[k + 1]), f.radii[k], f.radii[k + 1], 1.0f, m(hf.n));
        parent = j;
      }
    }
    // The hand's bone runs from the wrist to the middle knuckle.
    tip(hand, plan_.joint_positions[static_cast<std::size_t>(first_knuckle + 3)] / s_);
  }

  void buildLeg(float side) {
    const std::string pre = side > 0.0f ? "l_" : "r_";
    const auto m = [side](glm::vec3 v) { return glm::vec3(side * v.x, v.y, v.z); };
    const glm::vec3 hip{0.090f, 0.925f, 0.000f};
    const glm::vec3 knee{0.100f, 0.500f, 0.012f};
    const glm::vec3 ankle{0.108f, 0.082f, -0.030f};
    const glm::vec3 ball{0.114f, 0.022f, 0.110f};
    const glm::vec3 toe_tip{0.118f, 0.020f, 0.185f};
    const int thigh = joint(pre + "thigh", hips_, m(hip));
    const int shin = joint(pre + "shin", thigh, m(knee));
    const int foot = joint(pre + "foot", shin, m(ankle));
    const int toes = joint(pre + "toes", foot, m(ball));
    tip(thigh, m(knee));
    tip(shin, m(ankle));
    tip(foot, m(ball));
    tip(toes, m(toe_tip));

    const int thigh_part = part(trunk_, 0.04f, 0.06f);
    cone(thigh_part, thigh, m(hip), m(knee), 0.082f, 0.053f, g_);
    const int shin_part = part(thigh_part, 0.035f, 0.035f);
    ellipsoid(shin_part, shin, m(knee + glm::vec3(0.0f, 0.0f, 0.008f)), {0.048f, 0.052f, 0.048f},
              g_);
    cone(shin_part, shin, m(knee), m(ankle), 0.050f, 0.033f, g_);
    ellipsoid(shin_part, shin, m({0.100f, 0.355f, -0.028f}), {0.050f, 0.105f, 0.052f}, g_);

    // Foot: heel, instep and a flat sole (soles on y = 0); the toes as one flattened
    // cone-sphere across the foot, from the big toe to the little toe.
    const int foot_part = part(shin_part, 0.03f, 0.03f);
    ellipsoid(foot_part, foot, m({0.108f, 0.040f, -0.040f}), {0.035f, 0.040f, 0.040f}, 1.0f);
    ellipsoid(foot_part, foot, m({0.110f, 0.043f, 0.025f}), {0.040f, 0.038f, 0.085f}, 1.0f);
    roundBox(foot_part, foot, m({0.113f, 0.016f, 0.050f}), glm::mat3(1.0f),
             {0.044f, 0.016f, 0.085f}, 0.014f);
    const int toes_part = part(foot_part, 0.0f, 0.03f);
    constexpr float kToeFlat = 0.75f;
    cone(toes_part, toes, m({0.092f, 0.017f * kToeFlat, 0.160f}),
         m({0.140f, 0.013f * kToeFlat, 0.128f}), 0.017f, 0.013f, 1.0f, {0.0f, 1.0f, 0.0f},
         kToeFlat);
  }

  // Bounding spheres, overall bounds and the fine regions: each hand two halvings finer
  // than the body, its four fingers (narrow gaps) three.
  void finish() {
    const auto empty = [] { return Box{glm::vec3(1e9f), glm::vec3(-1e9f)}; };
    const auto grow = [](Box& box, const Shape& sh) {
      box.min = glm::min(box.min, sh.bound_center - glm::vec3(sh.bound_radius));
      box.max = glm::max(box.max, sh.bound_center + glm::vec3(sh.bound_radius));
    };
    Box all = empty();
    std::array<Box, 2> hands{empty(), empty()};
    std::array<Box, 2> fingers{empty(), empty()};
    for (Shape& sh : plan_.shapes) {
      finishShape(sh);
      grow(all, sh);
      const std::string& name = plan_.joint_names[static_cast<std::size_t>(sh.joint)];
      const std::size_t side = name[0] == 'l' ? 0 : 1;
      const bool finger =
          name.find("index") != std::string::npos || name.find("middle") != std::string::npos ||
          name.find("ring") != std::string::npos || name.find("pinky") != std::string::npos;
      if (finger) grow(fingers[side], sh);
      if (finger || name.find("hand") != std::string::npos ||
          name.find("thumb") != std::string::npos) {
        grow(hands[side], sh);
      }
    }
    plan_.bounds = all;
    for (std::size_t side = 0; side < 2; ++side) {
      plan_.fine_regions.push_back({hands[side], 2});
      plan_.fine_regions.push_back({fingers[side], 3});
    }
  }

  float s_;
  float g_;
  DefaultAvatarOptions options_;
  BodyPlan plan_;
  int trunk_ = 0;
  int upper_chest_ = 0;
  int hips_ = 0;
};

}  // namespace

BodyPlan makeBodyPlan(const DefaultAvatarOptions& options) { return Builder(options).build(); }

void finishShape(Shape& sh) {
  const float stretch_max = std::max({sh.stretch.x, sh.stretch.y, sh.stretch.z});
  const float stretch_min = std::min({sh.stretch.x, sh.stretch.y, sh.stretch.z});
  // Values of squeezed shapes shrink by up to this ratio against true distances.
  sh.bound_slope = stretch_min / stretch_max;
  const glm::mat3 to_model = glm::transpose(sh.to_local);
  switch (sh.kind) {
    case ShapeKind::kEllipsoid:
      sh.bound_center = sh.origin;
      sh.bound_radius = std::max({sh.size.x, sh.size.y, sh.size.z});
      sh.detail = std::min({sh.size.x, sh.size.y, sh.size.z});
      sh.bound_slope = sh.detail / sh.bound_radius;
      break;
    case ShapeKind::kRoundCone:
      sh.bound_center =
          sh.origin + to_model * (sh.stretch * glm::vec3(0.0f, 0.5f * sh.size.x, 0.0f));
      sh.bound_radius = (0.5f * sh.size.x + std::max(sh.size.y, sh.size.z)) * stretch_max;
      sh.detail = std::min(sh.size.y, sh.size.z) * stretch_min;
      break;
    case ShapeKind::kRoundBox:
      sh.bound_center = sh.origin;
      sh.bound_radius = glm::length(sh.size) * stretch_max;
      sh.detail = std::min({sh.size.x, sh.size.y, sh.size.z});
      break;
  }
}

}  // namespace vistel::synth
