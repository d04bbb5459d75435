#include "tools/support/terminal_output.hpp"

#include <cstdio>

namespace stac::tools {

offline::JobOutput TerminalOutput::output() {
  return {[this](const std::string& text) {
            finish();
            std::fputs(text.c_str(), stderr);
          },
          [this](const std::string& text) {
            finish();
            std::fputs(text.c_str(), stdout);
          },
          [this](const std::string& stage, double done, double total) {
            if (!progress_ || progress_->label() != stage) progress_.emplace(stage, total);
            progress_->set_total(total);
            progress_->update(done);
          }};
}

void TerminalOutput::finish() {
  if (progress_) progress_->finish();
}

}  // namespace stac::tools
