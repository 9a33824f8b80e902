// RoomRecorder fed by a client's session (client/record sampleSession) over an in-process session
// (tests/net/sim_network.hpp, fake clock): a viewer records two members sending the synthetic wave,
// itself at rest, and a member who joins at 1 s and drops at 2 s. Spans follow who was shown,
// moving joints have keys within the tolerance of what the viewer's jitter buffer showed, constant
// ones collapse, and the export holds every member.
#include "common/record/room_recorder.hpp"

#include <algorithm>
#include <array>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "client/record/session_sampling.hpp"
#include "common/record/room_glb.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel::record {
namespace {

struct QuietLogs {
  QuietLogs() { spdlog::set_level(spdlog::level::warn); }
} quiet_logs;

TEST(RoomRecorder, RecordsWhoWasShownAndHowTheyMoved) {
  server::ServerConfig config;
  config.tick_rate_hz = 60.0;
  test::SimNetwork net(config, 7);
  const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar());
  const auto wave = net.addClient(test::sessionFor("r", "wave", avatar, 5));
  const auto clap = net.addClient(test::sessionFor("r", "clap", avatar, 5));
  const auto viewer = net.addClient(test::sessionFor("r", "viewer", avatar, 5), {}, {}, 5.0);
  const auto late = net.addClient(test::sessionFor("r", "late", avatar, 5));
  for (std::size_t i : {wave, clap, viewer}) net.connect(i);
  net.advance(0.5);
  ASSERT_EQ(net.session(viewer).state(), net::SessionState::kLive);

  // 30 Hz postures; the viewer's frame loop at 60 Hz samples (and records) as the client does.
  RoomRecorder recorder;
  const Posture own = restPosture(test::makeSyntheticAvatar().skeleton);
  const double t0 = net.now();
  double next_send = net.now(), next_frame = net.now();
  Posture shown, scratch;
  std::vector<std::pair<double, glm::quat>> wave_head;  // (recording time, shown rotation)
  net.advance(3.0, 0.001, [&](double now) {
    if (now >= t0 + 1.0 && !net.client(late).connected && now < t0 + 2.0) net.connect(late);
    if (now >= t0 + 2.0 && net.client(late).connected) net.cut(late);
    if (now + 1e-9 >= next_send) {
      next_send += 1.0 / 30.0;
      for (std::size_t i : {wave, clap, late}) {
        if (net.client(i).connected)
          net.session(i).sendPosture(test::syntheticPosture(now), net.localTime(i));
      }
    }
    if (now + 1e-9 >= next_frame) {
      next_frame += 1.0 / 60.0;
      const net::ClientSession& s = net.session(viewer);
      const double local = net.localTime(viewer);
      const double play = s.serverTime(local) - 0.1;
      const bool due = recorder.due(local);
      sampleSession(recorder, s, local, play, own, scratch);
      const net::RemoteMember* m = s.findMember(net.session(wave).memberId());
      if (due && m != nullptr &&
          m->buffer.sampleShown(play, 0.1, shown) != net::JitterBuffer::Shown::kNone) {
        wave_head.emplace_back(recorder.recording().duration_s, shown.rotations[2]);
      }
    }
  });
  const RoomRecording& rec = recorder.finish();
  EXPECT_GT(rec.samples, 150);  // about 60 Hz over 3 s
  EXPECT_NEAR(rec.duration_s, 2.95, 0.1);
  ASSERT_EQ(rec.members.size(), 4u);
  const RecordedMember* by_name[4] = {};
  for (const RecordedMember& m : rec.members) {
    for (int k = 0; k < 4; ++k) {
      if (m.name == std::array<const char*, 4>{"wave", "clap", "viewer", "late"}[k])
        by_name[k] = &m;
    }
  }
  for (const RecordedMember* m : by_name) ASSERT_NE(m, nullptr);

  // Spans: the three from the start to the end; "late" from about 1 s to about 2 s.
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(by_name[k]->spans.size(), 1u) << by_name[k]->name;
    EXPECT_LT(by_name[k]->spans[0].start, 0.2) << by_name[k]->name;
    EXPECT_DOUBLE_EQ(by_name[k]->spans[0].end, rec.duration_s);
  }
  const RecordedMember& lm = *by_name[3];
  ASSERT_EQ(lm.spans.size(), 1u);
  EXPECT_NEAR(lm.spans[0].start, 1.0, 0.25);
  EXPECT_NEAR(lm.spans[0].end, 2.0, 0.25);
  ASSERT_FALSE(lm.rotations[2].times().empty());
  EXPECT_GE(lm.rotations[2].times().front(), lm.spans[0].start);
  EXPECT_LE(lm.rotations[2].times().back(), lm.spans[0].end);

  // The viewer itself, at rest: constant channels. The wave's head: reduced keys that
  // reproduce every shown rotation within the tolerance (slerp between keys).
  EXPECT_TRUE(by_name[2]->rotations[3].constant());
  const QuatTrack& head = by_name[0]->rotations[2];
  EXPECT_FALSE(head.constant());
  EXPECT_LT(head.times().size(), static_cast<std::size_t>(rec.samples) / 2);
  ASSERT_GT(wave_head.size(), 100u);
  const float tol = RecorderOptions{}.rotation_tolerance_rad;
  for (const auto& [t, q] : wave_head) {
    const auto& ts = head.times();
    std::size_t i = 1;
    while (i + 1 < ts.size() && ts[i] < t) ++i;
    const auto u = static_cast<float>(std::clamp((t - ts[i - 1]) / (ts[i] - ts[i - 1]), 0.0, 1.0));
    const glm::quat keyed = glm::slerp(head.values()[i - 1], head.values()[i], u);
    EXPECT_LE(rotationAngle(keyed, q), tol * 1.01f) << "t = " << t;
  }

  // The export: every member a skin (their avatars given).
  RoomRecording with_avatars = rec;
  auto model = std::make_shared<const AvatarModel>(test::makeSyntheticAvatar());
  for (RecordedMember& m : with_avatars.members) m.avatar = model;
  RecordingSummary summary;
  auto bytes = encodeRoomGlb(with_avatars, &summary);
  ASSERT_TRUE(bytes) << bytes.error().message;
  EXPECT_EQ(summary.members, 4);
}

}  // namespace
}  // namespace vistel::record
