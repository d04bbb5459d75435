// One CAN transport read through the DBC signal map: frames -> odometry updates, the same read
// step for a SocketCAN raw socket, a gs_usb adapter and cannelloni datagrams (CAN over UDP). What
// differs between the transports is a trait: which read result means the bus is gone, and how their
// drop counters map to one set of causes. SocketCAN's kernel filter passes only the mapped ids; a
// gs_usb adapter delivers the whole bus (so does a cannelloni gateway), and the decoder drops and
// counts every frame outside the map (`not_mapped`).
#pragma once

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "drivers/can/cannelloni.hpp"
#include "drivers/can/gs_usb_device.hpp"
#include "drivers/can/odometry.hpp"
#include "drivers/can/socketcan.hpp"

namespace stac::can {

// What became of one input's frames since it opened.
struct CanInputCounters {
  std::uint64_t frames = 0;         // classic frames the transport returned
  std::uint64_t updates = 0;        // of those, frames carrying speed or yaw rate
  std::uint64_t not_mapped = 0;     // ids outside the signal map: dropped in user space
  std::uint64_t kernel_drops = 0;   // SocketCAN, cannelloni: the kernel's receive queue was full
  std::uint64_t overflows = 0;      // gs_usb: frames the adapter flagged as following a loss
  std::uint64_t can_fd = 0;         // CAN FD frames: dropped
  std::uint64_t malformed = 0;      // SocketCAN records of another size, gs_usb short transfers,
                                    // cannelloni datagrams of another version or cut short
  std::uint64_t lost = 0;           // cannelloni: datagrams missing from the sequence numbers
  std::uint64_t other_channel = 0;  // gs_usb: frames of another adapter channel, dropped
  std::uint64_t read_errors = 0;    // failed reads that did not end the input (retried)
  bool operator==(const CanInputCounters&) const = default;
};

enum class InputEvent : std::uint8_t {
  kRead,     // frames read (none on a timeout), or a failed read to retry
  kStopped,  // after stop()
  kGone,     // the interface or the device went away: no frame will come any more
};

template <class Reader>
struct TransportTraits;

template <>
struct TransportTraits<SocketCanReader> {
  static constexpr const char* kName = "socketcan";
  static constexpr const char* kGoneText = "the CAN interface closed";
  static constexpr int kGone = SocketCanReader::kClosed;  // a socket error (kError) is retried
  static void count(const SocketCanCounters& c, CanInputCounters& out) noexcept {
    out.frames = c.frames;
    out.kernel_drops = c.kernel_drops;
    out.can_fd = c.can_fd;
    out.malformed = c.bad_size;
  }
};

template <>
struct TransportTraits<GsUsbDevice> {
  static constexpr const char* kName = "gs_usb";
  static constexpr const char* kGoneText =
      "the gs_usb adapter went away (unplugged or a USB error)";
  static constexpr int kGone = GsUsbDevice::kError;
  static void count(const GsUsbCounters& c, CanInputCounters& out) noexcept {
    out.frames = c.frames;
    out.overflows = c.overflows;
    out.can_fd = c.can_fd;
    out.malformed = c.truncated;
    out.other_channel = c.other_channel;
  }
};

template <>
struct TransportTraits<CannelloniReader> {
  static constexpr const char* kName = "cannelloni";
  static constexpr const char* kGoneText = "the cannelloni UDP socket failed";
  // No read returns it: a bound UDP socket does not go away (a socket error, kError, is retried).
  static constexpr int kGone = std::numeric_limits<int>::min();
  static void count(const CannelloniCounters& c, CanInputCounters& out) noexcept {
    out.frames = c.frames;
    out.kernel_drops = c.kernel_drops;
    out.can_fd = c.can_fd;
    out.malformed = c.malformed;
    out.lost = c.lost;
  }
};

template <class Reader>
class OdometryInput {
 public:
  // Takes the opened transport and the decoder; `batch` frames per read are allocated here.
  OdometryInput(Reader reader, OdometryDecoder decoder, std::size_t batch = 64)
      : reader_(std::move(reader)), decoder_(std::move(decoder)), frames_(batch) {}

  // One read of up to timeout_ms (the transport's meaning: -1 until a frame or stop(), 0 only what
  // is there); calls on_update(const OdometryUpdate&) for each frame with speed or yaw rate.
  // No allocation (nor in on_update, the caller's part).
  template <class OnUpdate>
  InputEvent read(int timeout_ms, OnUpdate&& on_update) noexcept {
    const int n = reader_.read(frames_, timeout_ms);
    if (n == Reader::kStopped) return InputEvent::kStopped;
    if (n == TransportTraits<Reader>::kGone) return InputEvent::kGone;
    if (n < 0) {
      ++read_errors_;
      return InputEvent::kRead;
    }
    for (int i = 0; i < n; ++i) {
      const OdometryUpdate u = decoder_.decode(frames_[static_cast<std::size_t>(i)]);
      if (u.has_speed || u.has_yaw_rate) on_update(u);
    }
    return InputEvent::kRead;
  }

  // Any thread: the current and every later read() returns kStopped (gs_usb: within its
  // transfer slice, 100 ms).
  void stop() noexcept { reader_.stop(); }

  // The reading thread (or any thread once it ended).
  [[nodiscard]] CanInputCounters counters() const noexcept {
    CanInputCounters c;
    TransportTraits<Reader>::count(reader_.counters(), c);
    c.updates = decoder_.counters().decoded;
    c.not_mapped = decoder_.counters().not_mapped;
    c.read_errors = read_errors_;
    return c;
  }
  const OdometryDecoder& decoder() const noexcept { return decoder_; }

 private:
  Reader reader_;
  OdometryDecoder decoder_;
  std::vector<Frame> frames_;
  std::uint64_t read_errors_ = 0;
};

}  // namespace stac::can
