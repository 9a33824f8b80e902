// A program of the build folder run by an integration test: its stdout and stderr go to a
// log file, or its stdout to a pipe the test reads line by line (the server's address).
// The process is killed when the object goes if it has not exited.
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace vistel::test {

class Program {
 public:
  // Starts `program` (a file in test::binaryDir()) with args. pipe_stdout: stdout to a
  // pipe (readLine), stderr to log_path; else both to log_path.
  Program(const std::string& program, const std::vector<std::string>& args, std::string log_path,
          bool pipe_stdout = false);
  ~Program();
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  // The next line of piped stdout, waiting at most timeout_s.
  std::optional<std::string> readLine(double timeout_s);
  void signal(int sig);
  // Exit status (or -signal), waiting at most timeout_s; nullopt on timeout.
  std::optional<int> wait(double timeout_s);
  // The log so far, and waiting until it contains `text` (at most timeout_s).
  std::string log() const;
  bool waitForLog(const std::string& text, double timeout_s) const;

 private:
  std::string log_path_;
  pid_t pid_ = -1;
  int out_fd_ = -1;
  bool exited_ = false;
};

// The address a vistel-server started with a piped stdout prints ("127.0.0.1:PORT"),
// waiting at most 20 s; empty (and a test failure) when it prints something else.
std::string serverAddress(Program& server);

// A program's log file, or "(no log)" when it cannot be read (for failure messages).
std::string logOf(const std::string& path);

// Sleeps the calling thread for `s` seconds.
void sleepFor(double s);

}  // namespace vistel::test
