#include "server/record/server_recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <system_error>
#include <unordered_map>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/avatar/avatar_io.hpp"
#include "common/record/room_recorder.hpp"
#include "common/wire/bit_stream.hpp"
#include "common/wire/posture_codec.hpp"

namespace vistel::server {
namespace {

using Strand = asio::strand<asio::io_context::executor_type>;

std::int64_t unixNow() {
  return std::chrono::duration_cast<std::chrono::seconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// One room being recorded.
struct Recording {
  std::string room;
  std::int64_t started_unix = 0;
  std::unique_ptr<record::RoomRecorder> recorder;
  bool in_flight = false;  // a spectate() reply is pending
  bool capped = false;     // max_duration_s reached: no more samples
};

}  // namespace

struct ServerRecorder::State : std::enable_shared_from_this<ServerRecorder::State> {
  State(asio::io_context& io, ServerShell& s, ServerRecordOptions o)
      : shell(s), options(std::move(o)), strand(asio::make_strand(io)), timer(strand) {}

  void arm() {
    timer.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(1.0 / options.rate_hz)));
    timer.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec || self->stopped) return;
      self->tick();
      self->arm();
    });
  }

  // On the strand: which rooms are open; recordings of rooms gone are written.
  void tick() {
    shell.roomViews([self = shared_from_this()](std::vector<LobbyRoomView> rooms, double) {
      asio::post(self->strand, [self, rooms = std::move(rooms)]() mutable {
        if (self->stopped) return;
        self->onRooms(std::move(rooms));
      });
    });
  }

  void onRooms(std::vector<LobbyRoomView> rooms) {
    std::set<std::uint32_t> open;
    for (const LobbyRoomView& room : rooms) open.insert(room.id);
    // A room that closed (everyone left): its recording is complete.
    for (auto it = recordings.begin(); it != recordings.end();) {
      if (open.count(it->first) == 0 && !it->second.in_flight) {
        writeOne(it->second);
        it = recordings.erase(it);
      } else {
        ++it;
      }
    }
    for (const LobbyRoomView& room : rooms) {
      auto found = recordings.find(room.id);
      if (found == recordings.end()) {
        if (skipped.count(room.id) != 0) continue;
        if (static_cast<int>(recordings.size()) >= options.max_rooms) {
          skipped.insert(room.id);
          ++stats.rooms_skipped;
          spdlog::warn("record: room '{}' not recorded: {} rooms are being recorded already",
                       room.name, options.max_rooms);
          continue;
        }
        Recording rec;
        rec.room = room.name;
        rec.started_unix = unixNow();
        record::RecorderOptions ro;
        ro.rate_hz = options.rate_hz;
        rec.recorder = std::make_unique<record::RoomRecorder>(ro);
        found = recordings.emplace(room.id, std::move(rec)).first;
        spdlog::info("record: recording room '{}'", room.name);
      }
      Recording& rec = found->second;
      if (rec.in_flight || rec.capped) continue;
      rec.in_flight = true;
      shell.spectate(room.name, [self = shared_from_this(),
                                 id = room.id](std::optional<SpectatorFrame> frame) {
        asio::post(self->strand, [self, id, frame = std::move(frame)] {
          auto it = self->recordings.find(id);
          if (it == self->recordings.end()) return;
          it->second.in_flight = false;
          if (self->stopped || !frame || frame->room.id != id) return;
          self->onFrame(it->second, *frame);
        });
      });
    }
    // Forget skipped rooms that closed.
    for (auto it = skipped.begin(); it != skipped.end();) {
      it = open.count(*it) == 0 ? skipped.erase(it) : std::next(it);
    }
  }

  // On the strand: one sample of a room.
  void onFrame(Recording& rec, const SpectatorFrame& frame) {
    if (!rec.recorder->beginSample(frame.now, options.rate_hz)) return;
    wire::PostureRecord wire_record;
    for (const SpectatorPosture& p : frame.postures) {
      const auto member = std::find_if(frame.room.members.begin(), frame.room.members.end(),
                                       [&](const LobbyMemberView& m) { return m.id == p.member; });
      if (member == frame.room.members.end()) continue;
      wire::ReadStream in(p.record);
      if (!wire::serialize(in, wire_record) || !in.ok()) continue;
      wire::decodePostureRecord(wire_record, frame.now, posture);
      if (posture.rotations.empty()) continue;
      const SeatPlacement seat = seatPlacement(member->seat, options.seat_layout);
      rec.recorder->addMember(member->name, member->avatar_hash, {seat.x, seat.z, seat.yaw},
                              posture);
      if (member->avatar_ready) fetchAvatar(member->avatar_hash);
    }
    for (const SpectatorProp& p : frame.props) {
      BallSpec ball;
      ball.radius = p.radius;
      rec.recorder->addProp(p.id, ball, p.position);
    }
    rec.recorder->endSample();
    if (rec.recorder->recording().duration_s >= options.max_duration_s && !rec.capped) {
      rec.capped = true;
      ++stats.rooms_capped;
      spdlog::warn(
          "record: room '{}' reached the recording limit of {} s: no more is recorded (the file "
          "is written when the room empties or the server stops)",
          rec.room, options.max_duration_s);
    }
  }

  // On the strand: asks the shell for an avatar's .vavatar once.
  void fetchAvatar(const std::string& hash) {
    if (!avatars.emplace(hash, nullptr).second) return;
    shell.avatarFile(hash, [self = shared_from_this(),
                            hash](std::shared_ptr<const std::vector<std::uint8_t>> file) {
      if (!file) return;
      auto model = decodeAvatar(*file, hash);
      if (!model) {
        spdlog::warn("record: avatar {}: {}", hash.substr(0, 12), model.error().message);
        return;
      }
      auto shared = std::make_shared<const AvatarModel>(std::move(*model));
      asio::post(self->strand, [self, hash, shared] { self->avatars[hash] = shared; });
    });
  }

  // Writes a recording (strand, or after io.run()); drops avatars no recording uses.
  std::optional<std::string> writeOne(Recording& rec) {
    std::optional<std::string> written;
    if (rec.recorder->recording().samples == 0) {
      spdlog::info("record: room '{}': nothing was recorded", rec.room);
    } else {
      const std::string path = recordingPath(options.dir, rec.room, rec.started_unix);
      auto summary = rec.recorder->write(path, [this](const std::string& hash) {
        auto it = avatars.find(hash);
        return it == avatars.end() ? nullptr : it->second;
      });
      if (!summary) {
        ++stats.write_errors;
        spdlog::error("record: room '{}': {}", rec.room, summary.error().message);
      } else {
        ++stats.files_written;
        for (const std::string& w : summary->warnings) spdlog::warn("record: {}: {}", path, w);
        spdlog::info("record: wrote {} ({} members, {} props, {:.1f} s, {} keys, {} bytes)", path,
                     summary->members, summary->props, summary->duration_s, summary->keys,
                     summary->bytes);
        written = path;
      }
    }
    // The avatars the other recordings still need.
    std::set<std::string> used;
    for (const auto& [id, other] : recordings) {
      if (&other == &rec) continue;
      for (const record::RecordedMember& m : other.recorder->recording().members)
        used.insert(m.avatar_hash);
    }
    for (auto it = avatars.begin(); it != avatars.end();) {
      it = used.count(it->first) == 0 ? avatars.erase(it) : std::next(it);
    }
    return written;
  }

  ServerShell& shell;
  ServerRecordOptions options;
  Strand strand;
  asio::steady_timer timer;
  std::atomic<bool> stopped{false};
  // On the strand:
  std::map<std::uint32_t, Recording> recordings;  // by room id
  std::set<std::uint32_t> skipped;
  std::unordered_map<std::string, std::shared_ptr<const AvatarModel>> avatars;  // by hash
  Posture posture;                                                              // scratch
  Stats stats;
};

