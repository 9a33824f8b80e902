// libFuzzer target: parseJointMap (common/motion/joint_map.hpp) on arbitrary TOML text.
// Properties: nothing crashes or reads out of bounds (toml++ exceptions stay inside); a
// rejection names the source; an accepted map has entries in canonical order with
// non-empty, distinct skeleton names, every required joint among them, and
// selectJointMap picks it for a skeleton made of exactly its joint names.
//
// Seeds: the built-in maps (config/skeletons, embedded) and a generated map naming every
// canonical joint, plus tests/fuzz/corpus/joint_map; joint_map.dict lists keys and names.
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "common/anim/skeleton.hpp"
#include "common/base/embedded.hpp"
#include "common/motion/joint_map.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  for (const EmbeddedFile& f : embeddedFiles()) {
    if (!f.path.starts_with("skeletons/") || !f.path.ends_with(".toml")) continue;
    seeds.push_back(fuzz::textSeed("builtin_" + std::string(f.path.substr(10)), f.data));
  }
  std::string all = "name = \"every_joint\"\nrequired = [\"hips\", \"head\"]\n[joints]\n";
  for (std::string_view c : canonicalJoints()) {
    all += std::string(c) + " = \"J_" + std::string(c) + "\"\n";
  }
  seeds.push_back(fuzz::textSeed("gen_every_joint.toml", all));
  for (const fuzz::Seed& seed : seeds) {
    check(parseJointMap(fuzz::textOf(seed), seed.name).ok(), "a seed map parses");
  }
  return seeds;
}

// A chain skeleton whose joints are the map's skeleton names (only the names matter to
// selectJointMap).
Skeleton skeletonOf(const JointMap& map) {
  Skeleton s;
  for (std::size_t i = 0; i < map.joint.size(); ++i) {
    s.names.push_back(map.joint[i]);
    s.parents.push_back(static_cast<int>(i) - 1);
    s.rest_local.emplace_back();
  }
  computeInverseBind(s);
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  Result<JointMap> map = parseJointMap(text, "fuzz.toml");
  if (!map.ok()) {
    check(map.error().message.starts_with("fuzz.toml"), "a rejection names the source");
    return 0;
  }

  // Entries: canonical order, distinct non-empty skeleton names.
  check(!map->canonical.empty() && map->canonical.size() == map->joint.size(),
        "one skeleton name per canonical entry");
  int previous = -1;
  std::set<std::string> names;
  for (std::size_t i = 0; i < map->canonical.size(); ++i) {
    const int index = canonicalIndex(map->canonical[i]);
    check(index > previous, "entries are canonical names in canonical order");
    previous = index;
    check(!map->joint[i].empty(), "skeleton names are non-empty");
    check(names.insert(map->joint[i]).second, "skeleton names are distinct");
    check(map->jointFor(map->canonical[i]) == map->joint[i], "jointFor finds each entry");
  }
  for (const std::string& r : map->required) {
    check(canonicalIndex(r) >= 0 && !map->jointFor(r).empty(), "required joints are mapped");
  }

  // A skeleton with exactly the map's names selects it.
  const Skeleton skeleton = skeletonOf(*map);
  check(validateSkeleton(skeleton).ok(), "the map's names make a valid skeleton");
  const std::vector<JointMap> maps{*map};
  Result<const JointMap*> selected = selectJointMap(maps, skeleton);
  check(selected.ok() && *selected == &maps[0], "selectJointMap picks the map");
  return 0;
}
