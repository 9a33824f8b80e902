// Test helper: a recorded room without a session. Two members sharing the synthetic
// avatar (tests/net/synthetic_avatar.hpp) — "alice" shown throughout, waving; "bob" joining
// at 1 s, away from 2 s to 2.5 s, leaving at 3 s — and a ball falling from 0.5 s on, over
// 4 s at 60 Hz.
#pragma once

#include <cmath>
#include <memory>

#include "client/net/prop_models.hpp"
#include "common/record/room_recorder.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel::test {

inline record::RoomRecording syntheticRecording() {
  auto avatar = std::make_shared<const AvatarModel>(makeSyntheticAvatar("synthetic"));
  record::RoomRecording rec;
  const float rot_tol = 0.004f, pos_tol = 0.0005f;
  for (const char* name : {"alice", "bob"}) {
    record::RecordedMember& m = rec.members.emplace_back();
    m.name = name;
    m.avatar_hash = "hash";
    m.avatar = avatar;
    m.seat_translation = record::Vec3Track(pos_tol);
    m.seat_rotation = record::QuatTrack(rot_tol);
    m.root_translation = record::Vec3Track(pos_tol);
    m.rotations.assign(5, record::QuatTrack(rot_tol));
  }
  record::RecordedProp& ball = rec.props.emplace_back();
  ball.id = 7;
  ball.name = "ball 1";
  ball.position = record::Vec3Track(pos_tol);
  ball.model = net::PropModels().ball(ball.ball);
  rec.members[0].spans = {{0.0, 4.0}};
  rec.members[1].spans = {{1.0, 2.0}, {2.5, 3.0}};
  ball.spans = {{0.5, 4.0}};
  for (int i = 0; i <= 240; ++i) {
    const double t = i / 60.0;
    for (std::size_t k = 0; k < 2; ++k) {
      record::RecordedMember& m = rec.members[k];
      const bool shown = k == 0 || (t >= 1.0 && t < 2.0) || (t >= 2.5 && t < 3.0);
      if (!shown) continue;
      const Posture p = syntheticPosture(t + static_cast<double>(k));
      const float x = k == 0 ? -1.0f : 1.0f;
      m.seat_translation.add(t, glm::vec3(x, 0.0f, 0.0f));
      m.seat_rotation.add(t, glm::angleAxis(x * 1.5f, glm::vec3(0.0f, 1.0f, 0.0f)));
      m.root_translation.add(t, p.root_translation);
      for (std::size_t j = 0; j < 5; ++j) m.rotations[j].add(t, p.rotations[j]);
      if (k == 1 && (i == 119 || i == 179)) {  // its last samples before leaving
        m.seat_translation.cut();
        m.seat_rotation.cut();
        m.root_translation.cut();
        for (auto& r : m.rotations) r.cut();
      }
    }
    if (t >= 0.5) {
      const auto fall = static_cast<float>(t - 0.5);
      ball.position.add(t, glm::vec3(0.0f, std::max(0.2f, 3.0f - 4.9f * fall * fall), 0.0f));
    }
  }
  rec.duration_s = 4.0;
  rec.samples = 241;
  return rec;
}

}  // namespace vistel::test
