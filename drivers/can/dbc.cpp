#include "drivers/can/dbc.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace stac::can {
namespace {

constexpr std::uint32_t kDbcExtendedFlag = 0x80000000u;
// Vector's pseudo-message that holds signals not assigned to any message.
constexpr std::uint32_t kIndependentSignalsId = 0xC0000000u;

std::uint64_t mask_of(std::uint16_t length) noexcept {
  return length >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << length) - 1;
}

std::uint64_t load_le(std::span<const std::uint8_t, 8> p) noexcept {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[static_cast<std::size_t>(i)];
  return v;
}
std::uint64_t load_be(std::span<const std::uint8_t, 8> p) noexcept {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return v;
}
void store_le(std::uint64_t v, std::span<std::uint8_t, 8> p) noexcept {
  for (std::size_t i = 0; i < 8; ++i, v >>= 8) p[i] = static_cast<std::uint8_t>(v);
}
void store_be(std::uint64_t v, std::span<std::uint8_t, 8> p) noexcept {
  for (int i = 7; i >= 0; --i, v >>= 8)
    p[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v);
}

// Bit index of the signal's least significant bit in the 64-bit word the payload loads as
// (little-endian word for Intel, big-endian word for Motorola). Negative: the signal does not fit.
int lsb_in_word(const Signal& s) noexcept {
  if (s.order == ByteOrder::kIntel) return s.start_bit;
  const int msb = (7 - s.start_bit / 8) * 8 + s.start_bit % 8;
  return msb - (s.length - 1);
}

// A cursor over one line.
class Cursor {
 public:
  explicit Cursor(std::string_view s) : s_(s) {}
  void skip_ws() {
    while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\r')) ++i_;
  }
  bool done() {
    skip_ws();
    return i_ >= s_.size();
  }
  // A run of characters up to whitespace or one of `stops`.
  std::string_view word(std::string_view stops = "") {
    skip_ws();
    const std::size_t b = i_;
    while (i_ < s_.size() && s_[i_] != ' ' && s_[i_] != '\t' && s_[i_] != '\r' &&
           stops.find(s_[i_]) == std::string_view::npos) {
      ++i_;
    }
    return s_.substr(b, i_ - b);
  }
  bool accept(char c) {
    skip_ws();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  bool peek(char c) {
    skip_ws();
    return i_ < s_.size() && s_[i_] == c;
  }
  template <class T>
  bool number(T& out, std::string_view stops) {
    const std::string_view w = word(stops);
    if (w.empty()) return false;
    const char* first = w.data();
    if (w.front() == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, w.data() + w.size(), out);
    return ec == std::errc{} && ptr == w.data() + w.size();
  }
  // A double-quoted string without escapes inside (DBC units are plain).
  bool quoted(std::string& out) {
    if (!accept('"')) return false;
    const std::size_t e = s_.find('"', i_);
    if (e == std::string_view::npos) return false;
    out.assign(s_.substr(i_, e - i_));
    i_ = e + 1;
    return true;
  }

 private:
  std::string_view s_;
  std::size_t i_ = 0;
};

bool valid_identifier(std::string_view name) {
  if (name.empty() || (std::isdigit(static_cast<unsigned char>(name.front())) != 0)) return false;
  for (const char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c)) == 0 && c != '_') return false;
  }
  return true;
}

// Updates the "inside a quoted string" state over one line (backslash escapes a quote).
bool ends_inside_string(std::string_view line, bool inside) {
  for (std::size_t i = 0; i < line.size(); ++i) {
    if (line[i] == '\\' && inside) {
      ++i;
    } else if (line[i] == '"') {
      inside = !inside;
    }
  }
  return inside;
}

class Parser {
 public:
  explicit Parser(const std::string& source) : source_(source) {}

  rt::Result<Database> run(std::string_view text) {
    bool in_string = false;
    std::size_t pos = 0;
    while (pos <= text.size()) {
      const std::size_t nl = text.find('\n', pos);
      const std::string_view line =
          text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
      ++line_;
      if (!in_string) {
        Cursor c(line);
        const std::string_view keyword = c.word(":");
        if (keyword == "BO_") {
          if (auto e = message(c); !e.empty()) return rt::make_error(e);
        } else if (keyword == "SG_") {
          if (auto e = signal(c); !e.empty()) return rt::make_error(e);
        } else if (!keyword.empty() && keyword != "BO_TX_BU_") {
          current_ = nullptr;  // any other section ends the message's signal list
        }
      }
      in_string = ends_inside_string(line, in_string);
      if (nl == std::string_view::npos) break;
      pos = nl + 1;
    }
    if (in_string) return rt::make_error(where() + "a quoted string is never closed");
    db_.source = source_;
    return std::move(db_);
  }

