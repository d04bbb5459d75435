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
  std::uint32_t seq = s.seq;
  bool new_stream = false;
  if ((s.flags & kTcpSyn) != 0 || !started_) {
    for (auto& slot : slots_) slot.used = false;
    started_ = true;
    new_stream = true;
    ++counters_.streams;
    if ((s.flags & kTcpSyn) != 0) ++seq;  // the SYN takes one sequence number
    expected_ = seq;
  }
  if (s.payload.empty()) return new_stream;
  const std::int64_t start = seq_diff(seq, expected_);
  if (start + static_cast<std::int64_t>(s.payload.size()) <= 0) {
    ++counters_.retransmitted;
    return new_stream;
  }
  Slot* free = nullptr;
  for (auto& slot : slots_) {
    if (!slot.used) {
      free = &slot;
      break;
    }
  }
  if (start <= 0 || free == nullptr || s.payload.size() > slot_bytes_) {
    // In order, or no room to wait: next() delivers it (after skipping the hole if need be).
    current_ = s.payload;
    current_seq_ = seq;
    return new_stream;
  }
  ++counters_.out_of_order;
  const auto index = static_cast<std::size_t>(free - slots_.data());
  std::memcpy(store_.data() + index * slot_bytes_, s.payload.data(), s.payload.size());
  *free = Slot{seq, s.payload.size(), true};
  return new_stream;
}

bool TcpReassembler::next(std::span<const std::uint8_t>& out) noexcept {
  release_delivered();
  while (true) {
    // Stored segments that the stream has reached (or passed: then they were retransmitted).
    for (auto& slot : slots_) {
      if (!slot.used) continue;
      const std::int64_t start = seq_diff(slot.seq, expected_);
      const std::int64_t end = start + static_cast<std::int64_t>(slot.length);
      if (start > 0) continue;
      if (end <= 0) {
        ++counters_.retransmitted;
        slot.used = false;
        continue;
      }
      const auto index = static_cast<std::size_t>(&slot - slots_.data());
      out = {store_.data() + index * slot_bytes_ + static_cast<std::size_t>(-start),
             static_cast<std::size_t>(end)};
      counters_.overlap_bytes += static_cast<std::uint64_t>(-start);
      expected_ += static_cast<std::uint32_t>(out.size());
      counters_.bytes += out.size();
      delivered_ = &slot;
      return true;
    }
    Slot* first = earliest();
    if (!current_.empty()) {
      const std::int64_t start = seq_diff(current_seq_, expected_);
      if (start > 0) {  // the store was full: skip the hole before the earliest bytes we hold
        skip_to(first != nullptr && seq_diff(first->seq, current_seq_) < 0 ? first->seq
                                                                           : current_seq_);
        continue;
      }
      const std::int64_t end = start + static_cast<std::int64_t>(current_.size());
      if (end <= 0) {
        ++counters_.retransmitted;
        current_ = {};
        continue;
      }
      out = current_.subspan(static_cast<std::size_t>(-start));
      counters_.overlap_bytes += static_cast<std::uint64_t>(-start);
      current_ = {};
      expected_ += static_cast<std::uint32_t>(out.size());
      counters_.bytes += out.size();
      return true;
    }
    if (finishing_ && first != nullptr) {
      skip_to(first->seq);
      continue;
    }
    return false;
  }
}

void TcpReassembler::finish() noexcept {
  finishing_ = true;
}

}  // namespace stac::io
