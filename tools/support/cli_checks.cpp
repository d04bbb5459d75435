#include "tools/support/cli_checks.hpp"

#include <cmath>
#include <cstdlib>
#include <string>

namespace stac::tools {
namespace {

// The text as a double, or NaN when it is not a whole number text.
double number(const std::string& text) {
  if (text.empty()) return NAN;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  return end != nullptr && *end == '\0' ? v : NAN;
}

std::string range_text(double lo, double hi) {
  const auto f = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%g", v);
    return std::string(b);
  };
  return "[" + f(lo) + ", " + f(hi) + "]";
}

}  // namespace

CLI::Validator finite_range(double lo, double hi) {
  const std::string range = range_text(lo, hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        const double v = number(text);
        if (!std::isfinite(v) || v < lo || v > hi)
          return "value " + text + " is not a number in " + range;
        return "";
      },
      "in " + range);
}

void refuse_bad_numbers(CLI::App& app) {
  for (CLI::Option* opt : app.get_options()) {
    const std::string type = opt->get_type_name();
    if (type.rfind("FLOAT", 0) == 0) {
      opt->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const double v = number(text);
            if (!std::isfinite(v)) return "value " + text + " is not a finite number";
            return "";
          },
          ""));
    } else if (type.rfind("UINT", 0) == 0) {
      opt->check(CLI::Validator(
          [](std::string& text) -> std::string {
            const auto first = text.find_first_not_of(" \t");
            if (first != std::string::npos && text[first] == '-')
              return "value " + text + " is negative; this option counts from 0";
            return "";
          },
          ""));
    }
  }
  for (CLI::App* sub : app.get_subcommands({})) refuse_bad_numbers(*sub);
}

}  // namespace stac::tools
