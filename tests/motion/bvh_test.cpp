// BVH import and export (common/motion/bvh.hpp): every shared clip, decode-every-prefix,
// malformed input, round trips, units, sampling and forward kinematics.
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include "common/base/file.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

// ---------------------------------------------------------------------------------------
// Helpers.

// Counts taken from the file text without the parser: ROOT/JOINT lines, the CHANNELS
// numbers, the "Frames:" number.
struct TextCounts {
  int joints = 0;
  int channels = 0;
  int frames = -1;
};
TextCounts countFromText(const std::string& text) {
  TextCounts c;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string first;
    words >> first;
    if (first == "ROOT" || first == "JOINT") ++c.joints;
    if (first == "CHANNELS") {
      int n = 0;
      words >> n;
      c.channels += n;
    }
    if (first == "Frames:") words >> c.frames;
  }
  return c;
}

std::string readText(const std::string& path) {
  Result<std::string> text = readFileText(path);
  EXPECT_TRUE(text.ok()) << path;
  return text ? *text : std::string();
}

// The hierarchy and the first k frames of a clip's text ("Frames:" rewritten to k), line
// endings kept as they were.
std::string firstFrames(const std::string& text, int k) {
  std::string out;
  std::size_t pos = 0;
  int after_time = -1;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    eol = eol == std::string::npos ? text.size() : eol + 1;
    std::string line = text.substr(pos, eol - pos);
    pos = eol;
    const std::string ending = line.ends_with("\r\n") ? "\r\n" : "\n";
    if (line.starts_with("Frames:")) line = "Frames: " + std::to_string(k) + ending;
    if (after_time >= 0) ++after_time;
    if (line.starts_with("Frame Time:")) after_time = 0;
    out += line;
    if (after_time == k) break;
  }
  return out;
}

// Model-space joint positions of frame k.
std::vector<glm::vec3> framePositions(const MotionClip& clip, int k) {
  const Skeleton s = clipSkeleton(clip);
  Posture p;
  samplePosture(clip, k, p);
  std::vector<glm::mat4> model(s.names.size());
  poseSkeleton(s, p, model);
  std::vector<glm::vec3> out;
  for (const glm::mat4& m : model) out.emplace_back(m[3]);
  return out;
}

// Angle (radians) between two rotations, precise for small angles.
float rotationAngle(const glm::quat& a, const glm::quat& b) {
  const glm::quat d = glm::inverse(a) * b;
  return 2.0f * std::atan2(glm::length(glm::vec3(d.x, d.y, d.z)), std::abs(d.w));
}

// A small clip written here: tabs, a 0-channel joint, an End Site, XZY order.
const std::string kSmall =
    "HIERARCHY\n"
    "ROOT Hips\n"
    "{\n"
    "\tOFFSET 0 0 0\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "\tJOINT Spine\n"
    "\t{\n"
    "\t\tOFFSET 0 10 0\n"
    "\t\tCHANNELS 3 Xrotation Zrotation Yrotation\n"
    "\t\tJOINT Fixed\n"
    "\t\t{\n"
    "\t\t\tOFFSET 0 5 0\n"
    "\t\t\tCHANNELS 0\n"
    "\t\t\tEnd Site\n"
    "\t\t\t{\n"
    "\t\t\t\tOFFSET 0 3 0\n"
    "\t\t\t}\n"
    "\t\t}\n"
    "\t}\n"
    "}\n"
    "MOTION\n"
    "Frames: 3\n"
    "Frame Time: 0.04\n"
    "0 90 0 10 20 30 1 2 3\n"
    "0.5 90 0 11 21 31 2 3 4\n"
    "1 90 0 12 22 32 3 4 5\n";

// kSmall with some lines (1-based) replaced.
std::string smallWithLines(const std::map<int, std::string>& replacements) {
  std::istringstream in(kSmall);
  std::string out, l;
  for (int i = 1; std::getline(in, l); ++i) {
    const auto it = replacements.find(i);
    out += (it == replacements.end() ? l : it->second) + "\n";
  }
  return out;
}
std::string smallWithLine(int line, const std::string& replacement) {
  return smallWithLines({{line, replacement}});
}

