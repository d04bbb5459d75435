#include "drivers/io/tcp_stream.hpp"

#include <cstring>

namespace stac::io {
namespace {

// Signed distance a - b in sequence space (wraps at 2^32).
std::int64_t seq_diff(std::uint32_t a, std::uint32_t b) noexcept {
  return static_cast<std::int32_t>(a - b);
}

}  // namespace

TcpReassembler::TcpReassembler(std::size_t slots, std::size_t slot_bytes)
    : slots_(slots), store_(slots * slot_bytes), slot_bytes_(slot_bytes) {}

void TcpReassembler::release_delivered() noexcept {
  if (delivered_ != nullptr) delivered_->used = false;
  delivered_ = nullptr;
}

TcpReassembler::Slot* TcpReassembler::earliest() noexcept {
  Slot* best = nullptr;
  for (auto& s : slots_) {
    if (s.used && (best == nullptr || seq_diff(s.seq, best->seq) < 0)) best = &s;
  }
  return best;
}

void TcpReassembler::skip_to(std::uint32_t seq) noexcept {
  if (seq_diff(seq, expected_) <= 0) return;
  ++counters_.gaps;
  counters_.gap_bytes += static_cast<std::uint64_t>(seq_diff(seq, expected_));
  expected_ = seq;
}

bool TcpReassembler::add(const TcpSegment& s) noexcept {
  release_delivered();
  current_ = {};
  finishing_ = false;
  ++counters_.segments;
  std::span<const std::uint8_t> payload = s.payload;
  std::uint32_t seq = s.seq;
  bool new_stream = false;
  if ((s.flags & kTcpSyn) != 0 || !started_) {
    for (auto& slot : slots_) slot.used = false;
    started_ = true;
    new_stream = true;
    ++counters_.streams;
    expected_ = (s.flags & kTcpSyn) != 0 ? seq + 1 : seq;
    if ((s.flags & kTcpSyn) != 0) ++seq;  // the SYN takes one sequence number
  }
  if (payload.empty()) return new_stream;
  const std::int64_t start = seq_diff(seq, expected_);
  const std::int64_t end = start + static_cast<std::int64_t>(payload.size());
  if (end <= 0) {
    ++counters_.retransmitted;
    return new_stream;
  }
  if (start <= 0) {
    counters_.overlap_bytes += static_cast<std::uint64_t>(-start);
    current_ = payload.subspan(static_cast<std::size_t>(-start));
    return new_stream;
  }
  Slot* free = nullptr;
  for (auto& slot : slots_) {
    if (!slot.used) { free = &slot; break; }
  }
  if (free == nullptr || payload.size() > slot_bytes_) {
    // No room to wait for the hole: skip it; stored bytes now behind us are part of the gap.
    skip_to(seq);
    for (auto& slot : slots_) {
      if (slot.used && seq_diff(slot.seq + static_cast<std::uint32_t>(slot.length), expected_) <= 0) {
        slot.used = false;
      }
    }
    current_ = payload;
    return new_stream;
  }
  ++counters_.out_of_order;
  const auto index = static_cast<std::size_t>(free - slots_.data());
  std::memcpy(store_.data() + index * slot_bytes_, payload.data(), payload.size());
  *free = Slot{seq, payload.size(), true};
  return new_stream;
}

bool TcpReassembler::next(std::span<const std::uint8_t>& out) noexcept {
  release_delivered();
  if (!current_.empty()) {
    out = current_;
    current_ = {};
    expected_ += static_cast<std::uint32_t>(out.size());
    counters_.bytes += out.size();
    return true;
  }
  for (bool again = true; again;) {
    again = false;
    for (auto& slot : slots_) {
      if (!slot.used) continue;
      const std::int64_t start = seq_diff(slot.seq, expected_);
      const std::int64_t end = start + static_cast<std::int64_t>(slot.length);
      if (end <= 0) {  // a stored copy of bytes that came again in order
        ++counters_.retransmitted;
        slot.used = false;
        again = true;
        continue;
      }
      if (start > 0) continue;
      const auto index = static_cast<std::size_t>(&slot - slots_.data());
      out = {store_.data() + index * slot_bytes_ + static_cast<std::size_t>(-start),
             static_cast<std::size_t>(end)};
      counters_.overlap_bytes += static_cast<std::uint64_t>(-start);
      expected_ += static_cast<std::uint32_t>(out.size());
      counters_.bytes += out.size();
      delivered_ = &slot;
      return true;
    }
    if (!again && finishing_) {
      if (Slot* s = earliest()) {
        skip_to(s->seq);
        again = true;
      }
    }
  }
  return false;
}

void TcpReassembler::finish() noexcept { finishing_ = true; }

}  // namespace stac::io
