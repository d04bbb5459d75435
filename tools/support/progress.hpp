// A one-line progress bar on stderr for long jobs; silent when stderr is not a terminal.
#pragma once

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace stac::tools {

class Progress {
 public:
  Progress(std::string label, double total) : label_(std::move(label)), total_(total) {
    enabled_ = isatty(STDERR_FILENO) != 0 && total_ > 0;
  }
  ~Progress() { finish(); }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // For a job that learns its size as it goes (stac induct: the chunks not yet taken).
  void set_total(double total) {
    total_ = total;
    enabled_ = isatty(STDERR_FILENO) != 0 && total_ > 0;
  }
  void update(double done) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double f = done / total_ > 1.0 ? 1.0 : done / total_;
    const int width = 40;
    const int filled = static_cast<int>(f * width);
    std::fprintf(stderr, "\r%s [%s%s] %5.1f%%", label_.c_str(),
                 std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(width - filled), '.').c_str(), 100.0 * f);
    std::fflush(stderr);
    drawn_ = true;
  }
  [[nodiscard]] const std::string& label() const noexcept { return label_; }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\r%*s\r", 60 + static_cast<int>(label_.size()), "");
    drawn_ = false;
  }

 private:
  std::string label_;
  double total_;
  bool enabled_ = false;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace stac::tools
