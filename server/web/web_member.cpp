#include "server/web/web_member.hpp"

#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

namespace vistel::server {
namespace {

constexpr double kHalfPi = 1.5707963267948966;

// The finite number `key` of `j`, within ±limit; the error names the key.
Result<double> numberOf(const nlohmann::json& j, const char* key, double limit) {
  auto it = j.find(key);
  if (it == j.end()) return fail("\"{}\" is missing", key);
  if (!it->is_number()) return fail("\"{}\" is not a number", key);
  const double v = it->get<double>();
  if (!std::isfinite(v)) return fail("\"{}\" is not finite", key);
  if (std::abs(v) > limit) return fail("\"{}\" = {} is beyond ±{}", key, v, limit);
  return v;
}

// An axis-aligned box (24 vertices, flat normals, 12 triangles, counter-clockwise seen
// from outside), bound wholly to `joint`.
void addBox(SkinMesh& skin, glm::vec3 centre, glm::vec3 half, std::uint16_t joint) {
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int a = 0; a < 3; ++a) {
    for (float sign : {1.0f, -1.0f}) {
      const glm::vec3 n = axes[a] * sign;
      const glm::vec3 u = axes[(a + 1) % 3] * sign;
      const glm::vec3 v = axes[(a + 2) % 3];
      // u x v = n, so (c - u - v, c + u - v, c + u + v, c - u + v) turns counter-clockwise
      // seen from outside.
      const auto base = static_cast<std::uint32_t>(skin.positions.size());
      const glm::vec3 c = centre + n * half;
      const glm::vec3 du = u * half, dv = v * half;
      for (const glm::vec3& p : {c - du - dv, c + du - dv, c + du + dv, c - du + dv}) {
        skin.positions.push_back(p);
        skin.normals.push_back(n);
        for (int k = 0; k < skin.influences; ++k) {
          skin.joints.push_back(k == 0 ? joint : 0);
          skin.weights.push_back(k == 0 ? 1.0f : 0.0f);
        }
      }
      for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) skin.indices.push_back(base + i);
    }
  }
}

AvatarMaterial material(const char* name, glm::vec3 colour, float roughness) {
  AvatarMaterial m;
  m.name = name;
  m.base_color = glm::vec4(colour, 1.0f);
  m.roughness = roughness;
  return m;
}

}  // namespace

Result<SpectatorMessage> parseSpectatorMessage(std::string_view text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  if (j.is_discarded()) return fail("not JSON");
  if (!j.is_object()) return fail("not a JSON object");
  auto type = j.find("type");
  if (type == j.end() || !type->is_string()) return fail("no \"type\" string");
  const std::string& t = type->get_ref<const std::string&>();
  SpectatorMessage out;
  if (t == "join") {
    out.kind = SpectatorMessage::Kind::kJoin;
    if (auto name = j.find("name"); name != j.end() && !name->is_null()) {
      if (!name->is_string()) return fail("\"name\" is not a string");
      out.name = name->get<std::string>();
    }
    return out;
  }
  if (t == "leave") {
    out.kind = SpectatorMessage::Kind::kLeave;
    return out;
  }
  if (t != "pose") return fail("unknown type \"{}\"", t.substr(0, 32));
  out.kind = SpectatorMessage::Kind::kPose;
  auto x = numberOf(j, "x", kMaxPoseDistanceM);
  if (!x) return x.error();
  auto y = numberOf(j, "y", kMaxPoseDistanceM);
  if (!y) return y.error();
  auto z = numberOf(j, "z", kMaxPoseDistanceM);
  if (!z) return z.error();
  auto yaw = numberOf(j, "yaw", 1e6);
  if (!yaw) return yaw.error();
  auto pitch = numberOf(j, "pitch", kHalfPi + 1e-6);
  if (!pitch) return pitch.error();
  out.pose = {*x, *y, *z, std::remainder(*yaw, 2.0 * 3.141592653589793), *pitch};
  return out;
}

std::string spectatorMemberName(std::string_view requested, std::uint64_t serial) {
  std::string kept;
  for (char c : requested) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '-' || c == '_' || c == '.' || c == ' ';
    if (!ok || (c == ' ' && (kept.empty() || kept.back() == ' '))) continue;
    if (kept.size() == kMaxSpectatorNameChars) break;
    kept.push_back(c);
  }
  while (!kept.empty() && kept.back() == ' ') kept.pop_back();
  if (kept.empty()) return fmt::format("spectator-{}", serial);
  return kept + " (spectator)";
}

AvatarModel makeSpectatorAvatar() {
  AvatarModel a;
  a.name = "vistel-spectator";
  Skeleton& s = a.skeleton;
  s.names = {"hips", "head"};
  s.parents = {kNoParent, 0};
  s.rest_local.resize(2);
  s.rest_local[0].translation = {0.0f, 1.0f, 0.0f};
  s.rest_local[1].translation = {0.0f, kSpectatorHeadHeightM, 0.0f};
  computeInverseBind(s);

  SkinMesh& skin = a.skin;
  skin.influences = 4;
  AvatarLook& look = a.look;
  look.materials = {material("spectator body", {0.30f, 0.34f, 0.40f}, 0.8f),
                    material("spectator camera", {0.08f, 0.08f, 0.09f}, 0.4f),
                    material("spectator lens", {0.15f, 0.35f, 0.75f}, 0.1f)};
  auto run = [&](int m, auto&& add) {
    const auto first = static_cast<std::uint32_t>(skin.indices.size());
    add();
    look.submeshes.push_back({first, static_cast<std::uint32_t>(skin.indices.size()) - first, m});
  };
  // Body (hips): torso, shoulders, two legs down to the floor.
  run(0, [&] {
    addBox(skin, {0.0f, 1.2f, 0.0f}, {0.17f, 0.25f, 0.10f}, 0);
    addBox(skin, {0.0f, 1.47f, 0.0f}, {0.05f, 0.05f, 0.05f}, 0);  // neck
    addBox(skin, {0.09f, 0.47f, 0.0f}, {0.065f, 0.47f, 0.07f}, 0);
    addBox(skin, {-0.09f, 0.47f, 0.0f}, {0.065f, 0.47f, 0.07f}, 0);
  });
  // Camera (head): the body around the head joint and a viewfinder on top.
  run(1, [&] {
    addBox(skin, {0.0f, 1.6f, -0.03f}, {0.13f, 0.10f, 0.12f}, 1);
    addBox(skin, {0.0f, 1.73f, -0.08f}, {0.04f, 0.03f, 0.05f}, 1);
  });
  // Lens toward +Z (the way it looks).
  run(2, [&] { addBox(skin, {0.0f, 1.6f, 0.15f}, {0.06f, 0.06f, 0.06f}, 1); });
  return a;
}

Posture spectatorPosture(const SpectatorPose& pose, float seat_x, float seat_z, float seat_yaw) {
  Posture p;
  const glm::vec3 up(0.0f, 1.0f, 0.0f);
  const glm::quat unseat = glm::angleAxis(-seat_yaw, up);
  const glm::vec3 room(static_cast<float>(pose.x), static_cast<float>(pose.y),
                       static_cast<float>(pose.z));
  const glm::vec3 model = unseat * (room - glm::vec3(seat_x, 0.0f, seat_z));
  p.root_translation = model - glm::vec3(0.0f, kSpectatorHeadHeightM, 0.0f);
  p.rotations = {glm::angleAxis(static_cast<float>(pose.yaw) - seat_yaw, up),
                 glm::angleAxis(-static_cast<float>(pose.pitch), glm::vec3(1.0f, 0.0f, 0.0f))};
  return p;
}

}  // namespace vistel::server
