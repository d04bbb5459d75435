// The subset of the DBC format (Vector CANdb++) a vehicle signal map needs: `BO_` messages and
// their `SG_` signals. Every other keyword (VERSION, NS_, BU_, CM_, BA_, VAL_, ...) is skipped,
// quoted strings may span lines. Multiplexed signals are parsed and marked, not interpreted.
//
// Bit numbering is DBC's: bit b is bit (b % 8) of payload byte (b / 8), bit 0 the byte's LSB.
//   @1 Intel (little-endian): start bit = the signal's least significant bit.
//   @0 Motorola (big-endian): start bit = the signal's most significant bit; the next less
//      significant bit is b-1 inside a byte and b+15 across a byte boundary.
// physical = raw * factor + offset; raw is two's complement when the sign is '-'.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/can/frame.hpp"
#include "rt/expected.hpp"

namespace stac::can {

enum class ByteOrder : std::uint8_t { kIntel, kMotorola };

struct Signal {
  std::string name;
  std::uint16_t start_bit = 0;  // DBC start bit (see above)
  std::uint16_t length = 1;     // bits, 1..64
  ByteOrder order = ByteOrder::kIntel;
  bool is_signed = false;
  double factor = 1.0;
  double offset = 0.0;
  double min = 0.0;  // documented range (physical units); not enforced by decode()
  double max = 0.0;
  std::string unit;
  bool multiplexer = false;           // "M": selects which multiplexed signals are present
  std::int64_t multiplex_value = -1;  // "mN": present when the multiplexer equals N; -1 = always

  // The raw bits (sign-extended when signed) from a payload of at least bytes_needed() bytes.
  std::int64_t raw(std::span<const std::uint8_t, 8> payload) const noexcept;
  // raw() * factor + offset.
  double decode(std::span<const std::uint8_t, 8> payload) const noexcept;
  // Writes round((physical - offset) / factor) into the signal's bits, leaving the others alone.
  // False (payload untouched) when the value does not fit the signal's raw range.
  bool encode(double physical, std::span<std::uint8_t, 8> payload) const noexcept;
  // The number of payload bytes the signal reaches into (1..8).
  std::uint8_t bytes_needed() const noexcept;
};

struct Message {
  std::uint32_t id = 0;   // without the DBC extended flag (0x80000000)
  bool extended = false;  // the DBC id carried 0x80000000: a 29-bit identifier
  std::string name;
  std::uint8_t dlc = 8;
  std::vector<Signal> signals;

  const Signal* find(std::string_view signal_name) const noexcept;
};

struct Database {
  std::vector<Message> messages;
  std::string source;  // the file (or name) it was parsed from, for errors about its contents

  const Message* find(std::string_view message_name) const noexcept;
  const Message* find(std::uint32_t id, bool extended) const noexcept;
};

// Parses DBC text; `source` names it in errors ("<source>:<line>: <what is wrong>"). Checks:
// ids fit 11/29 bits and are unique, dlc <= 8, signals fit their message's dlc, lengths 1..64,
// factor != 0, signal names unique within a message, an SG_ follows a BO_.
rt::Result<Database> parse_dbc(std::string_view text, const std::string& source);
// Reads and parses a file; the error names the file.
rt::Result<Database> load_dbc(const std::filesystem::path& file);

}  // namespace stac::can
