// A device on a pseudo-terminal for tests: the driver opens the /dev/pts/N path like a
// serial port while a thread plays the device (a model from device_models.hpp) on the
// master side — answering commands, streaming, optionally putting garbage between pieces
// and writing each piece in small chunks (split reads), and "unplugging" by closing the
// master.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "tests/sensors/device_models.hpp"

namespace vistel::test {

struct PtyOptions {
  double garbage_probability = 0.0;  // chance of 1..12 random bytes before each piece
  std::string garbage_excludes;      // bytes garbage never contains
  int max_chunk = 0;                 // write pieces in chunks of 1..max_chunk bytes (0: whole)
  std::uint64_t seed = 1;
};

class PtyEmulator {
 public:
  using Receive = std::function<void(std::string_view, double, Pieces&)>;
  using Tick = std::function<void(double, Pieces&)>;

  // Opens the pty and starts the device thread; nullptr (with a gtest failure) on error.
  static std::unique_ptr<PtyEmulator> start(Receive receive, Tick tick, PtyOptions options = {});
  ~PtyEmulator();

  const std::string& path() const { return path_; }
  // Closes the master side: the device is gone.
  void unplug();
  // Runs f while the device thread is paused (to change the model's state).
  void withLock(const std::function<void()>& f);
  std::size_t garbageBytes() const { return garbage_bytes_; }

 private:
  PtyEmulator() = default;
  void run();
  void emit(Pieces& pieces);

  Receive receive_;
  Tick tick_;
  PtyOptions options_;
  int master_ = -1;
  int slave_ = -1;
  std::string path_;
  std::thread thread_;
  std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::atomic<std::size_t> garbage_bytes_{0};
  std::uint64_t rng_ = 1;
};

}  // namespace vistel::test
