// Admission of TCP connections at accept (issue 20, finding 5): at most max_total open
// connections, and at most max_per_address from one source address, so that one host
// cannot take every slot. A refusal happens before any handshake (the shell answers it
// with one ErrorReply and closes) and is counted by reason.
//
// Pure and single-threaded (the shell calls it on the lobby strand). Addresses are keys
// in any stable spelling; loopback peers are exempt from the per-address limit unless
// limit_loopback. A limit of 0 means none.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <unordered_map>

namespace vistel::server {

class ConnectionLimits {
 public:
  ConnectionLimits(int max_total, int max_per_address, bool limit_loopback)
      : max_total_(max_total), max_per_address_(max_per_address), limit_loopback_(limit_loopback) {}

  // Admits a connection from `address` (counted until release()) and returns an empty
  // reason, or refuses it: "connection limit" or "connections per address" (counted).
  std::string_view admit(const std::string& address, bool loopback);
  // A connection admitted from `address` closed.
  void release(const std::string& address);

  int open() const { return open_; }
  int openFrom(const std::string& address) const;
  // Refusals so far, by reason.
  const std::map<std::string, std::uint64_t>& refusals() const { return refusals_; }

 private:
  int max_total_;
  int max_per_address_;
  bool limit_loopback_;
  int open_ = 0;
  std::unordered_map<std::string, int> per_address_;  // open connections by address
  std::map<std::string, std::uint64_t> refusals_;
};

}  // namespace vistel::server
