// Finds and verifies Applanix "$GRP"/"$MSG" messages in a byte stream cut into chunks of any
// size (TCP reads, UDP datagrams, file blocks) and decodes Groups 1, 2, 3 and control messages.
// Fixed memory: one message buffer allocated by the constructor; no allocation afterwards.
// A candidate is accepted when its byte count is plausible (total a multiple of 4, at least the
// minimum layout, at most max_message_bytes), it ends in "$#" and its word sum is 0. Anything
// else is skipped byte by byte until the next "$GRP"/"$MSG" (so a message hidden inside a
// rejected one is still found) and counted.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <type_traits>
#include <variant>
#include <vector>

#include "drivers/applanix/groups.hpp"

namespace stac::applanix {

struct OtherGroup {  // a valid group this parser does not decode (4, 7, 99, 20000, ...)
  std::uint16_t id = 0;
  std::span<const std::uint8_t> data;  // after the time/distance block, pad included
};

static_assert(std::is_trivially_copyable_v<Group1> && std::is_trivially_copyable_v<Group2> &&
              std::is_trivially_copyable_v<Group3> && std::is_trivially_copyable_v<OtherGroup> &&
              std::is_trivially_copyable_v<Message>);

struct Parsed {
  // Every alternative is trivially copyable, so assigning or emplacing one never throws (the
  // parser's noexcept functions rely on it; clang-tidy cannot see it through std::variant).
  std::variant<Group1, Group2, Group3, OtherGroup, Message> content;
  TimeDistance time;                         // groups only
  std::optional<std::int64_t> time1_gps_ns;  // absolute GPS time of time1 when it is GPS or UTC
                                             // and a Group 3 has given the week
  std::span<const std::uint8_t> bytes;  // the whole message; valid until the next next()/feed()
};

struct ParserCounters {
  std::uint64_t groups = 0;            // accepted $GRP
  std::uint64_t control_messages = 0;  // accepted $MSG
  std::uint64_t other_groups = 0;      // accepted groups passed through undecoded
  std::uint64_t bad_checksum = 0;      // word sum not 0
  std::uint64_t bad_length = 0;        // byte count not a multiple of 4 or below the minimum layout
  std::uint64_t bad_terminator = 0;    // no "$#" where the byte count says
  std::uint64_t oversize = 0;          // byte count beyond max_message_bytes
  std::uint64_t malformed = 0;         // valid framing but a Group 1/2/3 layout that does not fit
  std::uint64_t garbage_bytes = 0;  // bytes skipped outside accepted messages (incl. rejected ones)
  std::uint64_t truncated = 0;      // partial messages dropped by end_of_stream()
  std::uint64_t gps_week_changes = 0;  // Group 3 gave a different week than before
};

class StreamParser {
 public:
  // max_message_bytes: largest message accepted (at least kGroup1Bytes, at most kMaxMessageBytes).
  explicit StreamParser(std::size_t max_message_bytes = 8192);

  // Hands over the next chunk. It is read by next(), which must return false before the next
  // feed(); the chunk must stay valid until then.
  void feed(std::span<const std::uint8_t> chunk) noexcept;
  // The next accepted message, or false when the chunk is used up (a partial message waits in
  // the buffer for the next chunk).
  bool next(Parsed& out) noexcept;  // NOLINT(bugprone-exception-escape): see Parsed
  // The stream ended or restarted (end of file, end of a UDP datagram, TCP reconnect): a
  // partial message is dropped and counted as truncated. The GPS week is kept.
  void end_of_stream() noexcept;

  std::optional<std::uint32_t> gps_week() const noexcept { return week_; }
  double gps_utc_offset_s() const noexcept { return gps_utc_offset_s_; }
  const ParserCounters& counters() const noexcept { return counters_; }
  // Accepted groups per id, in order of first appearance; ids beyond kIdSlots distinct ones
  // are counted in ids_not_tallied().
  struct IdCount {
    std::uint16_t id = 0;
    std::uint64_t count = 0;
  };
  static constexpr std::size_t kIdSlots = 64;
  std::span<const IdCount> group_counts() const noexcept { return {by_id_, id_slots_used_}; }
  std::uint64_t groups_seen(std::uint16_t id) const noexcept;
  std::uint64_t ids_not_tallied() const noexcept { return ids_not_tallied_; }

 private:
  enum class Verdict { need_more, reject, complete };
  Verdict examine() noexcept;
  void drop_front(std::size_t n) noexcept;
  void decode(Parsed& out) noexcept;  // NOLINT(bugprone-exception-escape): see Parsed

  std::vector<std::uint8_t> buffer_;
  std::size_t used_ = 0;
  std::size_t emitted_ = 0;  // length of the message handed out by the last next()
  std::span<const std::uint8_t> input_;
  std::optional<std::uint32_t> week_;
  double week_start_sow_ = 0.0;  // seconds of week of the Group 3 that gave week_ (GPS time)
  double gps_utc_offset_s_ = 0.0;
  ParserCounters counters_;
  IdCount by_id_[kIdSlots] = {};
  std::size_t id_slots_used_ = 0;
  std::uint64_t ids_not_tallied_ = 0;
};

}  // namespace stac::applanix
