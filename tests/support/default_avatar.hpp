// The project's default avatar with its implicit model, built from
// config/avatars/humanoid.toml once per process (about a second in Release).
#pragma once

#include <memory>

#include "common/avatar/avatar_model.hpp"

namespace vistel::test {

// Null (and a test failure recorded) when the build fails.
std::shared_ptr<const AvatarModel> defaultAvatarWithModel();

}  // namespace vistel::test
