// Number checks for the command line (issue 31): CLI11 lets "nan", "inf" and, for unsigned
// options, "-1" (wrapped to 2^64-1) through its own checks; these refuse them with a message
// naming the option and the range.
#pragma once

#include <CLI/CLI.hpp>

namespace stac::tools {

// A finite number in [lo, hi].
CLI::Validator finite_range(double lo, double hi);

// Every floating-point option of `app` and of its subcommands refuses NaN and infinities, and
// every unsigned one a negative number. main() calls it once every command is added.
void refuse_bad_numbers(CLI::App& app);

}  // namespace stac::tools
