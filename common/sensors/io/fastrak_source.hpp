// FastrakSource: a FASTRAK-class tracker driver (PROTOCOLS.md §1) over any ByteTransport
// (a serial port, or the same byte stream over USB bulk endpoints).
//
// open() initialises the unit: stops continuous output, drains the line, optionally checks
// that a status record ('2', station, 'S', ..., LF) answers an `S`, sends the stations,
// output lists, units and encoding (fastrakInitCommands), and starts continuous output or
// not. poll() then reads records (continuous), or sends `P` and waits for one record per
// station (polled); each record goes through the station map into the frame, converted to
// metres and into tracker space by the transmitter placement. Garbage, split records and
// unknown stations are survived (FastrakParser resynchronises; counters say how much was
// skipped); a closed or hung-up port is kUnplugged. Allocation-free per poll.
#pragma once

#include <array>
#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "common/base/result.hpp"
#include "common/sensors/fastrak_parser.hpp"
#include "common/sensors/io/byte_transport.hpp"
#include "common/sensors/sensor_config.hpp"
#include "common/sensors/sensor_source.hpp"

namespace vistel {

// Seconds on a monotonic clock (injectable for tests).
using SourceClock = std::function<double()>;
SourceClock steadySeconds();

class FastrakSource final : public SensorSource {
 public:
  static Result<std::unique_ptr<FastrakSource>> open(std::unique_ptr<ByteTransport> transport,
                                                     const TrackerConfig& config,
                                                     SourceClock clock = steadySeconds());
  PollResult poll(double timeout_s, SensorFrame& frame) override;
  std::string describe() const override;

  std::uint64_t recordCount() const { return parser_.recordCount(); }
  std::uint64_t discardedBytes() const { return parser_.discardedBytes(); }
  std::uint64_t unknownStationRecords() const { return unknown_station_; }

 private:
  FastrakSource(std::unique_ptr<ByteTransport> transport, const TrackerConfig& config,
                SourceClock clock);
  Status initialise();
  IoResult send(std::string_view command);
  // Reads whatever arrives within timeout_s into the parser and applies complete records;
  // returns how many records were applied, or a non-OK IoResult.
  IoResult pump(double timeout_s, int& applied);

  std::unique_ptr<ByteTransport> transport_;
  TrackerConfig config_;
  SourceClock clock_;
  FastrakParser parser_;
  std::array<int, kFastrakMaxStations + 1> site_of_station_{};  // -1 when not worn
  std::array<std::uint8_t, 512> buffer_{};
  SensorFrame state_;
  std::uint64_t sequence_ = 0;
  std::uint64_t unknown_station_ = 0;
  unsigned heard_ = 0;  // stations heard since the last poll request (bit per station)
};

}  // namespace vistel
