// Where an offline job's words go: the command line prints them (text on stderr, results on
// stdout, a progress bar), a test or another program may keep them. Every callback may be empty.
#pragma once

#include <functional>
#include <string>

namespace stac::offline {

struct JobOutput {
  std::function<void(const std::string&)> text;    // what it did and noticed, whole lines
  std::function<void(const std::string&)> result;  // what it found: figures, files written
  // A stage of the job (e.g. "dataset drive.pcap") and how far it is (done of total, any unit).
  std::function<void(const std::string& stage, double done, double total)> progress;

  void say(const std::string& line) const {
    if (text) text(line);
  }
  void tell(const std::string& line) const {
    if (result) result(line);
  }
  void advance(const std::string& stage, double done, double total) const {
    if (progress) progress(stage, done, total);
  }
};

}  // namespace stac::offline
