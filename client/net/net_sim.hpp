// A network simulator between a program and the server (`--netsim SPEC` on vistel-client
// and vistel-bot; `[network] netsim` in the client config): the UDP datagrams the
// NetDriver sends and receives pass through it and are lost, delayed, duplicated and
// reordered as the spec says. The bytes of a datagram are never changed. TCP is not
// touched (the control channel's own retransmission would hide most faults).
//
// The spec is a comma-separated list of KEY=VALUE (spaces around items are ignored;
// "" or "off" means no simulation):
//   loss=P           probability a datagram is lost, P in [0, 1] ("0.1" or "10%")
//   latency=D        fixed one-way delay added to every datagram
//   jitter=D         extra random delay per datagram, >= 0 (see jitter_dist)
//   jitter_dist=uniform|normal
//                    uniform (default): the extra delay is uniform in [0, D];
//                    normal: |N(0, D)|, a half-normal with scale D (mean 0.8 D, with a
//                    tail: 5% beyond 2 D)
//   dup=P            probability a datagram is delivered twice (the copy takes its own
//                    random delay)
//   reorder=P        probability a datagram is held back reorder_delay longer, so that
//                    datagrams sent after it overtake it
//   reorder_delay=D  how long a reordered datagram is held back (default 20ms)
//   dir=both|in|out  which direction is simulated: both (default), in (server to us),
//                    out (us to server)
//   seed=N           the random generator's seed (decimal, 64 bit); 0 or absent: random
//                    per run. NetDriver mixes the participant's name into it, so the
//                    bots of one process differ but runs repeat.
// Durations D are a number with a unit: us, ms or s ("30ms", "0.03s"); each at most 10 s.
// An unknown key, a repeated key, a value out of range or without a unit is an error
// naming the item.
//
// NetSimLink is the pure core of one direction, fed (bytes, now) and asked what is due
// (tests drive it with a fake clock). NetSim is its Asio shell for NetDriver: both
// directions, one steady_timer on the driver's strand (no threads, no sleeping),
// delivering through callbacks.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "client/net/asio.hpp"
#include "common/base/result.hpp"

namespace vistel::net {

enum class JitterDistribution { kUniform, kNormal };
enum class NetSimDirection { kBoth, kIn, kOut };

struct NetSimSpec {
  double loss = 0.0;       // probability, [0, 1]
  double latency_s = 0.0;  // fixed one-way delay, seconds, [0, 10]
  double jitter_s = 0.0;   // scale of the extra random delay, seconds, [0, 10]
  JitterDistribution jitter_dist = JitterDistribution::kUniform;
  double dup = 0.0;               // probability of a second copy, [0, 1]
  double reorder = 0.0;           // probability of being held back, [0, 1]
  double reorder_delay_s = 0.02;  // how long, seconds, [0, 10]
  NetSimDirection direction = NetSimDirection::kBoth;
  std::uint64_t seed = 0;  // 0: random per run

  // Any fault at all (an all-zero spec passes datagrams straight through).
  bool active() const;
  bool appliesIn() const { return active() && direction != NetSimDirection::kOut; }
  bool appliesOut() const { return active() && direction != NetSimDirection::kIn; }
};

// Parses a spec (see above). Errors name the item: "--netsim 'loss=2': loss must be in
// [0, 1]" (the prefix is the caller's `what`).
Result<NetSimSpec> parseNetSimSpec(std::string_view text, std::string_view what = "--netsim");
// The spec in the same syntax, every key written ("loss=0.1,latency=30ms,...").
std::string describeNetSim(const NetSimSpec& spec);

// What a link did, in datagrams.
struct NetSimCounters {
  std::uint64_t offered = 0;     // handed to the link
  std::uint64_t lost = 0;        // dropped by `loss`
  std::uint64_t duplicated = 0;  // extra copies made by `dup`
  std::uint64_t reordered = 0;   // held back by `reorder`
  std::uint64_t overflowed = 0;  // dropped because kMaxQueued were already in flight
  std::uint64_t delivered = 0;   // taken out with pop()
};

// One direction. Deterministic for a given seed and sequence of calls. Memory: the
// datagrams in flight (at most kMaxQueued; more are dropped and counted), copied on
// push(); buffers are reused after pop().
class NetSimLink {
 public:
  static constexpr std::size_t kMaxQueued = 8192;

  NetSimLink(const NetSimSpec& spec, std::uint64_t seed);

  // A datagram sent at `now` (seconds, any monotonic clock): lost, or queued to be due
  // at now + latency + jitter (+ reorder_delay), perhaps twice.
  void push(std::span<const std::uint8_t> bytes, double now);
  // The earliest due time queued; false when nothing is in flight.
  bool nextDue(double& due) const;
  // Takes the earliest datagram due at or before `now` (ties in push order) into `out`
  // (its previous contents replaced); false when none is due.
  bool pop(double now, std::vector<std::uint8_t>& out);
  // Drops everything in flight (a closed socket).
  void clear();
  std::size_t inFlight() const { return queue_.size(); }
  const NetSimCounters& counters() const { return counters_; }

 private:
  struct Pending {
    double due = 0.0;
    std::uint64_t order = 0;  // push order, breaks ties
    std::vector<std::uint8_t> bytes;
  };
  double delay();
  void enqueue(std::span<const std::uint8_t> bytes, double due);

  NetSimSpec spec_;
  std::mt19937_64 rng_;
  std::vector<Pending> queue_;                    // a min-heap on (due, order)
  std::vector<std::vector<std::uint8_t>> spare_;  // buffers to reuse
  std::uint64_t next_order_ = 0;
  NetSimCounters counters_;
};

// Both directions on an executor (the driver's strand): send() and receive() queue a
// datagram (or pass it straight on when that direction is not simulated), and a timer
// hands each one to the callback when it is due. Create with std::make_shared; the
// callbacks run on the executor. clear() drops what is in flight and cancels the timer.
class NetSim : public std::enable_shared_from_this<NetSim> {
 public:
  using Deliver = std::function<void(std::span<const std::uint8_t>)>;

  NetSim(asio::any_io_executor executor, const NetSimSpec& spec, std::uint64_t seed,
         Deliver to_server, Deliver to_program);

  // Call on the executor. `now`: monotonicSeconds().
  void send(std::span<const std::uint8_t> datagram, double now);
  void receive(std::span<const std::uint8_t> datagram, double now);
  void clear();

  const NetSimSpec& spec() const { return spec_; }
  const NetSimCounters& outCounters() const { return out_.counters(); }
  const NetSimCounters& inCounters() const { return in_.counters(); }

 private:
  void arm();
  void deliverDue();

  NetSimSpec spec_;
  NetSimLink out_;
  NetSimLink in_;
  Deliver to_server_;
  Deliver to_program_;
  asio::steady_timer timer_;
  double armed_for_ = -1.0;  // due time the timer waits for (< 0: idle)
  std::vector<std::uint8_t> scratch_;
};

// The seed a participant's simulator uses: the spec's seed mixed with its name (so that
// several bots of one process differ and a run repeats), or a random one when the spec
// has none.
std::uint64_t netSimSeed(const NetSimSpec& spec, const std::string& name);

}  // namespace vistel::net
