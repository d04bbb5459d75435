// The receiver thread: the Velodyne's UDP datagrams into the scan stream; wakes perception when
// a scan is complete. After a stop request it reads what its socket already holds, then ends.
#include <array>
#include <chrono>
#include <thread>

#include "rt/clock.hpp"
#include "runtime/live.hpp"

namespace stac::runtime {
namespace {

// After a stop request the receiver reads what its socket holds for at most this long (under a
// flood that never lets the socket run empty).
constexpr std::int64_t kStopDrainNs = 300'000'000;
constexpr int kReceiveTimeoutMs = 100;

}  // namespace

void receiver_loop(Component::Live& live) noexcept {
  io::UdpReceiver& receiver = *live.receiver;
  velodyne::ScanStream& stream = *live.stream;
  std::array<io::Datagram, 32> batch{};
  std::int64_t stop_seen_ns = 0;
  for (;;) {
    const bool stopping = live.stopping.load(std::memory_order_acquire);
    if (stopping && stop_seen_ns == 0) stop_seen_ns = rt::monotonic_ns();
    const int n = receiver.receive(batch, stopping ? 0 : kReceiveTimeoutMs);
    if (n == io::UdpReceiver::kStopped || (stopping && n == 0)) break;
    if (stopping && rt::monotonic_ns() - stop_seen_ns > kStopDrainNs) break;
    if (n == io::UdpReceiver::kError) {  // counted; a short pause, so a lasting error cannot spin
      live.counts.add(Count::kReceiveErrors);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    const velodyne::AssemblerCounters& ac = stream.assembler().counters();
    const auto rejected = [&] { return ac.wrong_size + ac.invalid_block + ac.duplicates; };
    const std::uint64_t rejected_before = rejected();
    bool scan_ready = false;
    for (int i = 0; i < n; ++i) {
      const io::Datagram& d = batch[static_cast<std::size_t>(i)];
      scan_ready = stream.add_packet(d.payload, d.stamp_ns) || scan_ready;
    }
    if (scan_ready) live.scans_ready.notify();
    if (n > 0) {
      // Only a packet the decoder took shows the sensor alive (not garbage on its port).
      if (rejected() - rejected_before < static_cast<std::uint64_t>(n))
        live.watchdog.beat(kLidar, rt::monotonic_ns());
      live.counts.add(Count::kPackets, static_cast<std::uint64_t>(n));
      live.counts.set(Count::kWrongSize, ac.wrong_size);
      live.counts.set(Count::kInvalidBlock, ac.invalid_block);
      live.counts.set(Count::kDuplicates, ac.duplicates);
      live.counts.set(Count::kLateFirings, ac.late_firings);
      live.counts.set(Count::kOtherModel, ac.model_mismatch);
    }
    live.counts.set(Count::kKernelDrops, receiver.counters().kernel_drops);
  }
  live.receiver_done.store(true, std::memory_order_release);
  live.scans_ready.notify();
}

}  // namespace stac::runtime