std::string crlf(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '\n') out += '\r';
    out += c;
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Every shared clip.

struct SharedClip {
  const char* path;
  float unit_scale;
  const char* map;
};
const SharedClip kSharedClips[] = {
    {"mocap/cmu/01_01.bvh", kCmuUnitMetres, "cmu_01"},
    {"mocap/cmu/131_01.bvh", kCmuUnitMetres, "cmu_131"},
    {"mocap/cmu/131_02.bvh", kCmuUnitMetres, "cmu_131"},
    {"mocap/cmu/scaled_131_03.bvh", 1.0f, "cmu_131"},
    {"mocap/gestures/dataset-1_bow_normal_001.bvh", 0.01f, "bandai_gestures"},
    {"mocap/gestures/dataset-1_call_normal_001.bvh", 0.01f, "bandai_gestures"},
    {"mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh", 0.01f, "bandai_gestures"},
};

class SharedClipTest : public ::testing::TestWithParam<SharedClip> {};

TEST_P(SharedClipTest, ParsesWithTheFilesCounts) {
  VISTEL_REQUIRE_SHARED(path, GetParam().path);
  const std::string text = readText(path);
  const TextCounts counts = countFromText(text);
  Result<MotionClip> clip = parseBvh(text, path);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  EXPECT_EQ(static_cast<int>(clip->joints.size()), counts.joints);
  EXPECT_EQ(clip->channel_count, counts.channels);
  EXPECT_EQ(clip->frame_count, counts.frames);
  EXPECT_EQ(clip->values.size(),
            static_cast<std::size_t>(counts.frames) * static_cast<std::size_t>(counts.channels));
  EXPECT_GT(clip->frame_time, 0.0);
  EXPECT_TRUE(validateSkeleton(clipSkeleton(*clip)).ok());
}

TEST_P(SharedClipTest, InfersUnitsAndStandsPlausibly) {
  VISTEL_REQUIRE_SHARED(path, GetParam().path);
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  EXPECT_NEAR(clip->unit_scale, GetParam().unit_scale, 1e-6f);

  // The naming family's map is the one selected.
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  const Skeleton skeleton = clipSkeleton(*clip);
  Result<const JointMap*> map = selectJointMap(*maps, skeleton);
  ASSERT_TRUE(map.ok()) << map.error().message;
  EXPECT_EQ((*map)->name, GetParam().map);
  const auto at = [&](const std::vector<glm::vec3>& p, std::string_view c) {
    return p[static_cast<std::size_t>(skeleton.find((*map)->jointFor(c)))];
  };

  // First and middle frames: hips 0.8-1.2 m up, head above them, feet below, toes
  // forward of the ankles (forward = left x up, so a left/right mix-up would show).
  for (int k : {0, clip->frame_count / 2}) {
    const std::vector<glm::vec3> p = framePositions(*clip, k);
    const glm::vec3 hips = at(p, "hips");
    EXPECT_GT(hips.y, 0.8f) << "frame " << k;
    EXPECT_LT(hips.y, 1.2f) << "frame " << k;
    EXPECT_GT(at(p, "head").y, hips.y + 0.25f) << "frame " << k;
    const glm::vec3 up = glm::normalize(at(p, "neck") - hips);
    const glm::vec3 left = at(p, "l_thigh") - at(p, "r_thigh");
    const glm::vec3 forward = glm::normalize(glm::cross(left, up));
    for (const char* side : {"l_", "r_"}) {
      const std::string s(side);
      EXPECT_LT(at(p, s + "foot").y, hips.y - 0.6f) << s << " frame " << k;
      EXPECT_GT(glm::dot(glm::normalize(at(p, s + "toes") - at(p, s + "foot")), forward), 0.3f)
          << s << " frame " << k;
    }
  }
}

