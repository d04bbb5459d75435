// printf's formatting into a std::string, whatever its length: for messages and summary lines
// (allocates; not for the hot path).
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

}  // namespace stac::rt
