// Server-side recording (vistel-server --record-room DIR): what the server saw of each
// room, written as a skinned glTF animation DIR/<room>-<start>.glb (common/record's
// RoomRecorder and room_glb: one skeleton per member, joint tracks, props as node tracks)
// when the room empties (its last member left) or the server stops. <start> is the UTC time
// the recording began, "YYYYMMDDTHHMMSSZ" (a suffix "-2", "-3", ... when that file exists).
//
// Sampling: a timer on a strand of its own, at rate_hz, asks the shell for the open rooms
// (ServerShell::roomViews) and each one's newest postures and props
// (ServerShell::spectate), as the spectator stream does. A member is recorded from its
// first posture at its seat (the [room] seat layout); its avatar (the .vavatar the server
// holds) is fetched once, when the member is first seen, and kept while a recording uses it.
// A member whose avatar never arrived is left out of the file with a warning.
//
// Bounds: a room's recording stops growing after max_duration_s (one warning; what was
// recorded is still written); at most max_rooms rooms are recorded at once (further rooms
// are not recorded, with a warning).
//
// Threads: everything runs on the recorder's strand; stop() may be called from any thread
// (the signal handler); writeAll() once io.run() has returned.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "common/base/result.hpp"
#include "common/scene/seat_layout.hpp"
#include "server/shell/asio.hpp"
#include "server/shell/server_shell.hpp"

namespace vistel::server {

struct ServerRecordOptions {
  std::string dir;                 // must exist (checked by start())
  double rate_hz = 30.0;           // samples per second (1 .. 240)
  double max_duration_s = 1800.0;  // per room (> 0)
  int max_rooms = 64;              // recorded at once (>= 1)
  SeatLayout seat_layout;          // the server's ([room])
};

class ServerRecorder {
 public:
  struct Stats {
    std::uint64_t files_written = 0;
    std::uint64_t write_errors = 0;
    std::uint64_t rooms_capped = 0;   // recordings that reached max_duration_s
    std::uint64_t rooms_skipped = 0;  // rooms not recorded (max_rooms)
  };

  // Checks the options (the error names the folder or the value) and starts sampling.
  static Result<std::unique_ptr<ServerRecorder>> start(asio::io_context& io, ServerShell& shell,
                                                       ServerRecordOptions options);
  ~ServerRecorder();

  // Stops sampling (any thread); recordings in progress stay for writeAll().
  void stop();
  // Writes every recording in progress (call after stop(), once no handler runs: after
  // io.run() has returned). Returns the paths written; errors are logged and counted.
  std::vector<std::string> writeAll();
  // The counts so far; read them once no handler runs (after writeAll()).
  Stats stats() const;

  struct State;

 private:
  explicit ServerRecorder(std::shared_ptr<State> state);
  std::shared_ptr<State> state_;
};

// "<dir>/<room>-<YYYYMMDDTHHMMSSZ>.glb" for a start at `unix_seconds` (UTC), with "-N"
// before ".glb" from N = 2 on while such a file exists. Room names are the lobby's
// ([A-Za-z0-9_.-]), safe in a file name.
std::string recordingPath(const std::string& dir, const std::string& room,
                          std::int64_t unix_seconds);

}  // namespace vistel::server
