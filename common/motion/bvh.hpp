// BVH motion clips: parsing, sampling as postures, writing.
//
// A clip keeps the file's hierarchy, channels and values (in file units); its skeleton
// and postures are in metres through unit_scale. Parsing is strict and never trusts
// the input: a malformed file gives an Error naming the source, the line and the reason.
//
// Conventions (the usual BVH ones): a joint's local transform is T(offset or its position
// channels) * R, where R is the product of its rotation channels in file order
// (R = R_first * R_second * R_third, angles in degrees). The zero pose (every rotation
// 0, every joint at its OFFSET) is the clip skeleton's rest pose.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"

namespace vistel {

enum class BvhChannel : std::uint8_t {
  kXposition,
  kYposition,
  kZposition,
  kXrotation,
  kYrotation,
  kZrotation
};

struct BvhJoint {
  std::string name;
  int parent = kNoParent;             // index into MotionClip::joints; parents first
  glm::vec3 offset{0.0f};             // file units
  std::vector<BvhChannel> channels;   // 0, 3 or 6 channels, in file order
  int first_channel = 0;              // index of channels[0] within a frame's values
  std::optional<glm::vec3> end_site;  // End Site offset (file units), if present
};

// How to turn file units into metres.
enum class BvhUnits { kAuto, kMetres, kCentimetres, kInches, kCmu };

// Metres per "CMU unit" (the CMU database's BVH exports: 1/0.45 inch).
inline constexpr float kCmuUnitMetres = 0.0254f / 0.45f;

// Limits a parsed file must respect, so that a hostile file cannot make the parser
// allocate without bound (the values array is also capped by the text's own size).
inline constexpr int kBvhMaxJoints = 1024;
inline constexpr int kBvhMaxFrames = 1'000'000;
inline constexpr std::size_t kBvhMaxNameLength = 256;

struct MotionClip {
  std::string source;            // file name, for messages
  std::vector<BvhJoint> joints;  // hierarchy order (parents precede children)
  int channel_count = 0;         // values per frame
  int frame_count = 0;
  double frame_time = 0.0;    // seconds per frame (> 0)
  std::vector<float> values;  // frame_count * channel_count, file units/degrees
  float unit_scale = 1.0f;    // metres per file unit

  double duration() const { return frame_time * frame_count; }
  std::span<const float> frame(int k) const {
    return {values.data() + static_cast<std::size_t>(k) * channel_count,
            static_cast<std::size_t>(channel_count)};
  }
};

// Parses BVH text (tabs or spaces, CRLF or LF, any rotation order, 0, 3 or 6 channels per
// joint, End Sites). units = kAuto picks metres, centimetres or CMU units (see
// bvhUnitScale) from the skeleton's size. Errors ("source:line: reason") for: unexpected
// or missing tokens and braces, bad channel lists, non-numeric or non-finite numbers,
// frame lines with the wrong number of values, fewer or more frame lines than "Frames:",
// and sizes past the kBvhMax* limits. Cost: linear in the text.
Result<MotionClip> parseBvh(std::string_view text, std::string_view source_name,
                            BvhUnits units = BvhUnits::kAuto);
// Reads and parses a file (at most 512 MiB); errors name the path.
Result<MotionClip> loadBvh(const std::string& path, BvhUnits units = BvhUnits::kAuto);

// Metres per file unit for explicit units. For kAuto, from the largest extent E (along
// any axis) of the zero pose, end sites included: E < 5 -> metres; 5 <= E < 60 -> CMU
// units (a 1.7 m person is ~30 units); E >= 60 -> centimetres.
float bvhUnitScale(const MotionClip& clip, BvhUnits units);

// BVH text of a clip (tabs, LF; numbers in their shortest round-trip form, so parseBvh of
// the text gives back the same hierarchy, channels and values exactly). Joints are written
// depth first; a clip whose joint order is not depth first is written consistently.
std::string writeBvh(const MotionClip& clip);

// The clip's skeleton in metres: rest = the zero pose (identity rotations, translations =
// OFFSETs * unit_scale), joint order and names as in the file, end sites not included.
// inverse_bind is computed from it.
Skeleton clipSkeleton(const MotionClip& clip);

// The posture of frame k (0 <= k < frame_count) on clipSkeleton(clip), in metres; out
// is resized once and reused (no allocation afterwards). Position channels give the
// joint's local translation (they replace the OFFSET, as in the files in use); for
// non-root joints they go to Posture::translations, which stays empty when no non-root
// joint has them. time = k * frame_time.
void samplePosture(const MotionClip& clip, int frame, Posture& out);
// Interpolated posture at time t seconds (clamped to [0, (frame_count - 1) * frame_time]):
// slerp of rotations, lerp of translations between the two nearest frames. No allocation
// once out has its size.
void samplePostureAt(const MotionClip& clip, double t, Posture& out);

// A clip with the given skeleton's hierarchy (depth-first order; offsets = rest
// translations / unit_scale, in file units) whose frames are the given postures: 6
// channels (XYZ position, ZXY rotation) on the root and 3 rotation channels (ZXY order) on
// every other joint, or 6 when the postures carry non-root translations. A posture's
// local rotations become the channels directly, so the clip's zero pose has identity
// rotations (equal to the skeleton's rest only when its rest rotations are identity).
// Leaf joints get an End Site half as long as their own bone, along it.
// Preconditions: every posture has skeleton.jointCount() rotations; frame_time > 0.
MotionClip clipFromPostures(const Skeleton& skeleton, std::span<const Posture> postures,
                            double frame_time, float unit_scale, std::string source_name);

}  // namespace vistel
