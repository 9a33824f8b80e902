// libFuzzer target: parseBvh (common/motion/bvh.hpp) on arbitrary text. Properties: nothing
// crashes, hangs or reads out of bounds; a rejection says "source:line: reason"; an
// accepted clip keeps the header's invariants (parents first, channel bookkeeping, finite
// values, frame_time > 0), its skeleton validates, every frame samples, and
// writeBvh -> parseBvh gives back the same hierarchy, channels and values exactly.
//
// Seeds: clips written by writeBvh from small generated postures, plus the hand-written
// files in tests/fuzz/corpus/bvh; bvh.dict lists the format's words.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/motion/bvh.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

bool sameBits(const glm::vec3& a, const glm::vec3& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A chain of `joints` joints up +Y with a few postures (rotations about all three axes;
// non-root translations when asked), as a BVH clip.
std::string generatedClip(int joints, int frames, bool translations, float unit_scale) {
  Skeleton s;
  for (int j = 0; j < joints; ++j) {
    s.names.push_back("joint" + std::to_string(j));
    s.parents.push_back(j - 1);
    Transform t;
    t.translation = glm::vec3(0.0f, j == 0 ? 0.9f : 0.2f, j % 2 ? 0.01f : 0.0f);
    s.rest_local.push_back(t);
  }
  computeInverseBind(s);
  std::vector<Posture> postures;
  for (int f = 0; f < frames; ++f) {
    Posture p = restPosture(s);
    p.root_translation += glm::vec3(0.01f * f, 0.0f, -0.02f * f);
    for (int j = 0; j < joints; ++j) {
      p.rotations[static_cast<std::size_t>(j)] =
          glm::angleAxis(0.1f * static_cast<float>(f + j), glm::normalize(glm::vec3(1, 2, 3)));
    }
    if (translations)
      p.translations.assign(static_cast<std::size_t>(joints), glm::vec3(0, 0.2f, 0));
    postures.push_back(std::move(p));
  }
  return writeBvh(clipFromPostures(s, postures, 1.0 / 30.0, unit_scale, "generated"));
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds = {
      fuzz::textSeed("gen_1joint.bvh", generatedClip(1, 1, false, 1.0f)),
      fuzz::textSeed("gen_chain_cm.bvh", generatedClip(4, 3, false, 0.01f)),
      fuzz::textSeed("gen_chain_cmu.bvh", generatedClip(3, 2, false, kCmuUnitMetres)),
      fuzz::textSeed("gen_translations.bvh", generatedClip(3, 2, true, 1.0f)),
  };
  for (const fuzz::Seed& seed : seeds) {
    check(parseBvh(fuzz::textOf(seed), seed.name).ok(), "a seed clip parses");
  }
  return seeds;
}

// The invariants of an accepted clip (bvh.hpp).
void checkClip(const MotionClip& clip) {
  check(!clip.joints.empty() && clip.joints.size() <= kBvhMaxJoints, "joint count in range");
  check(clip.joints[0].parent == kNoParent, "joint 0 is the root");
  int channels = 0;
  for (std::size_t j = 0; j < clip.joints.size(); ++j) {
    const BvhJoint& joint = clip.joints[j];
    check(j == 0 || (joint.parent >= 0 && joint.parent < static_cast<int>(j)),
          "parents precede children");
    check(!joint.name.empty() && joint.name.size() <= kBvhMaxNameLength, "joint name length");
    const std::size_t n = joint.channels.size();
    check(n == 0 || n == 3 || n == 6, "0, 3 or 6 channels");
    check(joint.first_channel == channels, "first_channel is the running channel count");
    channels += static_cast<int>(n);
  }
  check(clip.channel_count == channels, "channel_count sums the joints' channels");
  check(clip.frame_count >= 0 && clip.frame_count <= kBvhMaxFrames, "frame count in range");
  check(clip.values.size() ==
            static_cast<std::size_t>(clip.frame_count) * static_cast<std::size_t>(channels),
        "values has frame_count * channel_count entries");
  for (float v : clip.values) check(std::isfinite(v), "values are finite");
  check(std::isfinite(clip.frame_time) && clip.frame_time > 0.0, "frame_time > 0");
  check(std::isfinite(clip.unit_scale) && clip.unit_scale > 0.0f, "unit_scale > 0");
}

// Sampling: the skeleton validates, frames and times give postures of the right size.
void checkSampling(const MotionClip& clip) {
  const Skeleton skeleton = clipSkeleton(clip);
  check(validateSkeleton(skeleton).ok(), "clipSkeleton validates");
  Posture posture;
  if (clip.frame_count > 0) {
    samplePosture(clip, 0, posture);
    check(posture.rotations.size() == clip.joints.size(), "a posture per joint");
    samplePosture(clip, clip.frame_count - 1, posture);
    samplePostureAt(clip, 0.5 * clip.duration(), posture);
    samplePostureAt(clip, -1.0, posture);
    samplePostureAt(clip, clip.duration() + 1.0, posture);
    check(posture.rotations.size() == clip.joints.size(), "a posture per joint");
  }
}

// writeBvh -> parseBvh is exact for the hierarchy, channels and values.
void checkRoundTrip(const MotionClip& clip) {
  const std::string text = writeBvh(clip);
  Result<MotionClip> again = parseBvh(text, "rewritten.bvh", BvhUnits::kMetres);
  if (!again.ok()) {
    std::fprintf(stderr, "%s\n", again.error().message.c_str());
    check(false, "parseBvh accepts writeBvh's text");
  }
  check(again->joints.size() == clip.joints.size(), "round trip: joint count");
  for (std::size_t j = 0; j < clip.joints.size(); ++j) {
    const BvhJoint& a = clip.joints[j];
    const BvhJoint& b = again->joints[j];
    check(a.name == b.name && a.parent == b.parent, "round trip: names and parents");
    check(sameBits(a.offset, b.offset), "round trip: offsets exact");
    check(a.channels == b.channels && a.first_channel == b.first_channel, "round trip: channels");
    check(a.end_site.has_value() == b.end_site.has_value(), "round trip: end sites");
    if (a.end_site) check(sameBits(*a.end_site, *b.end_site), "round trip: end site exact");
  }
  check(again->frame_count == clip.frame_count, "round trip: frame count");
  check(std::memcmp(again->values.data(), clip.values.data(), clip.values.size() * sizeof(float)) ==
            0,
        "round trip: values exact");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Result<MotionClip> clip = parseBvh(text, "fuzz.bvh");
  if (!clip.ok()) {
    check(clip.error().message.starts_with("fuzz.bvh:"), "a rejection names source:line");
    return 0;
  }
  checkClip(*clip);
  checkSampling(*clip);
  checkRoundTrip(*clip);
  return 0;
}
