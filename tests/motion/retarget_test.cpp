// Retargeting (common/motion/retarget.hpp), checked on real geometry: after retargeting a
// frame, each mapped limb bone of the target points the way the source's does.
#include <cmath>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "tests/motion/glb_skeleton.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

struct Limb {
  const char* from;
  const char* to;
};
constexpr Limb kLimbs[] = {{"l_upperarm", "l_forearm"}, {"l_forearm", "l_hand"},
                           {"r_upperarm", "r_forearm"}, {"r_forearm", "r_hand"},
                           {"l_thigh", "l_shin"},       {"l_shin", "l_foot"},
                           {"r_thigh", "r_shin"},       {"r_shin", "r_foot"}};
constexpr Limb kSpine = {"spine", "neck"};

JointMap mapNamed(const std::string& name) {
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  EXPECT_TRUE(maps.ok());
  for (const JointMap& m : *maps) {
    if (m.name == name) return m;
  }
  ADD_FAILURE() << "no map " << name;
  return {};
}

MotionClip clipAt(const std::string& path) {
  Result<MotionClip> clip = loadBvh(path);
  EXPECT_TRUE(clip.ok()) << (clip ? "" : clip.error().message);
  return clip ? *clip : MotionClip{};
}

// A skeleton in a posture, seen through a map.
struct Posed {
  const Skeleton* skeleton;
  const JointMap* map;
  std::vector<glm::mat4> model;

  Posed(const Skeleton& s, const JointMap& m, const Posture& p)
      : skeleton(&s), map(&m), model(s.names.size()) {
    poseSkeleton(s, p, model);
  }
  int index(std::string_view canonical) const {
    const int j = skeleton->find(map->jointFor(canonical));
    EXPECT_GE(j, 0) << canonical;
    return j;
  }
  glm::vec3 at(std::string_view canonical) const {
    return glm::vec3(model[static_cast<std::size_t>(index(canonical))][3]);
  }
  glm::vec3 direction(const Limb& b) const { return glm::normalize(at(b.to) - at(b.from)); }
  glm::quat rotation(std::string_view canonical) const {
    return glm::normalize(
        glm::quat_cast(glm::mat3(model[static_cast<std::size_t>(index(canonical))])));
  }
};

float degreesBetween(glm::vec3 a, glm::vec3 b) {
  return glm::degrees(std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)));
}

// Largest angle (degrees) between source and target directions of the given bones.
template <typename Bones>
float worstBone(const Posed& source, const Posed& target, const Bones& bones, std::string* which) {
  float worst = 0.0f;
  for (const Limb& b : bones) {
    const float e = degreesBetween(source.direction(b), target.direction(b));
    if (e > worst) {
      worst = e;
      if (which != nullptr) *which = std::string(b.from) + "->" + b.to;
    }
  }
  return worst;
}

// Retargets every `step`-th frame and checks limb and spine directions; returns the worst
// limb error seen (degrees).
float checkClip(const MotionClip& clip, const JointMap& clip_map, const Skeleton& target,
                const JointMap& target_map, const Retargeter& r, int step, float limb_limit,
                float spine_limit) {
  const Skeleton source = clipSkeleton(clip);
  Posture in, out;
  float worst = 0.0f;
  float worst_spine = 0.0f;
  for (int k = 0; k < clip.frame_count; k += step) {
    samplePosture(clip, k, in);
    r.apply(in, out);
    const Posed s(source, clip_map, in);
    const Posed t(target, target_map, out);
    std::string bone;
    const float limb = worstBone(s, t, kLimbs, &bone);
    EXPECT_LT(limb, limb_limit) << clip.source << " frame " << k << " bone " << bone;
    const float spine = degreesBetween(s.direction(kSpine), t.direction(kSpine));
    EXPECT_LT(spine, spine_limit) << clip.source << " frame " << k;
    worst = std::max(worst, limb);
    worst_spine = std::max(worst_spine, spine);
  }
  std::cout << clip.source << " -> " << target_map.name << ": worst limb " << worst
            << " deg, worst spine-neck " << worst_spine << " deg\n";
  return worst;
}