std::string recordingPath(const std::string& dir, const std::string& room,
                          std::int64_t unix_seconds) {
  const std::time_t t = static_cast<std::time_t>(unix_seconds);
  std::tm utc{};
  gmtime_r(&t, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", &utc);
  const std::filesystem::path base = std::filesystem::path(dir) / fmt::format("{}-{}", room, stamp);
  std::string path = base.string() + ".glb";
  std::error_code ec;
  for (int n = 2; std::filesystem::exists(path, ec) && n < 1000; ++n) {
    path = fmt::format("{}-{}.glb", base.string(), n);
  }
  return path;
}

ServerRecorder::ServerRecorder(std::shared_ptr<State> state) : state_(std::move(state)) {}

ServerRecorder::~ServerRecorder() { stop(); }

Result<std::unique_ptr<ServerRecorder>> ServerRecorder::start(asio::io_context& io,
                                                              ServerShell& shell,
                                                              ServerRecordOptions options) {
  std::error_code ec;
  if (options.dir.empty()) return fail("--record-room: no folder given");
  if (!std::filesystem::is_directory(options.dir, ec)) {
    return fail("--record-room {}: not a folder (create it first)", options.dir);
  }
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 240.0)) {
    return fail("--record-rate {}: expected 1 .. 240 samples per second", options.rate_hz);
  }
  if (!(options.max_duration_s > 0.0)) {
    return fail("--record-max-s {}: expected a positive duration", options.max_duration_s);
  }
  if (options.max_rooms < 1) return fail("record: max_rooms {}: expected >= 1", options.max_rooms);
  auto state = std::make_shared<State>(io, shell, std::move(options));
  asio::post(state->strand, [state] { state->arm(); });
  return std::unique_ptr<ServerRecorder>(new ServerRecorder(std::move(state)));
}

void ServerRecorder::stop() {
  if (state_->stopped.exchange(true)) return;
  asio::post(state_->strand, [state = state_] { state->timer.cancel(); });
}

std::vector<std::string> ServerRecorder::writeAll() {
  stop();
  std::vector<std::string> written;
  State& s = *state_;
  while (!s.recordings.empty()) {
    auto it = s.recordings.begin();
    if (auto path = s.writeOne(it->second)) written.push_back(std::move(*path));
    s.recordings.erase(it);
  }
  return written;
}

ServerRecorder::Stats ServerRecorder::stats() const { return state_->stats; }

}  // namespace vistel::server
