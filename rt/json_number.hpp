// Numbers for the JSON lines written by hand with snprintf (tracks and truth files): JSON has no
// NaN or infinity, so a number that is not finite is written as null, never as "nan" or "inf"
// (a reader then refuses it, naming the field, instead of the whole line failing to parse or a
// bad value passing). Finite numbers are written as "%.*f" would, up to 1e15 in magnitude, and
// as "%.17g" beyond.
#pragma once

#include <cmath>
#include <cstdio>

namespace stac::rt {

struct JsonNumber {
  char text[32];  // "%.*f" below 1e15 with up to 10 decimals, or "%.17g": at most 27
  [[nodiscard]] const char* c_str() const noexcept { return text; }
};

inline JsonNumber json_number(double v, int decimals) noexcept {
  JsonNumber n{};
  if (!std::isfinite(v))
    std::snprintf(n.text, sizeof n.text, "null");
  else if (std::fabs(v) >= 1e15)
    std::snprintf(n.text, sizeof n.text, "%.17g", v);
  else
    std::snprintf(n.text, sizeof n.text, "%.*f", decimals, v);
  return n;
}

}  // namespace stac::rt
