// CyberGloveSource: a CyberGlove-class glove driver (PROTOCOLS.md §3) over a ByteTransport.
//
// open() stops any streaming (`^c`, and Ctrl-C for boxes that read it so), drains, asks how
// many sensors are enabled (`?N`) and sets the configured count (`N n`) when it differs,
// then starts streaming (`S`) unless polling. poll() reads records (streaming) or sends `G`
// and waits for one; samples are calibrated to radians into frame.gloves[hand]. A box that
// reports `e g` (glove not plugged in) and a port that hangs up are kUnplugged; `e s`
// (sampling problem) is counted and skipped. Allocation-free per poll.
#pragma once

#include <array>
#include <memory>
#include <string>

#include "common/base/result.hpp"
#include "common/sensors/cyberglove_protocol.hpp"
#include "common/sensors/io/byte_transport.hpp"
#include "common/sensors/io/fastrak_source.hpp"
#include "common/sensors/sensor_config.hpp"
#include "common/sensors/sensor_source.hpp"

namespace vistel {

class CyberGloveSource final : public SensorSource {
 public:
  static Result<std::unique_ptr<CyberGloveSource>> open(std::unique_ptr<ByteTransport> transport,
                                                        const GloveDeviceConfig& config,
                                                        SourceClock clock = steadySeconds());
  PollResult poll(double timeout_s, SensorFrame& frame) override;
  std::string describe() const override;

  std::uint64_t recordCount() const { return parser_.recordCount(); }
  std::uint64_t samplingErrors() const { return sampling_errors_; }
  std::uint64_t discardedBytes() const { return parser_.discardedBytes(); }

 private:
  CyberGloveSource(std::unique_ptr<ByteTransport> transport, const GloveDeviceConfig& config,
                   SourceClock clock);
  Status initialise();
  IoResult send(std::string_view bytes);
  // Reads one query reply: `?`, the letter, `count` value bytes, NUL.
  Result<std::string> queryReply(char letter, std::size_t count);

  std::unique_ptr<ByteTransport> transport_;
  GloveDeviceConfig config_;
  SourceClock clock_;
  CyberGloveParser parser_;
  std::array<std::uint8_t, 256> buffer_{};
  GloveReading reading_;
  std::uint64_t sequence_ = 0;
  std::uint64_t sampling_errors_ = 0;
};

}  // namespace vistel
