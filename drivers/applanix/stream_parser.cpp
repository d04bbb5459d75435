#include "drivers/applanix/stream_parser.hpp"

#include <algorithm>
#include <cstring>

namespace stac::applanix {
namespace {

constexpr char kGrp[] = "$GRP";
constexpr char kMsg[] = "$MSG";

std::uint16_t load16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

bool is_group(const std::uint8_t* p) noexcept {
  return std::memcmp(p, kGrp, 4) == 0;
}

// True while the first n (<= 4) bytes can still become "$GRP" or "$MSG".
bool sync_prefix(const std::uint8_t* p, std::size_t n) noexcept {
  return std::memcmp(p, kGrp, n) == 0 || std::memcmp(p, kMsg, n) == 0;
}

constexpr double kHalfWeek = 302'400.0;

}  // namespace

StreamParser::StreamParser(std::size_t max_message_bytes)
    : buffer_(std::clamp(max_message_bytes, kGroup1Bytes, kMaxMessageBytes)) {}

void StreamParser::feed(std::span<const std::uint8_t> chunk) noexcept {
  input_ = chunk;
}

void StreamParser::end_of_stream() noexcept {
  drop_front(emitted_);
  emitted_ = 0;
  if (used_ > 0) {
    ++counters_.truncated;
    counters_.garbage_bytes += used_;
    used_ = 0;
  }
  input_ = {};
}

void StreamParser::drop_front(std::size_t n) noexcept {
  if (n == 0) return;
  std::memmove(buffer_.data(), buffer_.data() + n, used_ - n);
  used_ -= n;
}

StreamParser::Verdict StreamParser::examine() noexcept {
  const std::uint8_t* b = buffer_.data();
  if (used_ == 0) return Verdict::need_more;
  if (!sync_prefix(b, std::min<std::size_t>(used_, 4))) return Verdict::reject;
  if (used_ < kHeaderBytes) return Verdict::need_more;
  const std::size_t total = load16(b + 6) + kHeaderBytes;
  const std::size_t minimum = is_group(b) ? kGroupMinBytes : kMessageMinBytes;
  if (total % 4 != 0 || total < minimum) {
    ++counters_.bad_length;
    return Verdict::reject;
  }
  if (total > buffer_.size()) {
    ++counters_.oversize;
    return Verdict::reject;
  }
  if (used_ < total) return Verdict::need_more;
  if (b[total - 2] != '$' || b[total - 1] != '#') {
    ++counters_.bad_terminator;
    return Verdict::reject;
  }
  if (word_sum({b, total}) != 0) {
    ++counters_.bad_checksum;
    return Verdict::reject;
  }
  return Verdict::complete;
}

bool StreamParser::next(Parsed& out) noexcept {  // NOLINT(bugprone-exception-escape)
  drop_front(emitted_);
  emitted_ = 0;
  while (true) {
    const Verdict v = examine();
    if (v == Verdict::complete) {
      emitted_ = load16(buffer_.data() + 6) + kHeaderBytes;
      const std::size_t malformed = counters_.malformed;
      decode(out);
      if (counters_.malformed == malformed) return true;
      drop_front(emitted_);  // counted by decode()
      emitted_ = 0;
      continue;
    }
    if (v == Verdict::reject) {
      // Skip to the next '$' after the first byte; the rest is examined again.
      const auto* begin = buffer_.data() + 1;
      const auto* end = buffer_.data() + used_;
      const auto* dollar = std::find(begin, end, std::uint8_t{'$'});
      const auto skip = static_cast<std::size_t>(dollar - buffer_.data());
      counters_.garbage_bytes += skip;
      drop_front(skip);
      continue;
    }
    if (input_.empty()) return false;
    if (used_ == 0) {  // hunting: skip garbage without copying it
      const auto dollar = std::find(input_.begin(), input_.end(), std::uint8_t{'$'});
      const auto skip = static_cast<std::size_t>(dollar - input_.begin());
      counters_.garbage_bytes += skip;
      input_ = input_.subspan(skip);
      if (input_.empty()) return false;
    }
    // Copy only what the current candidate still needs, so the buffer holds at most one message.
    std::size_t want = kHeaderBytes;
    if (used_ >= kHeaderBytes) want = load16(buffer_.data() + 6) + kHeaderBytes;
    if (used_ < 4) want = 4;
    const std::size_t n = std::min(want - used_, input_.size());
    std::memcpy(buffer_.data() + used_, input_.data(), n);
    used_ += n;
    input_ = input_.subspan(n);
  }
}

void StreamParser::decode(Parsed& out) noexcept {  // NOLINT(bugprone-exception-escape)
  const std::span<const std::uint8_t> m{buffer_.data(), emitted_};
  const std::uint16_t id = load16(m.data() + 4);
  out.bytes = m;
  out.time = TimeDistance{};
  out.time1_gps_ns.reset();
  if (!is_group(m.data())) {
    Message msg;
    (void)decode_message(m, msg);  // the minimum length was checked by examine()
    out.content = msg;
    ++counters_.control_messages;
    return;
  }
  (void)decode_time_distance(m, out.time);
  bool ok = true;
  switch (id) {
    case 1:
      ok = decode_group1(m, out.content.emplace<Group1>());
      break;
    case 2:
      ok = decode_group2(m, out.content.emplace<Group2>());
      break;
    case 3: {
      auto& g3 = out.content.emplace<Group3>();
      ok = decode_group3(m, g3);
      if (ok) {
        if (week_ && *week_ != g3.gps_week) ++counters_.gps_week_changes;
        week_ = g3.gps_week;
        gps_utc_offset_s_ = g3.gps_utc_offset_s;
        week_start_sow_ = out.time.time1_type() == TimeType::gps ? out.time.time1_s : 0.0;
      }
      break;
    }
    default: {
      constexpr std::size_t kData = kHeaderBytes + sizeof(WireTimeDistance);
      out.content = OtherGroup{id, m.subspan(kData, m.size() - kData - kTrailerBytes)};
      ++counters_.other_groups;
      break;
    }
  }
  if (!ok) {
    ++counters_.malformed;
    counters_.garbage_bytes += emitted_;
    return;
  }
  ++counters_.groups;
  auto* slot =
      std::find_if(by_id_, by_id_ + id_slots_used_, [id](const IdCount& c) { return c.id == id; });
  if (slot != by_id_ + id_slots_used_) {
    ++slot->count;
  } else if (id_slots_used_ < kIdSlots) {
    by_id_[id_slots_used_++] = IdCount{id, 1};
  } else {
    ++ids_not_tallied_;
  }
  if (week_) {
    // Group 3 comes about once a second: a seconds-of-week far below (above) the one it came
    // with means Sunday midnight has passed since (or had not yet passed).
    std::uint32_t week = *week_;
    const double sow =
        out.time.time1_s + (out.time.time1_type() == TimeType::utc ? gps_utc_offset_s_ : 0.0);
    if (week_start_sow_ > 0.0 && sow < week_start_sow_ - kHalfWeek) ++week;
    if (week_start_sow_ > 0.0 && sow > week_start_sow_ + kHalfWeek && week > 0) --week;
    out.time1_gps_ns =
        gps_time_ns(out.time.time1_type(), out.time.time1_s, week, gps_utc_offset_s_);
  }
}

std::uint64_t StreamParser::groups_seen(std::uint16_t id) const noexcept {
  for (std::size_t i = 0; i < id_slots_used_; ++i) {
    if (by_id_[i].id == id) return by_id_[i].count;
  }
  return 0;
}

}  // namespace stac::applanix