TEST_P(SharedClipTest, WriteParseRoundTripIsExact) {
  VISTEL_REQUIRE_SHARED(path, GetParam().path);
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  Result<MotionClip> again = parseBvh(writeBvh(*clip), "written.bvh");
  ASSERT_TRUE(again.ok()) << again.error().message;
  ASSERT_EQ(again->joints.size(), clip->joints.size());
  for (std::size_t j = 0; j < clip->joints.size(); ++j) {
    const BvhJoint& a = clip->joints[j];
    const BvhJoint& b = again->joints[j];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.parent, b.parent);
    EXPECT_EQ(a.offset, b.offset);
    EXPECT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.first_channel, b.first_channel);
    EXPECT_EQ(a.end_site, b.end_site);
  }
  EXPECT_EQ(again->frame_count, clip->frame_count);
  EXPECT_EQ(again->frame_time, clip->frame_time);
  EXPECT_EQ(again->unit_scale, clip->unit_scale);
  EXPECT_TRUE(again->values == clip->values);
}

INSTANTIATE_TEST_SUITE_P(AllClips, SharedClipTest, ::testing::ValuesIn(kSharedClips),
                         [](const ::testing::TestParamInfo<SharedClip>& param) {
                           std::string name = param.param.path;
                           name = name.substr(name.rfind('/') + 1);
                           name = name.substr(0, name.find('.'));
                           std::replace_if(
                               name.begin(), name.end(), [](char c) { return !std::isalnum(c); },
                               '_');
                           return name;
                         });

TEST(Bvh, ExplicitUnitsOverrideInference) {
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/131_01.bvh");
  const std::string text = readText(path);
  EXPECT_EQ(parseBvh(text, path, BvhUnits::kCentimetres)->unit_scale, 0.01f);
  EXPECT_EQ(parseBvh(text, path, BvhUnits::kInches)->unit_scale, 0.0254f);
  EXPECT_EQ(parseBvh(text, path, BvhUnits::kMetres)->unit_scale, 1.0f);
  EXPECT_EQ(parseBvh(text, path, BvhUnits::kCmu)->unit_scale, kCmuUnitMetres);
  // The small clip is 18 units tall: CMU units by inference.
  EXPECT_EQ(parseBvh(kSmall, "small.bvh")->unit_scale, kCmuUnitMetres);
}

// ---------------------------------------------------------------------------------------
// Decode every prefix: a prefix that is not a complete file fails cleanly; one that holds
// every value of the last frame parses.

void checkEveryPrefix(const std::string& text, const std::string& name) {
  Result<MotionClip> whole = parseBvh(text, name);
  ASSERT_TRUE(whole.ok()) << whole.error().message;
  const int frames = whole->frame_count;
  // Where the last value begins and ends.
  std::size_t end = text.size();
  while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
  std::size_t begin = end;
  while (begin > 0 && !std::isspace(static_cast<unsigned char>(text[begin - 1]))) --begin;
  int parsed = 0;
  for (std::size_t n = 0; n < text.size(); ++n) {
    Result<MotionClip> clip = parseBvh(std::string_view(text).substr(0, n), name);
    if (clip.ok()) {
      ++parsed;
      EXPECT_GT(n, begin) << "a prefix of " << n << " bytes parsed";
      EXPECT_EQ(clip->frame_count, frames);
    } else {
      EXPECT_EQ(clip.error().message.rfind(name + ":", 0), 0u) << clip.error().message;
      EXPECT_FALSE(n >= end) << "the prefix holding every value failed: " << clip.error().message;
    }
  }
  EXPECT_GE(parsed, 1);
}

TEST(BvhPrefix, SmallClipLfAndCrlf) {
  checkEveryPrefix(kSmall, "small.bvh");
  checkEveryPrefix(crlf(kSmall), "small_crlf.bvh");
}

TEST(BvhPrefix, SharedClipsFirstFrames) {
  for (const char* relative :
       {"mocap/cmu/131_01.bvh", "mocap/gestures/dataset-1_bow_normal_001.bvh"}) {
    VISTEL_REQUIRE_SHARED(path, relative);
    const std::string text = firstFrames(readText(path), 3);
    checkEveryPrefix(text, "first3.bvh");
  }
}

// ---------------------------------------------------------------------------------------
// Malformed input: the error names the source and the line, and says why.

