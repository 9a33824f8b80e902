// Joint-name maps: how one skeleton's joints correspond to vistel's canonical humanoid
// joints. Kept in config/skeletons/*.toml (one file per naming family), compiled in as
// defaults. Used to retarget clips onto avatars and to find body parts by role.
//
// File format (TOML):
//   name = "cmu_131"                 # optional; default: the file's stem
//   description = "..."              # optional
//   required = ["hips", ...]         # optional; default: kDefaultRequiredJoints
//   [joints]
//   hips = "Hips"                    # canonical name = that skeleton's joint name
//   l_upperarm = "LeftShoulder"
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"

namespace vistel {

// The canonical humanoid joints (52), in hierarchy order (parents precede children):
// hips, spine, chest, upper_chest, neck, head, l_clavicle, l_upperarm, l_forearm, l_hand,
// l_thumb1..3, l_index1..3, l_middle1..3, l_ring1..3, l_pinky1..3, the same for r_, then
// l_thigh, l_shin, l_foot, l_toes, r_thigh, r_shin, r_foot, r_toes. A map need not name
// all of them.
std::span<const std::string_view> canonicalJoints();
// Parent of each canonical joint (index into canonicalJoints(); -1 for hips).
std::span<const int> canonicalParents();
// Index of a canonical name in canonicalJoints(), or -1.
int canonicalIndex(std::string_view name);

// The joints a map must name (and a skeleton must have) to be selected and to retarget.
inline constexpr std::string_view kDefaultRequiredJoints[] = {
    "hips",      "spine",   "head",   "l_upperarm", "l_forearm", "r_upperarm",
    "r_forearm", "l_thigh", "l_shin", "r_thigh",    "r_shin"};

struct JointMap {
  std::string name;                    // e.g. "cmu_131"
  std::string source;                  // file it came from, for messages
  std::vector<std::string> canonical;  // canonical joint name per entry (canonical order)
  std::vector<std::string> joint;      // that skeleton's joint name per entry
  std::vector<std::string> required;   // canonical names a skeleton must have for this map

  // The skeleton's name for a canonical joint, or empty.
  std::string_view jointFor(std::string_view canonical_name) const;
};

// Parses a map's TOML text; errors name the source, the line, the key and the reason
// (TOML syntax, unknown key or canonical name, a skeleton joint named twice, a non-string
// or empty value, a required joint the map does not name).
Result<JointMap> parseJointMap(std::string_view toml_text, std::string_view source_name);

// Every map in <config_dir>/skeletons/*.toml, sorted by file name: the disk folder when it
// exists, else the embedded copies of config/skeletons (config_dir is then only used in
// messages). Fails on the first bad file, naming it.
Result<std::vector<JointMap>> loadJointMaps(const std::string& config_dir = "config");

// The map naming most of the skeleton's joints among those whose required joints the
// skeleton all has (ties: the larger share of the map's entries found, then the first);
// an error listing every candidate's coverage and missing joints when none fits. The
// result points into `maps`.
Result<const JointMap*> selectJointMap(std::span<const JointMap> maps, const Skeleton& skeleton);

}  // namespace vistel
