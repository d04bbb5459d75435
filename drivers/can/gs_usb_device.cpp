#include "drivers/can/gs_usb_device.hpp"

#include <libusb.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <utility>

#include "rt/clock.hpp"

namespace stac::can {
namespace {

constexpr int kInterface = 0;
constexpr unsigned kControlTimeoutMs = 1000;
// bmRequestType: vendor request to the interface, host-to-device (0x41) or device-to-host (0xC1).
constexpr std::uint8_t kVendorInterface = static_cast<std::uint8_t>(LIBUSB_REQUEST_TYPE_VENDOR) |
                                          static_cast<std::uint8_t>(LIBUSB_RECIPIENT_INTERFACE);
constexpr std::uint8_t kOut = static_cast<std::uint8_t>(LIBUSB_ENDPOINT_OUT) | kVendorInterface;
constexpr std::uint8_t kIn = static_cast<std::uint8_t>(LIBUSB_ENDPOINT_IN) | kVendorInterface;
static_assert(kOut == 0x41 && kIn == 0xC1);

std::string usb_error(int code) {
  return std::string(libusb_error_name(code));
}

std::string id_text() {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%04x:%04x", gs_usb::kVendorId, gs_usb::kProductId);
  return buf;
}

// open()'s and check_present()'s error when no adapter could be opened.
rt::Unexpected<rt::Error> no_adapter(const std::string& what) {
  return rt::make_error(what +
                        "no gs_usb/candleLight adapter found, or no permission to open it: "
                        "check `lsusb -d " +
                        id_text() +
                        "` and a udev rule granting access "
                        "(deploy/60-stac-gs-usb.rules, docs/can.md)");
}

template <class T>
int control(libusb_device_handle* h, std::uint8_t type, gs_usb::Request request,
            std::uint16_t value, T& body) {
  return libusb_control_transfer(h, type, static_cast<std::uint8_t>(request), value, kInterface,
                                 reinterpret_cast<unsigned char*>(&body), sizeof(T),
                                 kControlTimeoutMs);
}

}  // namespace

rt::Status GsUsbDevice::check_present() {
  const std::string what = "gs_usb (" + id_text() + "): ";
  libusb_context* context = nullptr;
  if (const int rc = libusb_init(&context); rc != 0) {
    return rt::make_error(what + "libusb_init failed (" + usb_error(rc) +
                          "); is /dev/bus/usb available?");
  }
  libusb_device_handle* handle =
      libusb_open_device_with_vid_pid(context, gs_usb::kVendorId, gs_usb::kProductId);
  if (handle != nullptr) libusb_close(handle);
  libusb_exit(context);
  if (handle == nullptr) {
    return no_adapter(what);
  }
  return {};
}

rt::Result<GsUsbDevice> GsUsbDevice::open(const GsUsbConfig& config) {
  GsUsbDevice d;
  d.config_ = config;
  const std::string what = "gs_usb (" + id_text() + "): ";
  if (const int rc = libusb_init(&d.context_); rc != 0) {
    d.context_ = nullptr;
    return rt::make_error(what + "libusb_init failed (" + usb_error(rc) +
                          "); is /dev/bus/usb available?");
  }
  d.handle_ = libusb_open_device_with_vid_pid(d.context_, gs_usb::kVendorId, gs_usb::kProductId);
  if (d.handle_ == nullptr) {
    return no_adapter(what);
  }
  libusb_set_auto_detach_kernel_driver(d.handle_, 1);  // unbind the kernel gs_usb driver if bound
  if (const int rc = libusb_claim_interface(d.handle_, kInterface); rc != 0) {
    return rt::make_error(what + "cannot claim interface 0 (" + usb_error(rc) +
                          "); another program uses it?");
  }
  d.claimed_ = true;
  gs_usb::HostConfig host{gs_usb::kHostFormatLittleEndian};
  if (const int rc = control(d.handle_, kOut, gs_usb::Request::kHostFormat, 1, host); rc < 0) {
    return rt::make_error(what + "HOST_FORMAT request failed (" + usb_error(rc) + ")");
  }
  gs_usb::DeviceConfig dc{};
  if (const int rc = control(d.handle_, kIn, gs_usb::Request::kDeviceConfig, 1, dc); rc < 0) {
    return rt::make_error(what + "DEVICE_CONFIG request failed (" + usb_error(rc) + ")");
  }
  if (config.channel > dc.icount) {
    return rt::make_error(what + "channel " + std::to_string(config.channel) +
                          " requested, the adapter has " + std::to_string(dc.icount + 1));
  }
  gs_usb::BtConst bt{};
  if (const int rc = control(d.handle_, kIn, gs_usb::Request::kBtConst, config.channel, bt);
      rc < 0) {
    return rt::make_error(what + "BT_CONST request failed (" + usb_error(rc) + ")");
  }
  if (!gs_usb::compute_bit_timing(bt, config.bitrate_bps, d.timing_)) {
    return rt::make_error(what + "bitrate " + std::to_string(config.bitrate_bps) +
                          " bit/s cannot be made exactly from the adapter's " +
                          std::to_string(bt.fclk_can) + " Hz clock");
  }
  if (const int rc =
          control(d.handle_, kOut, gs_usb::Request::kBitTiming, config.channel, d.timing_);
      rc < 0) {
    return rt::make_error(what + "BITTIMING request failed (" + usb_error(rc) + ")");
  }
  d.config_.hw_timestamp = config.hw_timestamp && (bt.feature & gs_usb::kFlagHwTimestamp) != 0;
  gs_usb::DeviceMode mode{gs_usb::kModeStart,
                          (config.listen_only ? gs_usb::kFlagListenOnly : 0u) |
                              (d.config_.hw_timestamp ? gs_usb::kFlagHwTimestamp : 0u)};
  if (config.listen_only && (bt.feature & gs_usb::kFlagListenOnly) == 0) {
    return rt::make_error(
        what +
        "the adapter cannot listen only; set can.gs_usb_listen_only: false to allow "
        "acknowledging frames on the bus");
  }
  if (const int rc = control(d.handle_, kOut, gs_usb::Request::kMode, config.channel, mode);
      rc < 0) {
    return rt::make_error(what + "MODE start failed (" + usb_error(rc) + ")");
  }
  return d;
}

GsUsbDevice::GsUsbDevice(GsUsbDevice&& o) noexcept
    : context_(std::exchange(o.context_, nullptr)),
      handle_(std::exchange(o.handle_, nullptr)),
      config_(o.config_),
      timing_(o.timing_),
      claimed_(std::exchange(o.claimed_, false)),
      stop_(o.stop_.load()),
      counters_(o.counters_) {}

GsUsbDevice::~GsUsbDevice() {
  close();
}

void GsUsbDevice::close() noexcept {
  if (handle_ != nullptr) {
    if (claimed_) {
      gs_usb::DeviceMode reset{gs_usb::kModeReset, 0};
      control(handle_, kOut, gs_usb::Request::kMode, config_.channel, reset);
      libusb_release_interface(handle_, kInterface);
    }
    libusb_close(handle_);
    handle_ = nullptr;
  }
  if (context_ != nullptr) {
    libusb_exit(context_);
    context_ = nullptr;
  }
}

int GsUsbDevice::read(std::span<Frame> out, int timeout_ms) noexcept {
  if (out.empty()) return 0;
  std::uint8_t buffer[64];
  int waited = 0;
  while (!stop_.load(std::memory_order_relaxed)) {
    const int slice = timeout_ms < 0 ? config_.transfer_timeout_ms
                                     : std::min(config_.transfer_timeout_ms, timeout_ms - waited);
    if (timeout_ms >= 0 && slice <= 0) return 0;
    int got = 0;
    const int rc = libusb_bulk_transfer(handle_, gs_usb::kEndpointIn, buffer, sizeof(buffer), &got,
                                        static_cast<unsigned>(slice));
    waited += slice;
    if (rc == LIBUSB_ERROR_TIMEOUT && got == 0) continue;
    if (rc != 0 && rc != LIBUSB_ERROR_TIMEOUT) return kError;
    const auto d = gs_usb::decode_frame(
        std::span<const std::uint8_t>(buffer, static_cast<std::size_t>(got)), config_.hw_timestamp);
    if (d.overflow) ++counters_.overflows;
    switch (d.status) {
      case gs_usb::DecodeStatus::kTruncated:
        ++counters_.truncated;
        continue;
      case gs_usb::DecodeStatus::kCanFd:
        ++counters_.can_fd;
        continue;
      case gs_usb::DecodeStatus::kEcho:
        ++counters_.echoes;
        continue;
      case gs_usb::DecodeStatus::kReceived:
        break;
    }
    if (d.channel != config_.channel) {
      ++counters_.other_channel;
      continue;
    }
    out[0] = d.frame;
    out[0].stamp_ns = rt::realtime_ns();
    ++counters_.frames;
    return 1;
  }
  return kStopped;
}

}  // namespace stac::can
