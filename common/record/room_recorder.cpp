#include "common/record/room_recorder.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include <fmt/format.h>
#include <glm/gtc/quaternion.hpp>

#include "common/base/file.hpp"
#include "common/record/room_glb.hpp"
#include "common/scene/deform_scene.hpp"

namespace vistel::record {
namespace {

constexpr double kDefaultRateHz = 60.0;

// Ends a span that is open (its end still unset) at t.
void closeSpan(std::vector<Span>& spans, double t) {
  if (!spans.empty() && spans.back().end < spans.back().start) spans.back().end = t;
}
bool spanOpen(const std::vector<Span>& spans) {
  return !spans.empty() && spans.back().end < spans.back().start;
}

void cutMember(RecordedMember& rec) {
  rec.seat_translation.cut();
  rec.seat_rotation.cut();
  rec.root_translation.cut();
  for (QuatTrack& track : rec.rotations) track.cut();
  for (Vec3Track& track : rec.translations) track.cut();
}

}  // namespace

Status checkRecordPath(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty()) return fail("no file name given");
  if (fs::is_directory(path, ec)) return fail("{}: is a folder (give a .glb file name)", path);
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec)) {
    return fail("{}: the folder {} does not exist", path, parent.string());
  }
  return {};
}

RoomRecorder::RoomRecorder(RecorderOptions options) : options_(options) {}

RecordedMember& RoomRecorder::memberFor(const std::string& name, const std::string& avatar_hash) {
  const std::string key = name + '\n' + avatar_hash;
  auto found = member_index_.find(key);
  if (found != member_index_.end()) return recording_.members[found->second];
  // A new member (a name seen again with another avatar is another member).
  RecordedMember rec;
  rec.name = name;
  for (const RecordedMember& other : recording_.members) {
    if (other.name == name) rec.name = fmt::format("{} ({})", name, recording_.members.size());
  }
  rec.avatar_hash = avatar_hash;
  rec.seat_translation = Vec3Track(options_.translation_tolerance_m);
  rec.seat_rotation = QuatTrack(options_.rotation_tolerance_rad);
  rec.root_translation = Vec3Track(options_.translation_tolerance_m);
  member_index_.emplace(key, recording_.members.size());
  member_seen_.push_back(-1);
  recording_.members.push_back(std::move(rec));
  return recording_.members.back();
}

RecordedProp& RoomRecorder::propFor(std::uint32_t id, const BallSpec& ball) {
  auto found = prop_index_.find(id);
  if (found != prop_index_.end()) return recording_.props[found->second];
  RecordedProp rec;
  rec.id = id;
  rec.name = fmt::format("ball {}", recording_.props.size() + 1);
  rec.ball = ball;
  rec.position = Vec3Track(options_.translation_tolerance_m);
  prop_index_.emplace(id, recording_.props.size());
  prop_seen_.push_back(-1);
  recording_.props.push_back(std::move(rec));
  return recording_.props.back();
}

void RoomRecorder::addPosture(RecordedMember& rec, const SeatPlacement& seat,
                              const Posture& posture, double t) {
  const std::size_t nj = posture.rotations.size();
  // The joint count is fixed by the first posture (the avatar's); others are not shown.
  if (rec.rotations.empty()) {
    rec.rotations.assign(nj, QuatTrack(options_.rotation_tolerance_rad));
  }
  if (rec.rotations.size() != nj) return;
  if (!posture.translations.empty() && posture.translations.size() == nj &&
      rec.translations.empty()) {
    rec.translations.assign(nj, Vec3Track(options_.translation_tolerance_m));
  }
  rec.seat_translation.add(t, glm::vec3(seat.x, 0.0f, seat.z));
  rec.seat_rotation.add(t, glm::angleAxis(seat.yaw, glm::vec3(0.0f, 1.0f, 0.0f)));
  rec.root_translation.add(t, posture.root_translation);
  for (std::size_t j = 0; j < nj; ++j)
    rec.rotations[j].add(t, glm::normalize(posture.rotations[j]));
  if (!rec.translations.empty() && posture.translations.size() == nj) {
    for (std::size_t j = 1; j < nj; ++j) rec.translations[j].add(t, posture.translations[j]);
  }
}

