// libFuzzer target: parsePrimitiveMap (offline/build/primitive_map.hpp) on arbitrary TOML
// text. Properties: nothing crashes, throws or reads out of bounds; a rejection names the
// source; an accepted map keeps its promises: global values in range, at least one
// primitive, unique non-empty names and bones, every reference resolved to a primitive of
// the right role (joint: two different limbs; bone: a joint to blend with), no_collide
// naming known primitives, finite materials with a positive time constant.
//
// Seeds: the built-in config/avatars/humanoid.toml (embedded), a generated map with one
// primitive of every role and shape, and tests/fuzz/corpus/primitive_map.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/embedded.hpp"
#include "offline/build/primitive_map.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

constexpr std::string_view kEveryRole = R"(iso = 0.5
diff_exponent = 2
no_collide = [["upper", "hand"]]
[propagation]
amplitude = 0.2
width = 0.3
[material]
density = "piecewise"
stiffness = "rigid"
elasticity = "viscoelastic"
time_constant = 0.25
[[primitive]]
name = "upper"
shape = "sphylinder"
bone = "l_upperarm"
joints = ["l_upperarm"]
from = "l_upperarm"
to = "l_forearm"
[[primitive]]
name = "lower"
shape = "cone_sphere"
bone = "l_forearm"
joints = ["l_forearm"]
[[primitive]]
name = "hand"
shape = "offset_polygon"
bone = "l_hand"
joints = ["l_hand"]
normal = [0.0, 1.0, 0.0]
[[primitive]]
name = "elbow"
role = "joint"
shape = "sphere"
bone = "l_forearm"
at = "l_forearm"
between = ["upper", "lower"]
[[primitive]]
name = "elbow_bone"
role = "bone"
shape = "sphere"
bone = "l_forearm"
at = "l_forearm"
blend = "elbow"
offset = [0.0, 0.0, -1.0]
depth = 0.5
reach = 1.2
collides = false
elasticity = "plastic"
)";

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  if (const auto builtin = embeddedConfig("avatars/humanoid.toml")) {
    seeds.push_back(fuzz::textSeed("builtin_humanoid.toml", *builtin));
  }
  seeds.push_back(fuzz::textSeed("gen_every_role.toml", kEveryRole));
  for (const fuzz::Seed& seed : seeds) {
    const auto parsed = parsePrimitiveMap(fuzz::textOf(seed), seed.name);
    check(parsed.ok(), "a seed map parses");
  }
  return seeds;
}

void checkMaterial(const Material& m) {
  check(std::isfinite(m.time_constant) && m.time_constant > 0.0f, "material time constant > 0");
  check(!std::isnan(m.stiffness) && m.stiffness > 0.0f, "material stiffness > 0");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const Result<PrimitiveMapSpec> map = parsePrimitiveMap(text, "fuzz.toml");
  if (!map.ok()) {
    fuzz::checkRejection(map.error().message);
    return 0;
  }

  // Global values.
  check(map->iso > 0.0f && map->iso < 1.0f, "iso in (0, 1)");
  check(map->diff_exponent >= 1 && map->diff_exponent <= 8, "diff_exponent 1..8");
  check(map->joint_weight > 0.0f && map->joint_weight < 0.5f, "joint_weight in (0, 0.5)");
  check(map->limb_weight > 0.0f && map->limb_weight <= 1.0f, "limb_weight in (0, 1]");
  check(map->propagation_width > 0.0f && map->propagation_width < map->iso &&
            map->propagation_amplitude >= 0.0f && std::isfinite(map->propagation_amplitude),
        "propagation in range");
  checkMaterial(map->material);

  // Primitives: unique names, resolved references of the right roles.
  check(!map->primitives.empty(), "at least one primitive");
  std::set<std::string> names;
  for (const PrimitiveSpec& p : map->primitives) {
    check(!p.name.empty() && !p.bone.empty(), "a primitive has a name and a bone");
    check(names.insert(p.name).second, "primitive names are unique");
    check(map->find(p.name) == &p, "find() returns the primitive");
    checkMaterial(p.material);
    check(std::isfinite(p.depth) && std::isfinite(p.reach), "finite depth and reach");
    if (p.role == PrimitiveRole::kJoint) {
      const PrimitiveSpec* a = map->find(p.between[0]);
      const PrimitiveSpec* b = map->find(p.between[1]);
      check(a != nullptr && b != nullptr && a != b && a->role == PrimitiveRole::kLimb &&
                b->role == PrimitiveRole::kLimb,
            "a joint primitive joins two different limbs");
    }
    if (p.role == PrimitiveRole::kBone) {
      const PrimitiveSpec* joint = map->find(p.blend);
      check(joint != nullptr && joint->role == PrimitiveRole::kJoint && p.offset.has_value(),
            "a bone primitive blends with a joint primitive along an offset");
    }
    if (p.offset) {
      check(std::isfinite(p.offset->x) && std::isfinite(p.offset->y) && std::isfinite(p.offset->z),
            "finite offsets");
    }
  }
  for (const auto& pair : map->no_collide) {
    check(map->find(pair[0]) != nullptr && map->find(pair[1]) != nullptr,
          "no_collide names known primitives");
  }
  return 0;
}
