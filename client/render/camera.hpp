// Cameras for the room view: framing a set of bodies, a first-person eye, stereo pairs.
// Pure math (no GL). Room space: metres, right-handed, +Y up; avatars face +Z at
// identity placement. Projections follow OpenGL conventions (clip depth -1..1).
#pragma once

#include <span>

#include <glm/glm.hpp>

namespace vistel {

// The camera of one eye in a rendered frame. Pixel coordinates of a room point p:
// c = projection * view * p; x_px = viewport.x + (c.x / c.w * 0.5 + 0.5) * viewport.z;
// y_px (from the bottom) likewise; rows of saved images count from the top
// (row = height - 1 - y_px).
struct EyeCamera {
  glm::mat4 view{1.0f};        // room -> eye
  glm::mat4 projection{1.0f};  // eye -> clip
  glm::ivec4 viewport{0};      // x, y, width, height in framebuffer pixels, origin bottom-left
  glm::vec3 position{0.0f};    // eye position, room space
};

// Where a camera is and where it looks (room space). forward and up are unit length and
// orthogonal.
struct CameraPose {
  glm::vec3 position{0.0f, 1.6f, 3.0f};
  glm::vec3 forward{0.0f, 0.0f, -1.0f};
  glm::vec3 up{0.0f, 1.0f, 0.0f};
};

struct Lens {
  float vertical_fov = 0.8727f;  // radians (50 degrees)
  float near_plane = 0.05f;      // metres
  float far_plane = 100.0f;      // metres
};

// A bounding sphere, room space.
struct Sphere {
  glm::vec3 center{0.0f};
  float radius = 0.0f;
};

// Smallest sphere around an axis-aligned box (its half diagonal).
Sphere sphereAroundBox(const glm::vec3& box_min, const glm::vec3& box_max);

// A camera that sees the whole sphere, looking along `direction` (from the camera
// towards the sphere; need not be unit, must be non-zero and not vertical), with the
// sphere filling at most `fill` (0..1] of the narrower field of view. Sets near/far
// planes around the sphere (far also covers `extra_far` metres beyond it, for the floor).
CameraPose frameSphere(const Sphere& sphere, const glm::vec3& direction, float vertical_fov,
                       float aspect, float fill, Lens& lens, float extra_far = 30.0f);

// The view direction of an orbiting camera: yaw about +Y (0 = looking along -Z, i.e.
// from the +Z side towards the origin), pitch downwards (radians, clamped to +-1.45).
glm::vec3 orbitDirection(float yaw, float pitch);

// Unit forward/up with up re-orthogonalised against forward; falls back to +Y/-Z when
// degenerate.
CameraPose makePose(const glm::vec3& position, const glm::vec3& forward, const glm::vec3& up);

// One eye of a camera: eye_offset metres along the camera's right axis (negative = left
// eye), with an off-axis frustum converging at focal_distance (parallel axes, so both
// eyes' images agree at that distance). eye_offset 0 gives the plain camera.
EyeCamera makeEye(const CameraPose& pose, const Lens& lens, float eye_offset, float focal_distance,
                  const glm::ivec4& viewport);

// Projects a room point through an eye: x, y in framebuffer pixels from the bottom-left,
// z the clip depth (-1..1). Returns false when the point is behind the eye.
bool projectToPixel(const EyeCamera& eye, const glm::vec3& p_room, glm::vec3& out_pixel);

}  // namespace vistel