// (a) Onto the clip's own skeleton: the identity, positions included.
TEST(Retarget, IdentityOnTheClipsOwnSkeleton) {
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/01_01.bvh");
  const MotionClip clip = clipAt(path);
  const Skeleton s = clipSkeleton(clip);
  const JointMap map = mapNamed("cmu_01");
  RetargetOptions options;
  options.target_floor = 0.0f;
  Result<Retargeter> r = Retargeter::create(s, map, s, map, options);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_FLOAT_EQ(r->translationScale(), 1.0f);
  Posture in, out;
  for (int k = 0; k < clip.frame_count; k += 150) {
    samplePosture(clip, k, in);
    r->apply(in, out);
    const Posed a(s, map, in);
    const Posed b(s, map, out);
    EXPECT_LT(worstBone(a, b, kLimbs, nullptr), 0.05f) << k;
    // Every mapped joint but the neck and head, which sit below the clip's unmapped
    // lower-neck joint "Neck" (kept at rest on the target).
    for (const std::string& c : map.canonical) {
      if (c == "neck" || c == "head") continue;
      EXPECT_LT(glm::distance(a.at(c), b.at(c)), 1e-4f) << c << " frame " << k;
    }
  }
}

TEST(Retarget, IdentityOnAGestureClip) {
  VISTEL_REQUIRE_SHARED(path, "mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh");
  const MotionClip clip = clipAt(path);
  const Skeleton s = clipSkeleton(clip);
  const JointMap map = mapNamed("bandai_gestures");
  Result<Retargeter> r = Retargeter::forClip(clip, map, s, map);
  ASSERT_TRUE(r.ok()) << r.error().message;
  checkClip(clip, map, s, map, *r, 5, 0.5f, 0.5f);
}

// (b) A CMU 01 clip onto the CMU 131 skeleton (other names, other rotation orders, arms
// down at rest), and the other way round.
TEST(Retarget, Cmu01OntoCmu131AndBack) {
  VISTEL_REQUIRE_SHARED(path01, "mocap/cmu/01_01.bvh");
  VISTEL_REQUIRE_SHARED(path131, "mocap/cmu/131_01.bvh");
  const MotionClip clip01 = clipAt(path01);
  const MotionClip clip131 = clipAt(path131);
  const JointMap map01 = mapNamed("cmu_01");
  const JointMap map131 = mapNamed("cmu_131");
  const Skeleton skel01 = clipSkeleton(clip01);
  const Skeleton skel131 = clipSkeleton(clip131);
  Result<Retargeter> forward = Retargeter::forClip(clip01, map01, skel131, map131);
  ASSERT_TRUE(forward.ok()) << forward.error().message;
  checkClip(clip01, map01, skel131, map131, *forward, 23, 1.0f, 3.0f);
  Result<Retargeter> back = Retargeter::forClip(clip131, map131, skel01, map01);
  ASSERT_TRUE(back.ok()) << back.error().message;
  checkClip(clip131, map131, skel01, map01, *back, 11, 1.0f, 3.0f);
}

// (c) Onto an A-pose variant of a skeleton: upper arms 45 degrees down at rest (and the
// forearms twisted), so local angles cannot be copied.
TEST(Retarget, OntoAnAPoseVariant) {
  VISTEL_REQUIRE_SHARED(path01, "mocap/cmu/01_01.bvh");
  VISTEL_REQUIRE_SHARED(path131, "mocap/cmu/131_02.bvh");
  const MotionClip clip01 = clipAt(path01);
  const MotionClip clip131 = clipAt(path131);
  const JointMap map01 = mapNamed("cmu_01");
  const JointMap map131 = mapNamed("cmu_131");
  Skeleton a_pose = clipSkeleton(clip01);
  const auto set = [&](const char* name, glm::quat q) {
    a_pose.rest_local[static_cast<std::size_t>(a_pose.find(name))].rotation = q;
  };
  set("LeftArm", glm::angleAxis(glm::radians(-45.0f), glm::vec3(0, 0, 1)));
  set("RightArm", glm::angleAxis(glm::radians(45.0f), glm::vec3(0, 0, 1)));
  set("LeftForeArm", glm::angleAxis(glm::radians(30.0f), glm::vec3(1, 0, 0)));
  set("RightForeArm", glm::angleAxis(glm::radians(-30.0f), glm::vec3(1, 0, 0)));
  computeInverseBind(a_pose);
  // The variant's rest really is an A-pose: the left upper arm points 45 degrees down.
  const Posed rest(a_pose, map01, restPosture(a_pose));
  EXPECT_NEAR(degreesBetween(rest.direction(kLimbs[0]), glm::vec3(1, 0, 0)), 45.0f, 6.0f);

  for (const auto& [clip, map] : {std::pair{&clip01, &map01}, std::pair{&clip131, &map131}}) {
    Result<Retargeter> r = Retargeter::forClip(*clip, *map, a_pose, map01);
    ASSERT_TRUE(r.ok()) << r.error().message;
    checkClip(*clip, *map, a_pose, map01, *r, 37, 1.0f, 3.0f);
  }
}