 private:
  std::string where() const { return source_ + ":" + std::to_string(line_) + ": "; }

  std::string message(Cursor& c) {
    std::uint64_t raw_id = 0;
    if (!c.number(raw_id, ":")) return where() + "BO_: expected a numeric message id";
    std::string_view name = c.word(":");
    if (!c.accept(':'))
      return where() + "BO_ " + std::string(name) + ": expected ':' after the name";
    unsigned dlc = 0;
    if (!c.number(dlc, "")) return where() + "BO_ " + std::string(name) + ": expected the dlc";
    if (raw_id == kIndependentSignalsId) {  // signals of no message: skipped with it
      skipping_ = true;
      current_ = nullptr;
      return {};
    }
    skipping_ = false;
    if (!valid_identifier(name))
      return where() + "BO_: '" + std::string(name) + "' is not a valid message name";
    if (dlc > 8)
      return where() + "BO_ " + std::string(name) + ": dlc " + std::to_string(dlc) +
             " > 8 (CAN FD is not supported)";
    Message m;
    m.extended = (raw_id & kDbcExtendedFlag) != 0;
    const std::uint64_t id = raw_id & ~std::uint64_t{kDbcExtendedFlag};
    if (id > (m.extended ? kExtendedIdMask : kStandardIdMask)) {
      return where() + "BO_ " + std::string(name) + ": id " + std::to_string(raw_id) +
             (m.extended ? " does not fit 29 bits"
                         : " does not fit 11 bits (extended ids carry 0x80000000)");
    }
    m.id = static_cast<std::uint32_t>(id);
    m.name = name;
    m.dlc = static_cast<std::uint8_t>(dlc);
    for (const Message& other : db_.messages) {
      if (other.name == m.name)
        return where() + "BO_: message name '" + m.name + "' is defined twice";
      if (other.id == m.id && other.extended == m.extended) {
        return where() + "BO_ " + m.name + ": id " + std::to_string(raw_id) +
               " is already used by " + other.name;
      }
    }
    db_.messages.push_back(std::move(m));
    current_ = &db_.messages.back();
    return {};
  }

  std::string signal(Cursor& c) {
    if (skipping_) return {};
    if (current_ == nullptr) return where() + "SG_ outside a BO_ message";
    Signal s;
    s.name = c.word(":");
    const std::string what = where() + "SG_ " + current_->name + "." + s.name + ": ";
    if (!valid_identifier(s.name))
      return where() + "SG_: '" + s.name + "' is not a valid signal name";
    if (!c.peek(':')) {  // multiplexer indicator
      const std::string_view mux = c.word(":");
      if (mux == "M") {
        s.multiplexer = true;
      } else if (mux.size() > 1 && mux[0] == 'm') {
        std::string_view digits = mux.substr(1);
        if (digits.back() == 'M') digits.remove_suffix(1);  // extended multiplexing: mNM
        if (std::from_chars(digits.data(), digits.data() + digits.size(), s.multiplex_value).ptr !=
            digits.data() + digits.size()) {
          return what + "bad multiplexer indicator '" + std::string(mux) + "'";
        }
      } else {
        return what + "expected ':' or a multiplexer indicator (M, mN), found '" +
               std::string(mux) + "'";
      }
    }
    if (!c.accept(':')) return what + "expected ':'";
    unsigned start = 0, length = 0;
    if (!c.number(start, "|")) return what + "expected the start bit";
    if (!c.accept('|') || !c.number(length, "@"))
      return what + "expected '|' and the length in bits";
    if (!c.accept('@')) return what + "expected '@' and the byte order";
    if (c.accept('1')) {
      s.order = ByteOrder::kIntel;
    } else if (c.accept('0')) {
      s.order = ByteOrder::kMotorola;
    } else {
      return what + "byte order must be @1 (Intel) or @0 (Motorola)";
    }
    if (c.accept('-')) {
      s.is_signed = true;
    } else if (!c.accept('+')) {
      return what + "sign must be '+' (unsigned) or '-' (signed)";
    }
    if (!c.accept('(') || !c.number(s.factor, ",") || !c.accept(',') || !c.number(s.offset, ")") ||
        !c.accept(')')) {
      return what + "expected (factor,offset)";
    }
    if (!c.accept('[') || !c.number(s.min, "|") || !c.accept('|') || !c.number(s.max, "]") ||
        !c.accept(']')) {
      return what + "expected [min|max]";
    }
    if (!c.quoted(s.unit)) return what + "expected the unit in double quotes";
    if (length < 1 || length > 64)
      return what + "length " + std::to_string(length) + " is not in 1..64";
    if (start > 63) return what + "start bit " + std::to_string(start) + " is not in 0..63";
    // No CAN signal needs more; beyond, a 64-bit raw value times the factor is no longer a
    // number a vehicle reports (1e308 made the odometry infinite).
    if (s.factor == 0.0 || !(std::fabs(s.factor) <= 1e9) || !(std::fabs(s.offset) <= 1e15)) {
      return what + "factor must be non-zero and at most 1e9 in magnitude, offset at most 1e15";
    }
    s.start_bit = static_cast<std::uint16_t>(start);
    s.length = static_cast<std::uint16_t>(length);
    const int lsb = lsb_in_word(s);
    if (lsb < 0 || lsb + s.length > 64 || s.bytes_needed() > current_->dlc) {
      return what + "bits " + std::to_string(start) + "|" + std::to_string(length) +
             (s.order == ByteOrder::kIntel ? "@1" : "@0") + " do not fit the message's " +
             std::to_string(current_->dlc) + " bytes";
    }
    if (current_->find(s.name) != nullptr) return what + "signal defined twice";
    current_->signals.push_back(std::move(s));
    return {};
  }

