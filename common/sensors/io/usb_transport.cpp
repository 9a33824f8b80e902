#include "common/sensors/io/usb_transport.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <libusb.h>

namespace vistel {
namespace {

unsigned usbTimeoutMs(double timeout_s) {
  if (!(timeout_s > 0.0)) return 1;  // libusb: 0 would mean "wait forever"
  return static_cast<unsigned>(std::ceil(std::min(timeout_s, 3600.0) * 1000.0));
}

UsbStatus statusOf(int code) {
  switch (code) {
    case LIBUSB_SUCCESS:
      return UsbStatus::kOk;
    case LIBUSB_ERROR_TIMEOUT:
      return UsbStatus::kTimeout;
    case LIBUSB_ERROR_NO_DEVICE:
    case LIBUSB_ERROR_IO:
    case LIBUSB_ERROR_PIPE:
      return UsbStatus::kNoDevice;
    default:
      return UsbStatus::kFailed;
  }
}

// A libusb device handle with its context; releases both.
class LibusbBulkDevice final : public UsbBulkDevice {
 public:
  LibusbBulkDevice(libusb_context* ctx, libusb_device_handle* handle, const UsbConfig& config)
      : ctx_(ctx), handle_(handle), config_(config) {}
  ~LibusbBulkDevice() override {
    libusb_release_interface(handle_, config_.interface_number);
    libusb_close(handle_);
    libusb_exit(ctx_);
  }
  UsbStatus bulkTransfer(std::uint8_t endpoint, std::uint8_t* data, int length, int& transferred,
                         unsigned timeout_ms, std::string& error) override {
    transferred = 0;
    const int code =
        libusb_bulk_transfer(handle_, endpoint, data, length, &transferred, timeout_ms);
    if (code != LIBUSB_SUCCESS) error = libusb_strerror(static_cast<libusb_error>(code));
    return statusOf(code);
  }
  std::string describe() const override {
    return fmt::format("usb {:04x}:{:04x}", config_.vendor_id, config_.product_id);
  }

 private:
  libusb_context* ctx_;
  libusb_device_handle* handle_;
  UsbConfig config_;
};

}  // namespace

Result<std::unique_ptr<UsbBulkDevice>> openLibusbDevice(const UsbConfig& config) {
  const std::string name = fmt::format("usb {:04x}:{:04x}", config.vendor_id, config.product_id);
  libusb_context* ctx = nullptr;
  if (int code = libusb_init(&ctx); code != LIBUSB_SUCCESS) {
    return fail("{}: libusb_init failed: {}", name,
                libusb_strerror(static_cast<libusb_error>(code)));
  }
  libusb_device_handle* handle =
      libusb_open_device_with_vid_pid(ctx, config.vendor_id, config.product_id);
  if (handle == nullptr) {
    libusb_exit(ctx);
    return fail("{}: no such device (not plugged in, or no permission to open it)", name);
  }
  libusb_set_auto_detach_kernel_driver(handle, 1);
  if (int code = libusb_claim_interface(handle, config.interface_number); code != LIBUSB_SUCCESS) {
    libusb_close(handle);
    libusb_exit(ctx);
    return fail("{}: cannot claim interface {}: {}", name, config.interface_number,
                libusb_strerror(static_cast<libusb_error>(code)));
  }
  return std::unique_ptr<UsbBulkDevice>(new LibusbBulkDevice(ctx, handle, config));
}

UsbTransport::UsbTransport(std::unique_ptr<UsbBulkDevice> device, const UsbConfig& config)
    : device_(std::move(device)), config_(config) {}

IoResult UsbTransport::read(std::span<std::uint8_t> buffer, double timeout_s) {
  if (gone_) return {IoStatus::kUnplugged, 0, fmt::format("{}: device unplugged", describe())};
  if (packet_start_ == packet_end_) {
    int got = 0;
    std::string error;
    const UsbStatus s =
        device_->bulkTransfer(config_.endpoint_in, packet_.data(), static_cast<int>(packet_.size()),
                              got, usbTimeoutMs(timeout_s), error);
    got = std::clamp(got, 0, static_cast<int>(packet_.size()));
    packet_start_ = 0;
    packet_end_ = static_cast<std::size_t>(got);
    if (s == UsbStatus::kNoDevice) {
      gone_ = true;
      return {IoStatus::kUnplugged, 0, fmt::format("{}: device unplugged ({})", describe(), error)};
    }
    if (s == UsbStatus::kFailed)
      return {IoStatus::kFailed, 0, fmt::format("{}: bulk read failed: {}", describe(), error)};
    if (got == 0) return {IoStatus::kTimeout, 0, fmt::format("{}: no data", describe())};
  }
  const std::size_t n = std::min(buffer.size(), packet_end_ - packet_start_);
  std::memcpy(buffer.data(), packet_.data() + packet_start_, n);
  packet_start_ += n;
  return {IoStatus::kOk, n, {}};
}

IoResult UsbTransport::write(std::span<const std::uint8_t> bytes, double timeout_s) {
  if (gone_) return {IoStatus::kUnplugged, 0, fmt::format("{}: device unplugged", describe())};
  std::size_t done = 0;
  std::array<std::uint8_t, 64> chunk{};
  while (done < bytes.size()) {
    const std::size_t n = std::min(chunk.size(), bytes.size() - done);
    std::memcpy(chunk.data(), bytes.data() + done, n);
    int sent = 0;
    std::string error;
    const UsbStatus s =
        device_->bulkTransfer(config_.endpoint_out, chunk.data(), static_cast<int>(n), sent,
                              usbTimeoutMs(timeout_s), error);
    done += static_cast<std::size_t>(std::clamp(sent, 0, static_cast<int>(n)));
    if (s == UsbStatus::kNoDevice) {
      gone_ = true;
      return {IoStatus::kUnplugged, done,
              fmt::format("{}: device unplugged ({})", describe(), error)};
    }
    if (s == UsbStatus::kFailed)
      return {IoStatus::kFailed, done, fmt::format("{}: bulk write failed: {}", describe(), error)};
    if (s == UsbStatus::kTimeout && sent == 0)
      return {IoStatus::kTimeout, done, fmt::format("{}: write timed out", describe())};
  }
  return {IoStatus::kOk, done, {}};
}

void UsbTransport::discardInput() {
  packet_start_ = packet_end_ = 0;
  for (int i = 0; i < 64 && !gone_; ++i) {  // empty the device's queue
    int got = 0;
    std::string error;
    const UsbStatus s = device_->bulkTransfer(config_.endpoint_in, packet_.data(),
                                              static_cast<int>(packet_.size()), got, 1, error);
    if (s == UsbStatus::kNoDevice) gone_ = true;
    if (s != UsbStatus::kOk || got == 0) break;
  }
}

}  // namespace vistel
