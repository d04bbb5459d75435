#include "drivers/can/candump.hpp"

#include <cinttypes>
#include <cstdio>
#include <memory>
#include <sstream>

namespace stac::can {
namespace {

int hex_value(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

CandumpLine malformed(const char* reason) noexcept {
  return {CandumpLineKind::kMalformed, reason, {}};
}

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

// Splits off the next space-separated token.
std::string_view token(std::string_view& s) noexcept {
  s = trim(s);
  std::size_t e = 0;
  while (e < s.size() && s[e] != ' ' && s[e] != '\t') ++e;
  const std::string_view t = s.substr(0, e);
  s.remove_prefix(e);
  return t;
}

constexpr std::int64_t kMaxStampSeconds = 9'223'372'035;

bool parse_stamp(std::string_view t, std::int64_t& stamp_ns) noexcept {
  if (t.size() < 4 || t.front() != '(' || t.back() != ')') return false;
  t = t.substr(1, t.size() - 2);
  const std::size_t dot = t.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot > 12 || t.size() - dot - 1 > 9 ||
      t.size() == dot + 1) {
    return false;
  }
  std::int64_t sec = 0, frac = 0;
  for (std::size_t i = 0; i < dot; ++i) {
    if (t[i] < '0' || t[i] > '9') return false;
    sec = sec * 10 + (t[i] - '0');
  }
  std::size_t digits = 0;
  for (std::size_t i = dot + 1; i < t.size(); ++i, ++digits) {
    if (t[i] < '0' || t[i] > '9') return false;
    frac = frac * 10 + (t[i] - '0');
  }
  for (; digits < 9; ++digits) frac *= 10;
  // Nanoseconds since 1970 must fit an int64 (up to the year 2262): a larger time would wrap.
  if (sec > kMaxStampSeconds) return false;
  stamp_ns = sec * 1'000'000'000 + frac;
  return true;
}

}  // namespace

CandumpLine parse_candump_line(std::string_view line, Frame& frame) noexcept {
  std::string_view rest = trim(line);
  if (rest.empty()) return {CandumpLineKind::kBlank, "", {}};
  Frame f;
  if (!parse_stamp(token(rest), f.stamp_ns))
    return malformed(
        "expected a timestamp like (1700000000.123456), in seconds below 9223372036 (2262)");
  const std::string_view interface = token(rest);
  if (interface.empty() || interface.find('#') != std::string_view::npos) {
    return malformed("expected an interface name after the timestamp");
  }
  const std::string_view body = token(rest);
  const std::string_view direction = token(rest);
  if (!rest.empty() || !(direction.empty() || direction == "R" || direction == "T")) {
    return malformed("unexpected text after the frame");
  }
  const std::size_t hash = body.find('#');
  if (hash == std::string_view::npos) return malformed("expected <id>#<data>");
  if (hash + 1 < body.size() && body[hash + 1] == '#')
    return {CandumpLineKind::kCanFd, "", interface};
  const std::string_view id = body.substr(0, hash);
  if (id.size() != 3 && id.size() != 8)
    return malformed("the id must have 3 (standard) or 8 (extended) hex digits");
  std::uint32_t value = 0;
  for (const char c : id) {
    const int h = hex_value(c);
    if (h < 0) return malformed("the id is not hexadecimal");
    value = (value << 4) | static_cast<std::uint32_t>(h);
  }
  if (id.size() == 3) {
    if (value > kStandardIdMask) return malformed("a 3-digit id must be at most 7FF");
    f.id = value;
  } else if ((value & kSocketCanErrFlag) != 0) {
    f.error = true;
    f.id = value & kExtendedIdMask;
  } else {
    if (value > kExtendedIdMask)
      return malformed("an 8-digit id must be at most 1FFFFFFF (or an error frame)");
    f.extended = true;
    f.id = value;
  }
  std::string_view data = body.substr(hash + 1);
  if (!data.empty() && (data.front() == 'R' || data.front() == 'r')) {
    f.remote = true;
    if (data.size() == 2 && data[1] >= '0' && data[1] <= '8') {
      f.dlc = static_cast<std::uint8_t>(data[1] - '0');
    } else if (data.size() != 1) {
      return malformed("a remote frame is R optionally followed by its dlc 0..8");
    }
    frame = f;
    return {CandumpLineKind::kFrame, "", interface};
  }
  while (!data.empty()) {
    if (data.front() == '.') {
      data.remove_prefix(1);
      continue;
    }
    if (data.size() < 2) return malformed("data must be whole bytes (two hex digits each)");
    const int hi = hex_value(data[0]);
    const int lo = hex_value(data[1]);
    if (hi < 0 || lo < 0) return malformed("data is not hexadecimal");
    if (f.dlc == kMaxDataBytes) return malformed("more than 8 data bytes (CAN FD lines use ##)");
    f.data[f.dlc++] = static_cast<std::uint8_t>(hi * 16 + lo);
    data.remove_prefix(2);
  }
  frame = f;
  return {CandumpLineKind::kFrame, "", interface};
}

rt::Result<CandumpReader> CandumpReader::open(const std::filesystem::path& file) {
  CandumpReader r;
  auto in = std::make_unique<std::ifstream>(file, std::ios::binary);
  if (!*in) return rt::make_error(file.string() + ": cannot open the candump log");
  r.in_ = std::move(in);
  r.file_ = file.string();
  return r;
}

CandumpReader CandumpReader::from_text(std::string text, const std::string& name) {
  CandumpReader r;
  r.in_ = std::make_unique<std::istringstream>(std::move(text));
  r.file_ = name;
  return r;
}

rt::Result<bool> CandumpReader::next(Frame& frame) {
  while (std::getline(*in_, line_)) {
    ++counters_.lines;
    const CandumpLine l = parse_candump_line(line_, frame);
    switch (l.kind) {
      case CandumpLineKind::kFrame:
        ++counters_.frames;
        return true;
      case CandumpLineKind::kBlank:
        ++counters_.blank;
        break;
      case CandumpLineKind::kCanFd:
        ++counters_.can_fd;
        break;
      case CandumpLineKind::kMalformed:
        return rt::make_error(file_ + ":" + std::to_string(counters_.lines) + ": " + l.reason);
    }
  }
  if (in_->bad())
    return rt::make_error(file_ + ": read error after line " + std::to_string(counters_.lines));
  return false;
}

rt::Result<CandumpWriter> CandumpWriter::open(const std::filesystem::path& file,
                                              std::string interface) {
  if (interface.empty() || interface.find_first_of(" \t#") != std::string::npos) {
    return rt::make_error("candump writer: interface name '" + interface +
                          "' is empty or has spaces or '#'");
  }
  CandumpWriter w;
  w.out_.open(file, std::ios::binary | std::ios::trunc);
  if (!w.out_) return rt::make_error(file.string() + ": cannot create the candump log");
  w.interface_ = std::move(interface);
  return w;
}

bool CandumpWriter::write(const Frame& f) {
  char buf[96];
  const std::int64_t sec = f.stamp_ns / 1'000'000'000;
  const std::int64_t usec = (f.stamp_ns % 1'000'000'000) / 1000;
  int n = std::snprintf(buf, sizeof(buf), "(%" PRId64 ".%06" PRId64 ") ", sec, usec);
  out_ << std::string_view(buf, static_cast<std::size_t>(n)) << interface_ << ' ';
  if (f.error) {
    n = std::snprintf(buf, sizeof(buf), "%08" PRIX32 "#",
                      (f.id & kExtendedIdMask) | kSocketCanErrFlag);
  } else if (f.extended) {
    n = std::snprintf(buf, sizeof(buf), "%08" PRIX32 "#", f.id & kExtendedIdMask);
  } else {
    n = std::snprintf(buf, sizeof(buf), "%03" PRIX32 "#", f.id & kStandardIdMask);
  }
  out_ << std::string_view(buf, static_cast<std::size_t>(n));
  if (f.remote) {
    out_ << 'R';
    if (f.dlc > 0 && f.dlc <= kMaxDataBytes) out_ << static_cast<char>('0' + f.dlc);
  } else {
    for (std::size_t i = 0; i < f.dlc && i < kMaxDataBytes; ++i) {
      std::snprintf(buf, sizeof(buf), "%02X", f.data[i]);
      out_ << buf;
    }
  }
  out_ << '\n';
  return static_cast<bool>(out_);
}

bool CandumpWriter::close() {
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  return ok && !out_.fail();
}

}  // namespace stac::can