  const std::string& source_;
  Database db_;
  Message* current_ = nullptr;
  bool skipping_ = false;
  int line_ = 0;
};

}  // namespace

std::int64_t Signal::raw(std::span<const std::uint8_t, 8> payload) const noexcept {
  const int lsb = lsb_in_word(*this);
  const std::uint64_t word = order == ByteOrder::kIntel ? load_le(payload) : load_be(payload);
  const std::uint64_t m = mask_of(length);
  std::uint64_t v = (word >> lsb) & m;
  if (is_signed && length < 64 && ((v >> (length - 1)) & 1u) != 0) v |= ~m;
  return static_cast<std::int64_t>(v);
}

double Signal::decode(std::span<const std::uint8_t, 8> payload) const noexcept {
  const std::int64_t r = raw(payload);
  const double value =
      is_signed ? static_cast<double>(r) : static_cast<double>(static_cast<std::uint64_t>(r));
  return value * factor + offset;
}

bool Signal::encode(double physical, std::span<std::uint8_t, 8> payload) const noexcept {
  const double r = std::round((physical - offset) / factor);
  const double lo = is_signed ? -std::ldexp(1.0, length - 1) : 0.0;
  const double hi = is_signed ? std::ldexp(1.0, length - 1) : std::ldexp(1.0, length);
  if (!(r >= lo && r < hi)) return false;  // also rejects NaN
  const std::uint64_t bits = r < 0 ? static_cast<std::uint64_t>(static_cast<std::int64_t>(r))
                                   : static_cast<std::uint64_t>(r);
  const int lsb = lsb_in_word(*this);
  const std::uint64_t m = mask_of(length) << lsb;
  std::uint64_t word = order == ByteOrder::kIntel ? load_le(payload) : load_be(payload);
  word = (word & ~m) | ((bits << lsb) & m);
  if (order == ByteOrder::kIntel) {
    store_le(word, payload);
  } else {
    store_be(word, payload);
  }
  return true;
}

std::uint8_t Signal::bytes_needed() const noexcept {
  if (order == ByteOrder::kIntel)
    return static_cast<std::uint8_t>((start_bit + length - 1) / 8 + 1);
  const int lsb = lsb_in_word(*this);
  return static_cast<std::uint8_t>(8 - (lsb < 0 ? 0 : lsb / 8));
}

const Signal* Message::find(std::string_view signal_name) const noexcept {
  for (const Signal& s : signals) {
    if (s.name == signal_name) return &s;
  }
  return nullptr;
}

const Message* Database::find(std::string_view message_name) const noexcept {
  for (const Message& m : messages) {
    if (m.name == message_name) return &m;
  }
  return nullptr;
}

const Message* Database::find(std::uint32_t id, bool extended) const noexcept {
  for (const Message& m : messages) {
    if (m.id == id && m.extended == extended) return &m;
  }
  return nullptr;
}

rt::Result<Database> parse_dbc(std::string_view text, const std::string& source) {
  return Parser(source).run(text);
}

rt::Result<Database> load_dbc(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec))
    return rt::make_error(file.string() + ": is a folder, not a DBC file");
  std::ifstream in(file, std::ios::binary);
  if (!in) return rt::make_error(file.string() + ": cannot open the DBC file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_dbc(text.str(), file.string());
}

}  // namespace stac::can
