// The bundled gesture clips (offline/gestures): they parse back, loop, are deterministic,
// and do what their names say (the clap's palms meet without passing through).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/gestures/gestures.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

const std::vector<MotionClip>& clips() {
  static const std::vector<MotionClip> kClips = makeBundledGestures();
  return kClips;
}

const MotionClip& clipNamed(const std::string& name) {
  for (const MotionClip& c : clips()) {
    if (c.source == name) return c;
  }
  ADD_FAILURE() << "no clip " << name;
  return clips().front();
}

// Model-space transforms of every joint in frame k.
struct Frame {
  Skeleton skeleton;
  std::vector<glm::mat4> model;

  Frame(const MotionClip& clip, int k)
      : skeleton(clipSkeleton(clip)), model(skeleton.names.size()) {
    Posture p;
    samplePosture(clip, k, p);
    poseSkeleton(skeleton, p, model);
  }
  const glm::mat4& m(std::string_view name) const {
    const int j = skeleton.find(name);
    EXPECT_GE(j, 0) << name;
    return model[static_cast<std::size_t>(std::max(j, 0))];
  }
  glm::vec3 at(std::string_view name) const { return glm::vec3(m(name)[3]); }
  // Palm centre (on the hand bone's axis) and palm normal.
  void palm(bool left, glm::vec3& centre, glm::vec3& normal) const {
    const std::string side = left ? "l_" : "r_";
    const glm::mat4& hand = m(side + "hand");
    const glm::vec3 knuckle =
        skeleton.rest_local[static_cast<std::size_t>(skeleton.find(side + "middle1"))].translation;
    centre = glm::vec3(hand * glm::vec4(0.5f * knuckle, 1.0f));
    normal = glm::normalize(glm::mat3(hand) * glm::vec3(0.0f, -1.0f, 0.0f));
  }
};

float degreesBetween(glm::vec3 a, glm::vec3 b) {
  return glm::degrees(std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)));
}

TEST(Gestures, SkeletonIsACanonicalTPose) {
  const Skeleton s = makeGestureSkeleton();
  ASSERT_TRUE(validateSkeleton(s).ok());
  ASSERT_EQ(s.names.size(), canonicalJoints().size());
  for (std::size_t j = 0; j < s.names.size(); ++j) EXPECT_EQ(s.names[j], canonicalJoints()[j]);
  const std::vector<glm::mat4> rest = restModelTransforms(s);
  const auto at = [&](std::string_view n) {
    return glm::vec3(rest[static_cast<std::size_t>(s.find(n))][3]);
  };
  // Adult proportions, +Y up, arms out along +-X, left side +X, facing +Z, soles on y = 0.
  EXPECT_NEAR(at("hips").y, 0.95f, 0.05f);
  EXPECT_GT(at("head").y, 1.5f);
  EXPECT_GT(at("l_hand").x, 0.6f);
  EXPECT_LT(at("r_hand").x, -0.6f);
  EXPECT_NEAR(at("l_hand").y, at("l_upperarm").y, 1e-6f);
  EXPECT_GT(at("l_toes").z, at("l_foot").z + 0.1f);
  for (const glm::mat4& m : rest) EXPECT_GT(m[3].y, 0.0f);
  // The identity map fits it.
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  ASSERT_TRUE(maps.ok());
  Result<const JointMap*> map = selectJointMap(*maps, s);
  ASSERT_TRUE(map.ok()) << map.error().message;
  EXPECT_EQ((*map)->name, "vistel_default");
}

TEST(Gestures, FourClipsOfSeveralSecondsAtThirtyFps) {
  std::vector<std::string> names;
  for (const MotionClip& c : clips()) {
    names.push_back(c.source);
    EXPECT_DOUBLE_EQ(c.frame_time, 1.0 / 30.0) << c.source;
    EXPECT_GE(c.duration(), 3.0) << c.source;
    EXPECT_LE(c.duration(), 10.0) << c.source;
    EXPECT_EQ(c.unit_scale, 1.0f);
    EXPECT_EQ(c.joints.size(), canonicalJoints().size());
    EXPECT_EQ(c.values.size(), static_cast<std::size_t>(c.frame_count) * c.channel_count);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"wave", "point", "clap", "idle"}));
}

