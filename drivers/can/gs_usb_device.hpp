// A gs_usb / candleLight USB-CAN adapter driven through libusb-1.0: the vehicle CAN bus where
// the kernel has no SocketCAN driver. Opens the first adapter with VID 0x1d50 PID 0x606f,
// claims interface 0 (detaching the kernel's gs_usb driver if bound), announces the host byte
// order, sets the bit timing for the bitrate and starts the channel; reads received frames.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>

#include "drivers/can/frame.hpp"
#include "drivers/can/gs_usb.hpp"
#include "rt/expected.hpp"

struct libusb_context;
struct libusb_device_handle;

namespace stac::can {

struct GsUsbConfig {
  std::uint32_t bitrate_bps = 500'000;
  std::uint8_t channel = 0;
  bool listen_only = true;   // never acknowledge or send on the vehicle bus
  bool hw_timestamp = true;  // 24-byte frames with the adapter's microsecond clock, if supported
  int transfer_timeout_ms = 100;  // bulk-read slice: how quickly stop() is noticed
};

struct GsUsbCounters {
  std::uint64_t frames = 0;     // received frames returned
  std::uint64_t echoes = 0;     // echoes of frames we sent
  std::uint64_t truncated = 0;  // transfers shorter than a frame: dropped
  std::uint64_t can_fd = 0;     // CAN FD frames: dropped
  std::uint64_t other_channel = 0;
  std::uint64_t overflows = 0;  // frames flagged: the adapter lost frames before them
};

class GsUsbDevice {
 public:
  static constexpr int kStopped = -1;
  static constexpr int kError = -2;

  // Errors say what failed and what to do: no adapter present (VID:PID, lsusb), no permission
  // (udev rule), interface busy, bitrate not reachable with the adapter's clock, channel absent.
  static rt::Result<GsUsbDevice> open(const GsUsbConfig& config);
  // Whether open() would find an adapter this process may open (`stac-node --check`): the
  // device looked up and opened for a moment, its interface left unclaimed, so a service that
  // holds it goes on undisturbed. The same errors as open() for a missing adapter or permission.
  static rt::Status check_present();
  GsUsbDevice(GsUsbDevice&&) noexcept;
  GsUsbDevice(const GsUsbDevice&) = delete;
  GsUsbDevice& operator=(const GsUsbDevice&) = delete;
  GsUsbDevice& operator=(GsUsbDevice&&) = delete;
  ~GsUsbDevice();  // resets the channel, releases the interface

  // Waits up to timeout_ms for one bulk transfer and returns the received frames it carried
  // (0 on timeout), kStopped after stop(), kError when the device went away. Stamps: host
  // CLOCK_REALTIME at reception. No allocation.
  int read(std::span<Frame> out, int timeout_ms) noexcept;
  // Any thread.
  void stop() noexcept { stop_.store(true, std::memory_order_relaxed); }

  const GsUsbCounters& counters() const noexcept { return counters_; }
  const gs_usb::BitTiming& bit_timing() const noexcept { return timing_; }

 private:
  GsUsbDevice() = default;
  void close() noexcept;

  libusb_context* context_ = nullptr;
  libusb_device_handle* handle_ = nullptr;
  GsUsbConfig config_;
  gs_usb::BitTiming timing_{};
  bool claimed_ = false;
  std::atomic<bool> stop_{false};
  GsUsbCounters counters_;
};

}  // namespace stac::can
