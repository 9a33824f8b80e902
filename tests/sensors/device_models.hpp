// The device side of the protocols, for tests: pure state machines that take the host's
// command bytes and the time and produce what a FASTRAK-class unit or a CyberGlove box would
// send, as pieces (one record or reply each, so an emulator can put garbage between them).
// Used behind a pseudo-terminal (pty_emulator.hpp) and behind the fake USB device.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "common/sensors/cyberglove_protocol.hpp"
#include "common/sensors/fastrak_protocol.hpp"

namespace vistel::test {

using Pieces = std::vector<std::string>;

class FastrakModel {
 public:
  // pose(station, t): the station's reading (position in metres, device axes).
  explicit FastrakModel(std::function<FastrakRecord(int station, double t)> pose,
                        double rate_hz = 120.0);

  void receive(std::string_view bytes, double now, Pieces& out);
  void tick(double now, Pieces& out);  // continuous output due by now

  // What the host configured.
  FastrakFormat format() const { return format_; }
  bool continuous() const { return continuous_; }
  bool enabled(int station) const { return enabled_[static_cast<std::size_t>(station)]; }
  int polls() const { return polls_; }
  std::string log() const { return log_; }  // commands seen, one letter each

 private:
  void command(const std::string& cmd, double now, Pieces& out);
  void records(double now, Pieces& out);

  std::function<FastrakRecord(int, double)> pose_;
  double period_;
  std::string pending_;
  FastrakFormat format_;
  bool continuous_ = true;  // a unit powers up streaming (the driver must stop it)
  std::array<bool, 5> enabled_{false, true, true, true, true};
  double next_ = 0.0;
  int polls_ = 0;
  std::string log_;
};

class GloveModel {
 public:
  // angles(t): raw sensor bytes (record order) at time t.
  GloveModel(int hardware_sensors, std::function<std::array<std::uint8_t, 22>(double t)> raw,
             double rate_hz = 100.0);

  void receive(std::string_view bytes, double now, Pieces& out);
  void tick(double now, Pieces& out);
  void setGlovePlugged(bool plugged) { plugged_ = plugged; }
  void setSamplingError(bool on) { sampling_error_ = on; }
  GloveFormat format() const { return format_; }
  bool streaming() const { return streaming_; }

 private:
  void sample(double now, Pieces& out);

  std::function<std::array<std::uint8_t, 22>(double)> raw_;
  double period_;
  std::string pending_;
  GloveFormat format_;
  bool streaming_ = true;  // powered up streaming
  bool plugged_ = true;
  bool sampling_error_ = false;
  double next_ = 0.0;
};

}  // namespace vistel::test
