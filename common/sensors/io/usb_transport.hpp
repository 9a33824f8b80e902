// UsbTransport: the FASTRAK family over USB — the same command and record byte stream as
// the serial port, carried by a pair of bulk endpoints. The few USB calls it needs sit
// behind UsbBulkDevice (libusb in openLibusbDevice; a fake in tests, since no USB devices
// exist on the build machines).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "common/base/result.hpp"
#include "common/sensors/io/byte_transport.hpp"
#include "common/sensors/sensor_config.hpp"

namespace vistel {

enum class UsbStatus : std::uint8_t { kOk, kTimeout, kNoDevice, kFailed };

class UsbBulkDevice {
 public:
  virtual ~UsbBulkDevice() = default;
  // One bulk transfer on `endpoint` (bit 7 set = IN); `transferred` says how many bytes
  // moved (a timed-out transfer may still have moved some). `error` gets the OS/USB reason.
  virtual UsbStatus bulkTransfer(std::uint8_t endpoint, std::uint8_t* data, int length,
                                 int& transferred, unsigned timeout_ms, std::string& error) = 0;
  virtual std::string describe() const = 0;
};

// Opens the first device with the configured vendor/product id through libusb, detaches a
// kernel driver if one is bound, and claims the interface. Errors name the ids and reason.
Result<std::unique_ptr<UsbBulkDevice>> openLibusbDevice(const UsbConfig& config);

class UsbTransport final : public ByteTransport {
 public:
  UsbTransport(std::unique_ptr<UsbBulkDevice> device, const UsbConfig& config);
  IoResult read(std::span<std::uint8_t> buffer, double timeout_s) override;
  IoResult write(std::span<const std::uint8_t> bytes, double timeout_s) override;
  void discardInput() override;
  std::string describe() const override { return device_->describe(); }

 private:
  std::unique_ptr<UsbBulkDevice> device_;
  UsbConfig config_;
  std::array<std::uint8_t, 512> packet_{};  // one IN transfer's worth
  std::size_t packet_start_ = 0;
  std::size_t packet_end_ = 0;
  bool gone_ = false;
};

}  // namespace vistel
