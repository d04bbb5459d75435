#include "replay/faults.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "drivers/velodyne/packet.hpp"

namespace stac::replay {
namespace {

// A Velodyne data packet's GPS trailer starts with the u32 microseconds past the hour.
constexpr std::size_t kVelodyneStampOffset = offsetof(velodyne::RawPacket, trailer);
static_assert(kVelodyneStampOffset == 1200);
constexpr std::uint64_t kMicrosPerHour = 3'600'000'000ull;

bool number(const std::string& text, double& out) {
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return !text.empty() && end != nullptr && *end == '\0' && std::isfinite(out);
}

// "A<sep>B" as two numbers.
bool pair_of(const std::string& text, char sep, double& a, double& b) {
  const auto at = text.find(sep, 1);  // not a leading sign
  return at != std::string::npos && number(text.substr(0, at), a) && number(text.substr(at + 1), b);
}

}  // namespace

rt::Result<FaultPlan> parse_fault_plan(const std::string& spec) {
  FaultPlan plan;
  std::stringstream items(spec);
  const auto bad = [](const std::string& item, const std::string& what) {
    return rt::make_error("--faults " + item + ": " + what +
                          " (items: loss=P, burst=P:N, reorder=P, duplicate=P, truncate=P, "
                          "oversize=P, garbage=P, dropout=START+SECONDS, clock-jump=AT:SECONDS, "
                          "window=START+SECONDS, seed=N, ins-dropout=START+SECONDS, "
                          "ins-garbage=START+SECONDS, ins-checksum=START+SECONDS, "
                          "ins-disconnect=AT, can-silence=START+SECONDS; P a probability in "
                          "[0, 1])");
  };
  for (std::string item; std::getline(items, item, ',');) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) return bad(item, "not NAME=VALUE");
    const std::string name = item.substr(0, eq), value = item.substr(eq + 1);
    double p = 0, a = 0, b = 0;
    if (name == "loss" || name == "reorder" || name == "duplicate" || name == "truncate" ||
        name == "oversize" || name == "garbage") {
      if (!number(value, p) || p < 0 || p > 1) return bad(item, "not a probability");
      (name == "loss"        ? plan.loss
       : name == "reorder"   ? plan.reorder
       : name == "duplicate" ? plan.duplicate
       : name == "truncate"  ? plan.truncate
       : name == "oversize"  ? plan.oversize
                             : plan.garbage) = p;
    } else if (name == "burst") {
      if (!pair_of(value, ':', p, b) || p < 0 || p > 1 || b < 1 || b > 1e6 || b != std::floor(b))
        return bad(item, "not PROBABILITY:DATAGRAMS (1 to 1000000 datagrams)");
      plan.burst = p;
      plan.burst_length = static_cast<std::uint32_t>(b);
    } else if (name == "dropout" || name == "window") {
      if (!pair_of(value, '+', a, b) || a < 0 || b <= 0)
        return bad(item, "not START+SECONDS (start >= 0, seconds > 0, capture time)");
      (name == "dropout" ? plan.dropout : plan.window) = std::pair{a, b};
    } else if (name == "can-silence") {
      if (!pair_of(value, '+', a, b) || a < 0 || b <= 0)
        return bad(item, "not START+SECONDS (start >= 0, seconds > 0, capture time)");
      plan.can_silence = std::pair{a, b};
    } else if (name == "ins-dropout" || name == "ins-garbage" || name == "ins-checksum") {
      if (!pair_of(value, '+', a, b) || a < 0 || b <= 0)
        return bad(item, "not START+SECONDS (start >= 0, seconds > 0, capture time)");
      (name == "ins-dropout"   ? plan.ins.dropout
       : name == "ins-garbage" ? plan.ins.garbage
                               : plan.ins.checksum) = std::pair{a, b};
    } else if (name == "ins-disconnect") {
      if (!number(value, a) || a < 0) return bad(item, "not AT (seconds >= 0, capture time)");
      plan.ins.disconnect = a;
    } else if (name == "clock-jump") {
      if (!pair_of(value, ':', a, b) || a < 0 || b == 0 || std::abs(b) >= 3600)
        return bad(item, "not AT:SECONDS (at >= 0; a jump of less than an hour, not 0)");
      plan.clock_jump = std::pair{a, b};
    } else if (name == "seed") {
      char* end = nullptr;
      plan.seed = std::strtoull(value.c_str(), &end, 10);
      if (value.empty() || *end != '\0' || value[0] == '-') return bad(item, "not a whole number");
    } else {
      return bad(item, "unknown fault");
    }
  }
  plan.ins.seed = plan.seed;
  if (!plan.any() && !plan.ins.any() && !plan.can_silence && !spec.empty())
    return rt::make_error("--faults " + spec + ": names no fault (only window or seed)");
  return plan;
}