bool RoomRecorder::beginSample(double now, double rate_hz) {
  if (!due(now)) return false;
  const double rate = options_.rate_hz > 0.0 ? options_.rate_hz
                      : rate_hz > 0.0        ? rate_hz
                                             : kDefaultRateHz;
  // Samples on a grid of the interval; a frame up to a quarter interval early takes its
  // grid point, and a stall longer than an interval restarts the grid.
  const bool first = interval_ <= 0.0;
  interval_ = 1.0 / rate;
  next_due_ = first ? now + interval_ : next_due_ + interval_;
  if (next_due_ < now) next_due_ = now + interval_;
  const double t = start_ < 0.0 ? 0.0 : now - start_;
  if (start_ >= 0.0 && !(t > last_t_)) return false;
  sample_now_ = now;
  sample_t_ = t;
  return true;
}

void RoomRecorder::addMember(const std::string& name, const std::string& avatar_hash,
                             const SeatPlacement& seat, const Posture& posture) {
  if (posture.rotations.empty()) return;
  if (start_ < 0.0) start_ = sample_now_;
  RecordedMember& rec = memberFor(name, avatar_hash);
  const std::size_t index = static_cast<std::size_t>(&rec - recording_.members.data());
  if (!spanOpen(rec.spans)) rec.spans.push_back({sample_t_, -1.0});
  member_seen_[index] = stamp_;
  addPosture(rec, seat, posture, sample_t_);
}

void RoomRecorder::addProp(std::uint32_t id, const BallSpec& ball, const glm::vec3& position) {
  if (start_ < 0.0) start_ = sample_now_;
  RecordedProp& rec = propFor(id, ball);
  const std::size_t index = static_cast<std::size_t>(&rec - recording_.props.data());
  if (!spanOpen(rec.spans)) rec.spans.push_back({sample_t_, -1.0});
  prop_seen_[index] = stamp_;
  rec.position.add(sample_t_, position);
}

void RoomRecorder::endSample() {
  if (start_ < 0.0) return;  // nothing shown yet: the recording has not started
  const double t = sample_t_;
  // Whoever was shown before but not in this sample has gone: its span ends here.
  for (std::size_t i = 0; i < recording_.members.size(); ++i) {
    RecordedMember& rec = recording_.members[i];
    if (member_seen_[i] != stamp_ && spanOpen(rec.spans)) {
      closeSpan(rec.spans, t);
      cutMember(rec);
    }
  }
  for (std::size_t i = 0; i < recording_.props.size(); ++i) {
    RecordedProp& rec = recording_.props[i];
    if (prop_seen_[i] != stamp_ && spanOpen(rec.spans)) {
      closeSpan(rec.spans, t);
      rec.position.cut();
    }
  }
  last_t_ = t;
  recording_.duration_s = t;
  ++recording_.samples;
  ++stamp_;
}

const RoomRecording& RoomRecorder::finish() {
  // Spans still open end with the recording (shown to its last sample).
  for (RecordedMember& rec : recording_.members) {
    if (spanOpen(rec.spans)) rec.spans.back().end = std::max(last_t_, rec.spans.back().start);
    cutMember(rec);
  }
  for (RecordedProp& rec : recording_.props) {
    if (spanOpen(rec.spans)) rec.spans.back().end = std::max(last_t_, rec.spans.back().start);
    rec.position.cut();
  }
  return recording_;
}

Result<RecordingSummary> RoomRecorder::write(
    const std::string& path,
    const std::function<std::shared_ptr<const AvatarModel>(const std::string&)>& avatar_of) {
  finish();
  for (RecordedMember& rec : recording_.members) {
    if (!rec.avatar && avatar_of) rec.avatar = avatar_of(rec.avatar_hash);
  }
  for (RecordedProp& rec : recording_.props) {
    if (rec.model) continue;
    auto made = makeBallAvatar(rec.ball);  // null: the prop is left out, with a warning
    if (made) rec.model = std::move(*made);
  }
  RecordingSummary summary;
  Result<std::vector<std::uint8_t>> bytes = encodeRoomGlb(recording_, &summary);
  if (!bytes) return withContext(path, bytes.error());
  if (Status st = writeFileBytes(path, *bytes); !st) return st.error();
  summary.bytes = bytes->size();
  return summary;
}

}  // namespace vistel::record
