// Test-only: the skin skeleton of a .glb, read from its JSON chunk (names, parents, rest
// TRS), so that retargeting can be tested on the shared MakeHuman avatar without the
// offline glTF importer.
#pragma once

#include <string>

#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"

namespace vistel::test {

// The first skin's joints, parents first (depth first from the scene), rest_local from
// each node's translation/rotation/scale, inverse_bind computed. Errors name the path.
Result<Skeleton> loadGlbSkeleton(const std::string& path);

}  // namespace vistel::test