// (d) CMU and gesture clips onto the MakeHuman avatar's skeleton (A-pose, other names,
// a Root joint above the pelvis).
class RetargetMakeHuman : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string glb = test::sharedDataPath("avatars/makehuman_game_engine.glb");
    Result<Skeleton> s = test::loadGlbSkeleton(glb);
    if (!s) GTEST_SKIP() << "shared avatar not available: " << s.error().message;
    human_ = *s;
    human_map_ = mapNamed("makehuman");
  }

  // Retargets every step-th frame; checks bone directions, the knees facing forward and
  // the feet staying near the floor. Returns the retargeter for further checks.
  void run(const std::string& relative, const char* map_name, int step, float spine_limit) {
    const std::string path = test::sharedDataPath(relative);
    if (!std::ifstream(path).good()) GTEST_SKIP() << "shared clip not available: " << path;
    const MotionClip clip = clipAt(path);
    const JointMap map = mapNamed(map_name);
    Result<Retargeter> r = Retargeter::forClip(clip, map, human_, human_map_);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_GT(r->translationScale(), 0.8f);
    EXPECT_LT(r->translationScale(), 1.2f);
    checkClip(clip, map, human_, human_map_, *r, step, 1.0f, spine_limit);

    // No leg turned about its own axis: each thigh's rest left-right axis (+X, the knee's
    // hinge) stays roughly left-right (a knee facing backwards would flip it).
    const Skeleton source = clipSkeleton(clip);
    const Posed rest(human_, human_map_, restPosture(human_));
    Posture in, out;
    float lowest_foot = 1e9f, highest_foot = -1e9f;
    for (int k = 0; k < clip.frame_count; k += step) {
      samplePosture(clip, k, in);
      r->apply(in, out);
      const Posed t(human_, human_map_, out);
      const glm::vec3 left = glm::normalize(t.at("l_thigh") - t.at("r_thigh"));
      for (const char* thigh : {"l_thigh", "r_thigh"}) {
        const glm::vec3 hinge =
            t.rotation(thigh) * glm::inverse(rest.rotation(thigh)) * glm::vec3(1, 0, 0);
        EXPECT_GT(glm::dot(hinge, left), 0.5f) << thigh << " frame " << k;
      }
      const float foot = std::min(t.at("l_foot").y, t.at("r_foot").y);
      lowest_foot = std::min(lowest_foot, foot);
      highest_foot = std::max(highest_foot, foot);
    }
    // The clip's planted feet land at the avatar's rest ankle height (the lowest point of
    // the motion; 01_01 jumps, so the highest is not checked).
    const float rest_ankle = rest.at("l_foot").y;
    EXPECT_NEAR(lowest_foot, rest_ankle, 0.02f) << relative;
  }

  Skeleton human_;
  JointMap human_map_;
};

TEST_F(RetargetMakeHuman, CmuJumpClip) { run("mocap/cmu/01_01.bvh", "cmu_01", 29, 3.0f); }
TEST_F(RetargetMakeHuman, CmuWalkClip) { run("mocap/cmu/131_01.bvh", "cmu_131", 17, 3.0f); }
TEST_F(RetargetMakeHuman, GestureWaveClip) {
  run("mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh", "bandai_gestures", 3, 3.0f);
}
TEST_F(RetargetMakeHuman, GestureBowClip) {
  run("mocap/gestures/dataset-1_bow_normal_001.bvh", "bandai_gestures", 3, 3.0f);
}

