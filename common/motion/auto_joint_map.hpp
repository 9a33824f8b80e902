// Joint maps for any humanoid rig: inferred from the joint names (known naming schemes)
// and, where names fail, from the skeleton's topology and rest-pose geometry. The curated
// maps in config/skeletons/*.toml stay overrides: chooseJointMap() takes a fitting one
// first.
//
// Naming schemes (names are normalised first: "mixamorig:", "Armature|", "DEF-", "ORG-"
// prefixes dropped; case and separators ignored; left/right read from "Left"/"Right"
// prefixes, "_l"/".L"/"L_" tokens, or a camel-case "L"/"R" prefix):
//   mixamo (Hips, Spine1, LeftArm, LeftUpLeg, LeftHandThumb1...), vrm (hips, upperChest,
//   leftUpperArm, leftThumbProximal...), unreal (pelvis, spine_01, upperarm_l, calf_l,
//   ball_l... also MakeHuman's game-engine rig), rigify (DEF-spine.001, upper_arm.L,
//   shin.L, f_index.01.L...), cmu_01 / cmu_131 (as config/skeletons/cmu_*.toml), vistel
//   (the canonical names).
// Topology (for what names leave unmapped): hips = the first joint from the root that
// branches into three chains; the spine = its largest child chain up to the next branch of
// three (neck and two arms); up = hips -> top of the spine; legs = the two other hip chains
// that point away from the head; forward = the feet's toe direction (else +Z, or -Y when
// the rig is Z-up); left = up x forward, and left/right by position along it; arms from
// the top of the spine along the longest branch (a joint whose children are all short
// chains is the hand; counted back from it: hand, forearm, upper arm, clavicle); neck and
// head = the fork's child reaching highest (a zero-length first joint skipped; a leaf after
// two or more joints taken as the head's tip); legs counted back from the foot (toes = a
// last bone across the up axis); fingers = the five child chains of a hand, the thumb the
// one that leaves most to the side, the others ordered away from it. Fingers are mapped
// only for hands with exactly five child chains.
// A rig whose names say left for the joints on the body's right (by the rest pose) keeps
// the names' sides; a note says so.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/motion/joint_map.hpp"

namespace vistel {

struct JointMapChoice {
  JointMap map;                     // the chosen map (a copy of a config map, or inferred)
  bool inferred = false;            // true: built by inferJointMap
  std::vector<std::string> origin;  // per map entry (map.canonical order): the config map's
                                    // name, the naming scheme's name, or "topology"
  std::vector<std::string> notes;   // what a user may want to know (sides by names vs pose)
};

// Infers a map for any humanoid skeleton (see the file comment). The map's name is
// "inferred", its required joints kDefaultRequiredJoints. Fails, naming the required
// canonical joints it could not find and why, when the skeleton is not a humanoid (a
// chain, a quadruped). Cost: O(njoint * scheme entries); allocates.
Result<JointMapChoice> inferJointMap(const Skeleton& skeleton);

// The config map selectJointMap() picks when one fits (origin: its name), else the
// inferred one; the error lists both the config candidates and what inference missed.
Result<JointMapChoice> chooseJointMap(std::span<const JointMap> maps, const Skeleton& skeleton);

// An explicit map (e.g. a VRM file's humanoid bones, GltfImportReport::humanoid) made
// complete: its entries are kept as they are (origin: the map's name), the canonical
// joints it leaves out are filled from inferJointMap where inference finds joints the map
// did not take. Fails when an entry names a joint the skeleton lacks or a canonical name
// that does not exist, when a joint is used twice, or when a required joint (the map's,
// else kDefaultRequiredJoints) is still missing. Cost: as inferJointMap.
Result<JointMapChoice> explicitJointMap(const JointMap& explicit_map, const Skeleton& skeleton);

// Human-readable lines: "map: <name> (<source>)" then "  canonical <- joint  [origin]".
std::string describeJointMapChoice(const JointMapChoice& choice);

}  // namespace vistel