bool FaultInjector::in_window(double capture_s) const noexcept {
  return !plan_.window || (capture_s >= plan_.window->first &&
                           capture_s < plan_.window->first + plan_.window->second);
}

std::uint64_t FaultInjector::offer(std::span<const std::uint8_t> payload, double capture_s,
                                   io::UdpSender& send) {
  std::uint64_t refused = 0;
  const auto out = [&](io::UdpSender& s, std::span<const std::uint8_t> bytes) {
    refused += s.send(bytes) ? 0 : 1;
  };
  if (plan_.dropout && capture_s >= plan_.dropout->first &&
      capture_s < plan_.dropout->first + plan_.dropout->second) {
    ++counts_.dropout_lost;
    return refused;
  }
  // The same draws for every datagram, in one order: a seed gives the same faults every run.
  const bool window = in_window(capture_s);
  const double u_loss = rng_.uniform(), u_burst = rng_.uniform(), u_reorder = rng_.uniform(),
               u_dup = rng_.uniform(), u_trunc = rng_.uniform(), u_over = rng_.uniform(),
               u_garbage = rng_.uniform();
  const std::uint64_t r1 = rng_.next(), r2 = rng_.next();
  if (window && u_garbage < plan_.garbage) {
    // Random bytes: half the time exactly the size of the datagram after it (a packet's size
    // with nothing valid in it), else any size.
    const std::size_t n =
        (r1 & 1) != 0 ? std::min(payload.size(), junk_.size()) : 1 + (r1 >> 1) % junk_.size();
    for (std::size_t i = 0; i < n; ++i) junk_[i] = static_cast<std::uint8_t>(rng_.next());
    out(send, std::span(junk_.data(), n));
    ++counts_.garbage;
  }
  if (burst_left_ > 0) {
    --burst_left_;
    ++counts_.burst_lost;
    return refused;
  }
  if (window && u_burst < plan_.burst) {
    burst_left_ = plan_.burst_length - 1;
    ++counts_.burst_lost;
    return refused;
  }
  if (window && u_loss < plan_.loss) {
    ++counts_.lost;
    return refused;
  }
  // The datagram as sent: changed in work_ when a fault changes it.
  std::span<const std::uint8_t> bytes = payload;
  const auto changeable = [&] {
    if (bytes.data() != work_.data()) {
      std::memcpy(work_.data(), payload.data(), payload.size());
      bytes = std::span(work_.data(), payload.size());
    }
  };
  if (payload.size() > kMaxDatagram) {
    out(send, payload);  // beyond what a fault changes (never a Velodyne packet)
    return refused;
  }
  if (plan_.clock_jump && capture_s >= plan_.clock_jump->first &&
      payload.size() == velodyne::kPacketSize) {
    changeable();
    std::uint32_t us = 0;
    std::memcpy(&us, work_.data() + kVelodyneStampOffset, 4);
    const auto jump = static_cast<std::int64_t>(std::llround(plan_.clock_jump->second * 1e6));
    const auto hour = static_cast<std::int64_t>(kMicrosPerHour);
    us = static_cast<std::uint32_t>(((static_cast<std::int64_t>(us) + jump) % hour + hour) % hour);
    std::memcpy(work_.data() + kVelodyneStampOffset, &us, 4);
    ++counts_.clock_jumped;
  }
  if (window && u_trunc < plan_.truncate && bytes.size() > 1) {
    bytes = bytes.first(1 + r2 % (bytes.size() - 1));
    ++counts_.truncated;
  } else if (window && u_over < plan_.oversize) {
    changeable();
    const std::size_t extra = 1 + r2 % 200;
    for (std::size_t i = 0; i < extra; ++i)
      work_[bytes.size() + i] = static_cast<std::uint8_t>(rng_.next());
    bytes = std::span(work_.data(), bytes.size() + extra);
    ++counts_.oversized;
  }
  if (holding_) {  // the one held back goes after this one
    out(send, bytes);
    out(*held_by_, std::span(held_.data(), held_size_));
    holding_ = false;
    return refused;
  }
  if (window && u_reorder < plan_.reorder) {
    std::memcpy(held_.data(), bytes.data(), bytes.size());
    held_size_ = bytes.size();
    held_by_ = &send;
    holding_ = true;
    ++counts_.reordered;
    return refused;
  }
  out(send, bytes);
  if (window && u_dup < plan_.duplicate) {
    out(send, bytes);
    ++counts_.duplicated;
  }
  return refused;
}

