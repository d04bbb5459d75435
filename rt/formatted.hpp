// Text for messages and summary lines (allocates; not for the hot path): printf's formatting into
// a std::string, and a value someone sent as a message quotes it. C++17, for the C++17 libraries
// too (view/).
#pragma once

#include <cstdio>
#include <string>

namespace stac::rt {

template <typename... Args>
std::string formatted(const char* format, Args... args) {
  const int n = std::snprintf(nullptr, 0, format, args...);
  if (n <= 0) return {};
  std::string text(static_cast<std::size_t>(n), '\0');
  std::snprintf(text.data(), text.size() + 1, format, args...);
  return text;
}

// TEXT as an error message quotes what a person or a peer sent: whole up to 80 characters, else
// its first 80 and its length ("xxx... (50000 bytes)"), so a message stays one readable line
// whatever was sent (issue 47).
inline std::string echoed(const std::string& text) {
  constexpr std::size_t kMaxEchoedChars = 80;
  if (text.size() <= kMaxEchoedChars) return text;
  return text.substr(0, kMaxEchoedChars) + "... (" + std::to_string(text.size()) + " bytes)";
}

}  // namespace stac::rt
