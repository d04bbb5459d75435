// The live component's CAN input (docs/run.md, "CAN"): the read step both transports share, the
// counters it leaves for the publisher's health, and the loop of the CAN thread that reads a gs_usb
// adapter (a libusb bulk read blocks, so it cannot share the pose thread's INS poll) into a ring
// the pose thread drains. No allocation, lock or exception after start-up.
#pragma once

#include <array>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstdio>

#include "drivers/can/odometry_input.hpp"
#include "rt/clock.hpp"
#include "rt/spsc_ring.hpp"
#include "rt/watchdog.hpp"

namespace stac::runtime {

// The CAN input's counters for other threads: stored by the thread that reads CAN after each
// read, loaded by the publisher (each field on its own, relaxed).
class CanCounterCells {
 public:
  void store(const can::CanInputCounters& c) noexcept {
    const Words w = std::bit_cast<Words>(c);
    for (std::size_t i = 0; i < w.size(); ++i) cells_[i].store(w[i], std::memory_order_relaxed);
  }
  [[nodiscard]] can::CanInputCounters load() const noexcept {
    Words w{};
    for (std::size_t i = 0; i < w.size(); ++i) w[i] = cells_[i].load(std::memory_order_relaxed);
    return std::bit_cast<can::CanInputCounters>(w);
  }
  // gs_usb: updates dropped because the ring to the pose thread was full (the newest is dropped).
  std::atomic<std::uint64_t> ring_full{0};

 private:
  using Words = std::array<std::uint64_t, sizeof(can::CanInputCounters) / sizeof(std::uint64_t)>;
  static_assert(sizeof(Words) == sizeof(can::CanInputCounters), "counters are uint64 fields only");
  std::array<std::atomic<std::uint64_t>, std::tuple_size_v<Words>> cells_{};
};

// Where the CAN input reports: its watchdog entry and the counters health publishes.
struct CanReport {
  rt::Watchdog& watchdog;
  std::size_t input;  // the watchdog's index of CAN
  CanCounterCells& cells;
};

// One read of the CAN input: each decoded update goes to on_update and beats the watchdog, then
// the counters go to the cells. When the input is gone it is marked lost in the watchdog (status
// 2 in health) with one warning on stderr; the caller stops reading it, the run goes on.
template <class Reader, class OnUpdate>
can::InputEvent read_can(can::OdometryInput<Reader>& in, int timeout_ms, OnUpdate&& on_update,
                         CanReport& report) noexcept {
  const can::InputEvent e = in.read(timeout_ms, [&](const can::OdometryUpdate& u) {
    on_update(u);
    report.watchdog.beat(report.input, rt::monotonic_ns());
  });
  report.cells.store(in.counters());
  if (e == can::InputEvent::kGone) {
    std::fprintf(stderr, "stac run: warning: %s; no more odometry\n",
                 can::TransportTraits<Reader>::kGoneText);
    report.watchdog.lose(report.input);
  }
  return e;
}

// The CAN thread: reads (blocking) until stop() or the input is gone, which it returns. Each
// update goes to the pose thread through `ring`; when it is full the update is dropped and
// counted (cells.ring_full).
template <class Reader>
can::InputEvent read_can_until_end(can::OdometryInput<Reader>& in,
                                   rt::SpscRing<can::OdometryUpdate>& ring,
                                   CanReport& report) noexcept {
  const auto push = [&](const can::OdometryUpdate& u) {
    if (!ring.try_push(u)) report.cells.ring_full.fetch_add(1, std::memory_order_relaxed);
  };
  for (;;) {
    const can::InputEvent e = read_can(in, -1, push, report);
    if (e != can::InputEvent::kRead) return e;
  }
}

}  // namespace stac::runtime