std::uint64_t FaultInjector::flush() {
  if (!holding_) return 0;
  holding_ = false;
  return held_by_->send(std::span(held_.data(), held_size_)) ? 0 : 1;
}

namespace {

void add(std::string& s, std::uint64_t n, const char* what) {
  if (n == 0) return;
  s += (s.back() == ':' ? " " : ", ") + std::to_string(n) + " " + what;
}

bool within(const TimeSpan& span, double t) {
  return span && t >= span->first && t < span->first + span->second;
}

}  // namespace

std::string summary(const FaultCounts& c) {
  std::string s = "faults:";
  add(s, c.lost, "lost");
  add(s, c.burst_lost, "lost in bursts");
  add(s, c.dropout_lost, "lost in the dropout");
  add(s, c.reordered, "reordered");
  add(s, c.duplicated, "duplicated");
  add(s, c.truncated, "truncated");
  add(s, c.oversized, "oversized");
  add(s, c.garbage, "garbage datagrams");
  add(s, c.clock_jumped, "with the clock jumped");
  if (s.back() == ':') s += " none happened";
  return s;
}

std::string summary(const StreamFaultCounts& c) {
  std::string s = "ins faults:";
  add(s, c.dropout_bytes, "bytes held back in the dropout");
  add(s, c.garbage_bytes, "bytes of garbage instead of the stream");
  add(s, c.checksums_broken, "messages with a broken checksum");
  add(s, c.disconnects, "disconnects");
  if (s.back() == ':') s += " none happened";
  return s;
}

std::span<const std::uint8_t> StreamFaultInjector::apply(std::span<const std::uint8_t> chunk,
                                                         double capture_s,
                                                         bool& disconnect) noexcept {
  disconnect = false;
  if (plan_.disconnect && !disconnected_ && capture_s >= *plan_.disconnect) {
    disconnected_ = true;
    disconnect = true;
    ++counts_.disconnects;
  }
  if (within(plan_.dropout, capture_s)) {
    counts_.dropout_bytes += chunk.size();
    return {};
  }
  const std::size_t n = std::min(chunk.size(), work_.size());
  if (within(plan_.garbage, capture_s)) {
    for (std::size_t i = 0; i < n; i += 8) {
      const std::uint64_t r = rng_.next();
      std::memcpy(work_.data() + i, &r, std::min<std::size_t>(8, n - i));
    }
    counts_.garbage_bytes += n;
    return {work_.data(), n};
  }
  if (within(plan_.checksum, capture_s)) {
    std::memcpy(work_.data(), chunk.data(), n);
    // "$GRP" + u16 group + u16 byte count, then the body: its 5th byte (in the first time field).
    constexpr std::size_t kBodyByte = 12;
    for (std::size_t at = 0; at + kBodyByte < n; ++at) {
      if (std::memcmp(work_.data() + at, "$GRP", 4) != 0) continue;
      work_[at + kBodyByte] ^= 0x5a;
      ++counts_.checksums_broken;
      at += kBodyByte;
    }
    return {work_.data(), n};
  }
  return chunk.first(n);
}

}  // namespace stac::replay