struct Malformed {
  const char* what;
  std::string text;
  int line;
  const char* reason;
};

TEST(BvhMalformed, ErrorsNameTheLineAndTheReason) {
  const std::vector<Malformed> cases = {
      {"missing brace", smallWithLine(20, ""), 21, "missing '}'"},
      {"missing opening brace", smallWithLine(7, ""), 8, "expected '{'"},
      {"bad channel count", smallWithLine(9, "CHANNELS 4 Xrotation Zrotation Yrotation Xposition"),
       9, "4 channels"},
      {"too few channel names", smallWithLine(9, "CHANNELS 3 Xrotation Zrotation"), 10,
       "expected a channel name"},
      {"unknown channel", smallWithLine(9, "CHANNELS 3 Xrotation Wrotation Yrotation"), 9,
       "expected a channel name"},
      {"repeated channel", smallWithLine(9, "CHANNELS 3 Xrotation Xrotation Yrotation"), 9,
       "twice"},
      {"mixed channels", smallWithLine(9, "CHANNELS 3 Xrotation Zrotation Yposition"), 9,
       "position and"},
      {"too few values", smallWithLine(25, "0.5 90 0 11 21 31 2 3"), 25,
       "has 8 values, expected 9"},
      {"too many values", smallWithLine(25, "0.5 90 0 11 21 31 2 3 4 5"), 25, "more than 9 values"},
      {"NaN value", smallWithLine(24, "0 nan 0 10 20 30 1 2 3"), 24, "non-finite"},
      {"overflowing value", smallWithLine(24, "0 1e999 0 10 20 30 1 2 3"), 24, "non-finite"},
      {"infinite offset", smallWithLine(8, "OFFSET 0 inf 0"), 8, "non-finite"},
      {"word in a frame", smallWithLine(26, "1 90 0 12 22 x32 3 4 5"), 26, "not a number"},
      {"huge frame count", smallWithLine(22, "Frames: 99999999999"), 22, "out of range"},
      {"frame count past the text", smallWithLine(22, "Frames: 900000"), 22, "mismatch"},
      {"more frame lines", smallWithLine(22, "Frames: 2"), 26, "more frame lines"},
      {"zero frame time", smallWithLine(23, "Frame Time: 0"), 23, "frame time"},
      {"duplicate joint", smallWithLine(10, "JOINT Spine"), 10, "appears twice"},
      {"second root", smallWithLine(21, "ROOT Other"), 21, "second ROOT"},
      {"misspelt keyword", smallWithLine(12, "OFFSETT 0 5 0"), 12, "unexpected token"},
      {"offset after children", smallWithLine(17, "} OFFSET 1 2 3"), 17, "after its children"},
      {"end site before offset", smallWithLine(12, ""), 14, "before its OFFSET"},
      {"no offset", smallWithLines({{12, ""}, {14, ""}, {15, ""}, {16, ""}, {17, ""}}), 18,
       "no OFFSET"},
      {"garbage", std::string("\x01\x02garbage{{}}\n\xff"), 1, "expected 'HIERARCHY'"},
      {"empty", "", 1, "empty file"},
      {"only whitespace", "\n\n  \t\n", 4, "empty file"},
      {"no MOTION", smallWithLine(21, "MOTON"), 21, "expected 'MOTION'"},
      {"nul byte in a frame", smallWithLine(24, std::string("0 9\0 0 10 20 30 1 2 3", 21)), 24,
       "not a number"},
  };
  for (const Malformed& m : cases) {
    Result<MotionClip> clip = parseBvh(m.text, "small.bvh");
    ASSERT_FALSE(clip.ok()) << m.what;
    const std::string& message = clip.error().message;
    EXPECT_EQ(message.rfind("small.bvh:" + std::to_string(m.line) + ":", 0), 0u)
        << m.what << ": " << message;
    EXPECT_NE(message.find(m.reason), std::string::npos) << m.what << ": " << message;
  }
  // A frame count short of the lines fails on the last line or on the count.
  Result<MotionClip> short_count = parseBvh(smallWithLine(22, "Frames: 4"), "small.bvh");
  ASSERT_FALSE(short_count.ok());
  EXPECT_NE(short_count.error().message.find("mismatch"), std::string::npos);
}

