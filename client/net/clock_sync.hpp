// The client's estimate of the server clock (DESIGN.md §6 "Clock"): each ping/pong gives
// a sample (local send time t0, server time ts, local receive time t3); its offset is
// ts - (t0 + t3) / 2 and its round trip t3 - t0. Queueing delay only ever lengthens a
// round trip, so the sample with the smallest round trip in a recent window is the
// least disturbed: its offset is used. The remaining error is at most half that
// sample's round trip, and exactly half the asymmetry of the two directions' base
// latencies (which no ping exchange can observe).
#pragma once

#include <cstdint>
#include <vector>

namespace vistel::net {

class ClockSync {
 public:
  // window: how many recent samples compete (older ones are forgotten, so a route
  // change is followed).
  explicit ClockSync(int window = 16);

  // A rough start before any ping: server time seen at local time (e.g. the Welcome's).
  void seed(double server_time, double local_time);
  // One ping/pong exchange; ignored when inconsistent (t3 < t0, non-finite).
  void addSample(double t0_local, double server_time, double t3_local);

  // server time - local time, seconds.
  double offset() const { return offset_; }
  // Round trip of the sample in use (seconds; 0 before any sample).
  double roundTrip() const { return round_trip_; }
  int sampleCount() const { return static_cast<int>(total_samples_); }
  bool synced() const { return total_samples_ > 0; }
  double serverTime(double local_time) const { return local_time + offset_; }

 private:
  struct Sample {
    double offset;
    double round_trip;
  };
  std::vector<Sample> samples_;  // ring of the last `window`
  std::size_t next_ = 0;
  std::size_t window_;
  std::uint64_t total_samples_ = 0;
  double offset_ = 0.0;
  double round_trip_ = 0.0;
};

}  // namespace vistel::net