// The hips follow the source's, scaled; the rest of the avatar's joints keep their rest
// rotations when the clip has nothing for them (fingers, Root).
TEST_F(RetargetMakeHuman, HipsFollowAndUnmappedJointsRest) {
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/131_01.bvh");
  const MotionClip clip = clipAt(path);
  const JointMap map = mapNamed("cmu_131");
  Result<Retargeter> r = Retargeter::forClip(clip, map, human_, human_map_);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const Skeleton source = clipSkeleton(clip);
  Posture a, b, ta, tb;
  samplePosture(clip, 0, a);
  samplePosture(clip, clip.frame_count - 1, b);
  r->apply(a, ta);
  r->apply(b, tb);
  const glm::vec3 source_move = Posed(source, map, b).at("hips") - Posed(source, map, a).at("hips");
  const glm::vec3 target_move =
      Posed(human_, human_map_, tb).at("hips") - Posed(human_, human_map_, ta).at("hips");
  EXPECT_GT(glm::length(source_move), 1.0f);  // the walk covers some ground
  EXPECT_LT(glm::distance(target_move, r->translationScale() * source_move), 1e-3f);
  for (const char* name : {"Root", "index_02_l", "thumb_03_r"}) {
    const int j = human_.find(name);
    ASSERT_GE(j, 0);
    EXPECT_EQ(r->sourceOf(j), -1) << name;
    const glm::quat rest = human_.rest_local[static_cast<std::size_t>(j)].rotation;
    const glm::quat got = tb.rotations[static_cast<std::size_t>(j)];
    EXPECT_GT(std::abs(glm::dot(rest, got)), 1.0f - 1e-6f) << name;
  }
}

TEST_F(RetargetMakeHuman, ApplyAllocatesNothingAfterTheFirstCall) {
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/01_01.bvh");
  const MotionClip clip = clipAt(path);
  Result<Retargeter> r = Retargeter::forClip(clip, mapNamed("cmu_01"), human_, human_map_);
  ASSERT_TRUE(r.ok()) << r.error().message;
  Posture in, out;
  samplePosture(clip, 0, in);
  r->apply(in, out);
  const long before = test::allocationCount();
  for (int k = 1; k < 200; ++k) {
    samplePosture(clip, k, in);
    r->apply(in, out);
  }
  EXPECT_EQ(test::allocationCount() - before, 0);
}

// Bad pairings fail with a message naming what is missing.
TEST(Retarget, ErrorsNameTheMissingJoint) {
  const JointMap map01 = mapNamed("cmu_01");
  const JointMap map131 = mapNamed("cmu_131");
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/01_01.bvh");
  const Skeleton s01 = clipSkeleton(clipAt(path));
  // The 01 skeleton through the 131 map: no "LeftHip" there.
  Result<Retargeter> r = Retargeter::create(s01, map131, s01, map01);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("source skeleton has no joint"), std::string::npos)
      << r.error().message;
  // A map without a required joint.
  Result<JointMap> small =
      parseJointMap("required = [\"hips\"]\n[joints]\nhips = \"Hips\"\n", "s.toml");
  ASSERT_TRUE(small.ok()) << small.error().message;
  r = Retargeter::create(s01, map01, s01, *small);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("does not name required joint 'spine'"), std::string::npos)
      << r.error().message;
  // A reference posture for another skeleton.
  RetargetOptions options;
  options.source_reference = Posture{};
  r = Retargeter::create(s01, map01, s01, map01, options);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("reference posture"), std::string::npos) << r.error().message;
}

// The gesture clips' zero pose is not a standing pose, so their first frame is the
// reference; the CMU clips' zero pose is.
TEST(Retarget, ReferencePostureOfEachFamily) {
  VISTEL_REQUIRE_SHARED(gesture, "mocap/gestures/dataset-1_bow_normal_001.bvh");
  VISTEL_REQUIRE_SHARED(cmu, "mocap/cmu/131_01.bvh");
  const MotionClip g = clipAt(gesture);
  Posture ref, first;
  clipReferencePosture(g, mapNamed("bandai_gestures"), ref);
  samplePosture(g, 0, first);
  EXPECT_EQ(ref.rotations, first.rotations);
  const MotionClip c = clipAt(cmu);
  clipReferencePosture(c, mapNamed("cmu_131"), ref);
  for (const glm::quat& q : ref.rotations) EXPECT_EQ(q, glm::quat(1, 0, 0, 0));
}

}  // namespace
}  // namespace vistel