TEST(Gestures, ParseBackLoopAndAreDeterministic) {
  const std::vector<MotionClip> again = makeBundledGestures();
  ASSERT_EQ(again.size(), clips().size());
  for (std::size_t i = 0; i < clips().size(); ++i) {
    const MotionClip& c = clips()[i];
    const std::string text = writeBvh(c);
    EXPECT_EQ(writeBvh(again[i]), text) << c.source;
    Result<MotionClip> parsed = parseBvh(text, c.source + ".bvh");
    ASSERT_TRUE(parsed.ok()) << parsed.error().message;
    EXPECT_EQ(parsed->unit_scale, 1.0f) << "units inferred as metres";
    EXPECT_TRUE(parsed->values == c.values) << c.source;
    // Loops: the last frame is the first.
    const std::span<const float> first = c.frame(0);
    const std::span<const float> last = c.frame(c.frame_count - 1);
    for (std::size_t v = 0; v < first.size(); ++v) {
      EXPECT_NEAR(first[v], last[v], 1e-4f) << c.source << " value " << v;
    }
  }
}

TEST(Gestures, SmoothAndStanding) {
  for (const MotionClip& c : clips()) {
    Frame previous(c, 0);
    for (int k = 1; k < c.frame_count; ++k) {
      const Frame f(c, k);
      float fastest = 0.0f;
      for (std::size_t j = 0; j < f.model.size(); ++j) {
        fastest = std::max(
            fastest, glm::distance(glm::vec3(f.model[j][3]), glm::vec3(previous.model[j][3])));
      }
      // No jumps: under 2 m/s for any joint (6.7 cm per frame at 30 fps).
      EXPECT_LT(fastest, 0.067f) << c.source << " frame " << k;
      EXPECT_GT(f.at("head").y, f.at("hips").y + 0.5f) << c.source << " frame " << k;
      previous = f;
    }
  }
}

TEST(Gestures, ClapPalmsMeetAndNeverPassThrough) {
  const MotionClip& clap = clipNamed("clap");
  float closest = 1e9f;
  int contacts = 0;
  for (int k = 0; k < clap.frame_count; ++k) {
    const Frame f(clap, k);
    glm::vec3 cl, nl, cr, nr;
    f.palm(true, cl, nl);
    f.palm(false, cr, nr);
    const float gap = glm::distance(cl, cr);
    closest = std::min(closest, gap);
    // The palm centres never come closer than the two palms' thickness: the skins touch
    // at most (1 mm of slack for float rounding).
    EXPECT_GE(gap, 2.0f * kGesturePalmHalfThickness - 0.001f) << "frame " << k;
    if (gap < 0.03f) {
      ++contacts;
      // Facing each other, the right palm straight across from the left one.
      EXPECT_LT(glm::dot(nl, nr), -0.95f) << "frame " << k;
      EXPECT_GT(glm::dot(glm::normalize(cr - cl), nl), 0.95f) << "frame " << k;
    }
  }
  // Three claps at frames 36, 57, 78: within ~3 cm (palm centres 2.6 cm apart).
  for (int k : {36, 57, 78}) {
    const Frame f(clap, k);
    glm::vec3 cl, nl, cr, nr;
    f.palm(true, cl, nl);
    f.palm(false, cr, nr);
    EXPECT_LT(glm::distance(cl, cr), 0.03f) << "frame " << k;
    EXPECT_NEAR(glm::distance(cl, cr), 2.0f * kGesturePalmHalfThickness, 1e-3f) << "frame " << k;
    // In front of the chest.
    EXPECT_GT(cl.z, f.at("chest").z + 0.15f);
    EXPECT_NEAR(cl.y, f.at("upper_chest").y - 0.05f, 0.15f);
  }
  EXPECT_GE(contacts, 3);
  EXPECT_NEAR(closest, 2.0f * kGesturePalmHalfThickness, 1e-3f);
  // Apart in between.
  const Frame apart(clap, 45);
  glm::vec3 cl, nl, cr, nr;
  apart.palm(true, cl, nl);
  apart.palm(false, cr, nr);
  EXPECT_GT(glm::distance(cl, cr), 0.2f);
}