TEST(BvhMalformed, LimitsOnJointsAndNames) {
  // Joints past kBvhMaxJoints: a chain, so the error comes before anything is large.
  std::string deep =
      "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n";
  for (int i = 1; i <= kBvhMaxJoints; ++i) {
    deep += "JOINT j" + std::to_string(i) + "\n{\nOFFSET 0 1 0\n";
  }
  Result<MotionClip> clip = parseBvh(deep, "deep.bvh");
  ASSERT_FALSE(clip.ok());
  EXPECT_NE(clip.error().message.find("more than 1024 joints"), std::string::npos)
      << clip.error().message;
  const std::string long_name = smallWithLine(6, "JOINT " + std::string(300, 'a'));
  clip = parseBvh(long_name, "small.bvh");
  ASSERT_FALSE(clip.ok());
  EXPECT_NE(clip.error().message.find("small.bvh:6:"), std::string::npos);
}

// ---------------------------------------------------------------------------------------
// Channels, rotation order, sampling.

TEST(BvhSample, RotationOrderFollowsTheChannels) {
  Result<MotionClip> clip = parseBvh(kSmall, "small.bvh", BvhUnits::kMetres);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  Posture p;
  samplePosture(*clip, 1, p);
  const auto rot = [](float degrees, glm::vec3 axis) {
    return glm::angleAxis(glm::radians(degrees), axis);
  };
  const glm::vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  // Root: Zrotation Xrotation Yrotation = 11 21 31; Spine: Xrotation Zrotation Yrotation.
  EXPECT_LT(rotationAngle(p.rotations[0], rot(11, z) * rot(21, x) * rot(31, y)), 1e-5f);
  EXPECT_LT(rotationAngle(p.rotations[1], rot(2, x) * rot(3, z) * rot(4, y)), 1e-5f);
  EXPECT_LT(rotationAngle(p.rotations[2], glm::quat(1, 0, 0, 0)), 1e-6f);
  EXPECT_EQ(p.root_translation, glm::vec3(0.5f, 90.0f, 0.0f));
  EXPECT_TRUE(p.translations.empty());
  EXPECT_DOUBLE_EQ(p.time, 0.04);

  // A quarter turn about Z takes the spine's +Y offset to -X.
  const std::string turned = smallWithLine(24, "0 0 0 90 0 0 0 0 0");
  const std::vector<glm::vec3> pos =
      framePositions(*parseBvh(turned, "t.bvh", BvhUnits::kMetres), 0);
  EXPECT_LT(glm::distance(pos[1], glm::vec3(-10, 0, 0)), 1e-4f);
  EXPECT_LT(glm::distance(pos[2], glm::vec3(-15, 0, 0)), 1e-4f);
}

TEST(BvhSample, NonRootPositionChannelsGoToTranslations) {
  VISTEL_REQUIRE_SHARED(path, "mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh");
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  Posture p;
  samplePosture(*clip, 5, p);
  ASSERT_EQ(p.translations.size(), clip->joints.size());
  // Spine's position channels equal its OFFSET (15.7357 cm along X) to file precision.
  const int spine = clipSkeleton(*clip).find("Spine");
  EXPECT_NEAR(p.translations[static_cast<std::size_t>(spine)].x, 0.157357f, 1e-5f);
  // The hips' position comes from the frame, not from the OFFSET.
  const int hips = clipSkeleton(*clip).find("Hips");
  const std::span<const float> v = clip->frame(5);
  const auto first =
      static_cast<std::size_t>(clip->joints[static_cast<std::size_t>(hips)].first_channel);
  EXPECT_NEAR(p.translations[static_cast<std::size_t>(hips)].y, v[first + 1] * 0.01f, 1e-6f);
}

