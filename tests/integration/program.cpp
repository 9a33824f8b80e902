#include "tests/integration/program.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "tests/support/test_support.hpp"

extern char** environ;

namespace vistel::test {
namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

Program::Program(const std::string& program, const std::vector<std::string>& args,
                 std::string log_path, bool pipe_stdout)
    : log_path_(std::move(log_path)) {
  std::vector<std::string> argv_strings = {binaryDir() + "/" + program};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  int fds[2] = {-1, -1};
  if (pipe_stdout) {
    EXPECT_EQ(pipe(fds), 0);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn_file_actions_addopen(&actions, 2, log_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
  } else {
    posix_spawn_file_actions_addopen(&actions, 1, log_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  EXPECT_EQ(rc, 0) << "cannot start " << argv[0];
  if (pipe_stdout) {
    close(fds[1]);
    out_fd_ = fds[0];
  }
}

Program::~Program() {
  if (pid_ > 0 && !exited_) {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  if (out_fd_ >= 0) close(out_fd_);
}

std::optional<std::string> Program::readLine(double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  std::string line;
  while (Clock::now() < deadline) {
    pollfd p{out_fd_, POLLIN, 0};
    if (poll(&p, 1, 50) <= 0) continue;
    char c = 0;
    if (read(out_fd_, &c, 1) != 1) return std::nullopt;
    if (c == '\n') return line;
    line += c;
  }
  return std::nullopt;
}

void Program::signal(int sig) { kill(pid_, sig); }

std::optional<int> Program::wait(double timeout_s) {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < deadline) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return std::nullopt;
}

std::string Program::log() const {
  auto text = readFileText(log_path_);
  return text ? *text : std::string("(no log)");
}

bool Program::waitForLog(const std::string& text, double timeout_s) const {
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (Clock::now() < deadline) {
    if (log().find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

std::string serverAddress(Program& server) {
  const auto line = server.readLine(20.0);
  const std::string prefix = "vistel-server listening on ";
  EXPECT_TRUE(line && line->rfind(prefix, 0) == 0) << line.value_or("(nothing)");
  return line ? line->substr(std::min(prefix.size(), line->size())) : std::string();
}

std::string logOf(const std::string& path) {
  auto text = readFileText(path);
  return text ? *text : std::string("(no log)");
}

void sleepFor(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

}  // namespace vistel::test