TEST(Gestures, WaveRaisesTheRightHandAndSwingsTheForearm) {
  const MotionClip& wave = clipNamed("wave");
  float min_angle = 1e9f, max_angle = -1e9f;
  for (int k = 45; k <= 105; ++k) {
    const Frame f(wave, k);
    EXPECT_GT(f.at("r_hand").y, f.at("head").y) << "frame " << k;
    EXPECT_LT(f.at("l_hand").y, f.at("hips").y) << "left hand stays down, frame " << k;
    // Forearm tilt in the frontal plane.
    const glm::vec3 fore = f.at("r_hand") - f.at("r_forearm");
    const float angle = glm::degrees(std::atan2(fore.x, fore.y));
    min_angle = std::min(min_angle, angle);
    max_angle = std::max(max_angle, angle);
    // Palm forward.
    glm::vec3 centre, normal;
    f.palm(false, centre, normal);
    EXPECT_GT(normal.z, 0.8f) << "frame " << k;
  }
  EXPECT_GT(max_angle - min_angle, 35.0f);
  const Frame start(wave, 0);
  EXPECT_LT(start.at("r_hand").y, start.at("hips").y);
}

TEST(Gestures, PointAheadThenToTheSide) {
  const MotionClip& point = clipNamed("point");
  const auto arm = [](const Frame& f) {
    return glm::normalize(f.at("r_hand") - f.at("r_upperarm"));
  };
  const Frame ahead(point, 45);
  EXPECT_LT(degreesBetween(arm(ahead), glm::vec3(0, 0, 1)), 15.0f);
  const Frame side(point, 105);
  EXPECT_LT(degreesBetween(arm(side), glm::vec3(-1, 0, 0)), 20.0f);
  for (const Frame* f : {&ahead, &side}) {
    // The index finger straight along the arm, the middle finger curled.
    const glm::vec3 index = f->at("r_index3") - f->at("r_index1");
    const glm::vec3 middle = f->at("r_middle3") - f->at("r_middle1");
    EXPECT_LT(degreesBetween(index, arm(*f)), 20.0f);
    EXPECT_GT(degreesBetween(middle, arm(*f)), 60.0f);
  }
  // The head turns towards the side.
  const glm::vec3 face = glm::mat3(side.m("head")) * glm::vec3(0, 0, 1);
  EXPECT_LT(face.x, -0.5f);
}

TEST(Gestures, IdleKeepsTheFeetPlantedWhileTheWeightShifts) {
  const MotionClip& idle = clipNamed("idle");
  const Frame first(idle, 0);
  float min_x = 1e9f, max_x = -1e9f;
  float min_chest = 1e9f, max_chest = -1e9f;
  for (int k = 0; k < idle.frame_count; ++k) {
    const Frame f(idle, k);
    for (const char* foot : {"l_foot", "r_foot", "l_toes", "r_toes"}) {
      EXPECT_LT(glm::distance(f.at(foot), first.at(foot)), 0.01f) << foot << " frame " << k;
    }
    min_x = std::min(min_x, f.at("hips").x);
    max_x = std::max(max_x, f.at("hips").x);
    const float chest = f.at("neck").z - f.at("chest").z;
    min_chest = std::min(min_chest, chest);
    max_chest = std::max(max_chest, chest);
  }
  EXPECT_GT(max_x - min_x, 0.04f);
  EXPECT_GT(max_chest - min_chest, 0.003f);  // breathing moves the chest
}

TEST(Gestures, WritesOneFilePerClip) {
  const std::string dir = test::scratchDir() + "/gestures";
  ASSERT_TRUE(writeBundledGestures(dir).ok());
  for (const MotionClip& c : clips()) {
    Result<MotionClip> read = loadBvh(dir + "/" + c.source + ".bvh");
    ASSERT_TRUE(read.ok()) << read.error().message;
    EXPECT_TRUE(read->values == c.values);
  }
  // A path that cannot be a folder fails with a message naming it.
  const std::string file = dir + "/wave.bvh/sub";
  Status bad = writeBundledGestures(file);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("wave.bvh"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace vistel