TEST(BvhSample, InterpolationBetweenFrames) {
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/131_01.bvh");
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok());
  Posture a, b, mid, at_frame;
  const int k = 200;
  samplePosture(*clip, k, a);
  samplePosture(*clip, k + 1, b);
  samplePostureAt(*clip, k * clip->frame_time, at_frame);
  samplePostureAt(*clip, (k + 0.5) * clip->frame_time, mid);
  for (std::size_t j = 0; j < a.rotations.size(); ++j) {
    EXPECT_LT(rotationAngle(at_frame.rotations[j], a.rotations[j]), 1e-3f);
    const float ab = rotationAngle(a.rotations[j], b.rotations[j]);
    EXPECT_NEAR(rotationAngle(mid.rotations[j], a.rotations[j]), ab / 2, 1e-3f);
    EXPECT_NEAR(rotationAngle(mid.rotations[j], b.rotations[j]), ab / 2, 1e-3f);
  }
  EXPECT_LT(glm::distance(mid.root_translation, 0.5f * (a.root_translation + b.root_translation)),
            1e-5f);
  // Clamped at both ends.
  Posture first, before;
  samplePosture(*clip, 0, first);
  samplePostureAt(*clip, -1.0, before);
  EXPECT_EQ(before.root_translation, first.root_translation);
  Posture last, after;
  samplePosture(*clip, clip->frame_count - 1, last);
  samplePostureAt(*clip, clip->duration() + 5.0, after);
  EXPECT_LT(glm::distance(after.root_translation, last.root_translation), 1e-6f);
}

// ---------------------------------------------------------------------------------------
// Export of postures.

void expectSamePostures(const MotionClip& clip, std::span<const Posture> postures) {
  ASSERT_EQ(clip.frame_count, static_cast<int>(postures.size()));
  Posture p;
  for (int k = 0; k < clip.frame_count; ++k) {
    samplePosture(clip, k, p);
    const Posture& q = postures[static_cast<std::size_t>(k)];
    ASSERT_EQ(p.rotations.size(), q.rotations.size());
    for (std::size_t j = 0; j < p.rotations.size(); ++j) {
      EXPECT_LT(rotationAngle(p.rotations[j], q.rotations[j]), 2e-4f)
          << "frame " << k << " joint " << j;
    }
    EXPECT_LT(glm::distance(p.root_translation, q.root_translation), 1e-5f);
    if (!q.translations.empty()) {
      ASSERT_EQ(p.translations.size(), q.translations.size());
      for (std::size_t j = 1; j < p.translations.size(); ++j) {
        EXPECT_LT(glm::distance(p.translations[j], q.translations[j]), 1e-5f);
      }
    }
  }
}

TEST(BvhExport, ClipFromPosturesReproducesThem) {
  VISTEL_REQUIRE_SHARED(path, "mocap/cmu/01_01.bvh");
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok());
  const Skeleton skeleton = clipSkeleton(*clip);
  std::vector<Posture> postures;
  for (int k = 0; k < clip->frame_count; k += 97) {
    samplePosture(*clip, k, postures.emplace_back());
  }
  // Gimbal lock of the ZXY order (x = +-90 degrees) must survive too.
  Posture locked = postures.front();
  locked.rotations[3] = glm::angleAxis(glm::radians(90.0f), glm::vec3(1, 0, 0)) *
                        glm::angleAxis(0.3f, glm::vec3(0, 1, 0));
  locked.rotations[4] = glm::angleAxis(glm::radians(-90.0f), glm::vec3(1, 0, 0));
  postures.push_back(locked);

  const MotionClip exported = clipFromPostures(skeleton, postures, 1.0 / 60, 0.01f, "export.bvh");
  EXPECT_EQ(exported.joints.size(), clip->joints.size());
  EXPECT_EQ(exported.channel_count, 6 + 3 * (static_cast<int>(clip->joints.size()) - 1));
  expectSamePostures(exported, postures);
  // And through the text.
  Result<MotionClip> reread = parseBvh(writeBvh(exported), "export.bvh", BvhUnits::kCentimetres);
  ASSERT_TRUE(reread.ok()) << reread.error().message;
  expectSamePostures(*reread, postures);
  // The skeleton's offsets survive in centimetres.
  const Skeleton again = clipSkeleton(*reread);
  for (std::size_t j = 0; j < skeleton.names.size(); ++j) {
    EXPECT_EQ(again.names[j], skeleton.names[j]);
    EXPECT_LT(glm::distance(again.rest_local[j].translation, skeleton.rest_local[j].translation),
              1e-6f);
  }
}

