#include "tests/sensors/pty_emulator.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <gtest/gtest.h>

namespace vistel::test {
namespace {

double nowSeconds() {
  static const auto start = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::unique_ptr<PtyEmulator> PtyEmulator::start(Receive receive, Tick tick, PtyOptions options) {
  std::unique_ptr<PtyEmulator> e(new PtyEmulator());
  e->receive_ = std::move(receive);
  e->tick_ = std::move(tick);
  e->options_ = options;
  e->rng_ = options.seed * 0x9E3779B97F4A7C15ull + 1;
  termios raw{};
  ::cfmakeraw(&raw);
  char name[256] = {};
  if (::openpty(&e->master_, &e->slave_, name, &raw, nullptr) != 0) {
    ADD_FAILURE() << "openpty failed: " << std::strerror(errno);
    return nullptr;
  }
  e->path_ = name;
  ::fcntl(e->master_, F_SETFL, ::fcntl(e->master_, F_GETFL) | O_NONBLOCK);
  e->thread_ = std::thread([p = e.get()] { p->run(); });
  return e;
}

PtyEmulator::~PtyEmulator() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
}

void PtyEmulator::unplug() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (master_ >= 0) ::close(master_);
  master_ = -1;
  if (slave_ >= 0) ::close(slave_);
  slave_ = -1;
}

void PtyEmulator::withLock(const std::function<void()>& f) {
  std::lock_guard<std::mutex> lock(mutex_);
  f();
}

void PtyEmulator::emit(Pieces& pieces) {
  auto next = [this]() {
    rng_ ^= rng_ << 13;
    rng_ ^= rng_ >> 7;
    rng_ ^= rng_ << 17;
    return rng_;
  };
  for (std::string& piece : pieces) {
    std::string bytes;
    if (options_.garbage_probability > 0.0 &&
        static_cast<double>(next() % 1000000) < options_.garbage_probability * 1e6) {
      const int n = 1 + static_cast<int>(next() % 12);
      for (int i = 0; i < n; ++i) {
        char c;
        do {
          c = static_cast<char>(next() & 0xFF);
        } while (options_.garbage_excludes.find(c) != std::string::npos);
        bytes.push_back(c);
      }
      garbage_bytes_ += static_cast<std::size_t>(n);
    }
    bytes += piece;
    std::size_t done = 0;
    while (done < bytes.size() && master_ >= 0) {
      std::size_t n = bytes.size() - done;
      if (options_.max_chunk > 0)
        n = std::min<std::size_t>(n, 1 + next() % static_cast<std::uint64_t>(options_.max_chunk));
      const ssize_t w = ::write(master_, bytes.data() + done, n);
      if (w <= 0) break;  // the line is full: drop the rest, as a real line would overflow
      done += static_cast<std::size_t>(w);
      if (options_.max_chunk > 0 && done < bytes.size()) {
        mutex_.unlock();
        std::this_thread::sleep_for(std::chrono::microseconds(200));
        mutex_.lock();
      }
    }
  }
  pieces.clear();
}

void PtyEmulator::run() {
  Pieces pieces;
  char buf[512];
  while (!stop_) {
    int fd;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      fd = master_;
    }
    if (fd < 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      continue;
    }
    pollfd p{fd, POLLIN, 0};
    ::poll(&p, 1, 1);
    std::lock_guard<std::mutex> lock(mutex_);
    if (master_ < 0) continue;
    const double now = nowSeconds();
    for (;;) {
      const ssize_t n = ::read(master_, buf, sizeof buf);
      if (n <= 0) break;
      receive_(std::string_view(buf, static_cast<std::size_t>(n)), now, pieces);
    }
    tick_(now, pieces);
    emit(pieces);
  }
}

}  // namespace vistel::test
