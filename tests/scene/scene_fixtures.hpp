// Small bodies for scene tests: a two-bone skinned tube ("arm") with an implicit model
// built from a three-primitive map, and balls.
#pragma once

#include <memory>

#include <glm/glm.hpp>

#include "common/avatar/avatar_model.hpp"
#include "common/scene/deform_scene.hpp"

namespace vistel::test {

// A tube of radius `radius` along +X: joint "upper" at 0, "fore" at `length`, "tip" at
// 2 * length; skin weights blend across the elbow; an implicit model (two cone-spheres
// and an elbow sphere). Built once per process and shared.
std::shared_ptr<const AvatarModel> tubeAvatar();

// A rigid ball of this radius (or soft with the given stiffness, Pa/m).
std::shared_ptr<const AvatarModel> ballAvatar(float radius, float stiffness = kRigidStiffness);

// Elbow flexion of the tube: the forearm turns about +Z by `angle` radians.
void bendTube(Posture& posture, float angle);

// Translation matrix.
glm::mat4 at(const glm::vec3& position);

}  // namespace vistel::test