TEST(BvhExport, NonRootTranslationsGetPositionChannels) {
  VISTEL_REQUIRE_SHARED(path, "mocap/gestures/dataset-1_call_normal_001.bvh");
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok());
  std::vector<Posture> postures(3);
  for (int k = 0; k < 3; ++k) samplePosture(*clip, 40 * k, postures[static_cast<std::size_t>(k)]);
  const MotionClip exported =
      clipFromPostures(clipSkeleton(*clip), postures, 1.0 / 30, 0.01f, "e.bvh");
  EXPECT_EQ(exported.channel_count, 6 * static_cast<int>(clip->joints.size()));
  expectSamePostures(exported, postures);
}

TEST(BvhExport, NonDepthFirstSkeletonIsWrittenDepthFirst) {
  // Breadth-first order: root, a, b, a's child, b's child.
  Skeleton s;
  s.names = {"root", "a", "b", "a1", "b1"};
  s.parents = {kNoParent, 0, 0, 1, 2};
  s.rest_local.resize(5);
  s.rest_local[1].translation = {1, 0, 0};
  s.rest_local[2].translation = {-1, 0, 0};
  s.rest_local[3].translation = {0, 1, 0};
  s.rest_local[4].translation = {0, -1, 0};
  computeInverseBind(s);
  Posture p = restPosture(s);
  p.rotations[3] = glm::angleAxis(0.5f, glm::vec3(0, 0, 1));
  p.rotations[2] = glm::angleAxis(-0.25f, glm::vec3(1, 0, 0));
  const MotionClip clip = clipFromPostures(s, std::span(&p, 1), 0.1, 1.0f, "bfs.bvh");
  std::vector<std::string> names;
  for (const BvhJoint& j : clip.joints) names.push_back(j.name);
  EXPECT_EQ(names, (std::vector<std::string>{"root", "a", "a1", "b", "b1"}));
  Result<MotionClip> reread = parseBvh(writeBvh(clip), "bfs.bvh", BvhUnits::kMetres);
  ASSERT_TRUE(reread.ok()) << reread.error().message;
  Posture q;
  samplePosture(*reread, 0, q);
  EXPECT_LT(rotationAngle(q.rotations[2], p.rotations[3]), 1e-5f);  // a1
  EXPECT_LT(rotationAngle(q.rotations[3], p.rotations[2]), 1e-5f);  // b
  EXPECT_TRUE(reread->joints[2].end_site.has_value());
}

}  // namespace
}  // namespace vistel

namespace vistel {
namespace {

// A joint without a CHANNELS line has no channels, and its first channel is where the
// channels before it end (the next joint's start), not 0 (a fuzzer's find).
TEST(Bvh, JointWithoutChannelsStartsAtTheRunningCount) {
  const char* text =
      "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition "
      "Zrotation Xrotation Yrotation\n\tJOINT Leg\n\t{\n\t\tOFFSET 0 -1 0\n\t\tJOINT Foot\n\t\t{\n"
      "\t\t\tOFFSET 0 -1 0\n\t\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\t\t\tEnd Site\n"
      "\t\t\t{\n\t\t\t\tOFFSET 0 0 1\n\t\t\t}\n\t\t}\n\t}\n}\nMOTION\nFrames: 1\n"
      "Frame Time: 0.1\n0 0 0 0 0 0 10 20 30\n";
  Result<MotionClip> clip = parseBvh(text, "no_channels.bvh");
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  ASSERT_EQ(clip->joints.size(), 3u);
  EXPECT_TRUE(clip->joints[1].channels.empty());
  EXPECT_EQ(clip->joints[1].first_channel, 6);
  EXPECT_EQ(clip->joints[2].first_channel, 6);
  EXPECT_EQ(clip->channel_count, 9);
}

}  // namespace
}  // namespace vistel
