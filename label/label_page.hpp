// The labelling page (`stac label`; docs/learning.md): a local web page where a person answers
// group induction's questions. It serves the questions `stac induct` wrote to DIR/queries.jsonl
// with what a person needs to answer them (each track's points from a few of its segments and its
// path; the model's class and confidence), appends each answer to DIR/labels.jsonl at once
// (fsynced) and, when every question is answered (or on "train now"), has a round of `stac
// induct` run beside it: retrospection on the new labels, a round, and new questions.
//
// The page runs no program itself: whoever serves it says how a round is started (`stac label`
// runs `stac induct` as a child process; the fuzzing harness starts none), so the library can be
// driven in-process by tests and by fuzzing.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace httplib {
class Server;
}  // namespace httplib

namespace stac::label {

struct PageOptions {
  std::filesystem::path state;  // the state folder of `stac induct`
  std::string address = "127.0.0.1";
  int port = 8642;  // 0: any free port
  // Passed on to each round of `stac induct`.
  std::size_t ask = 5;
  std::optional<std::size_t> ask_confident;
  std::size_t warm_rounds = 200, reset_rounds = 1000;
};

// What one labeller's page accepts, and no more (docs/learning.md "Limits"; issue 47).
inline constexpr std::size_t kMaxBodyBytes = std::size_t{64} * 1024;  // an answer: ~100 bytes
inline constexpr int kReadTimeoutS = 5;      // per read of a request, and per write of a reply
inline constexpr int kIdleTimeoutS = 2;      // a connection that sends nothing is closed
inline constexpr std::size_t kThreads = 32;  // requests served at once (slow ones included)
// What one connection may send in all (its request line, headers and body), read by serve()'s
// server: an endless line ends there (cpp-httplib 0.11.4 reads a line whole before it checks it).
inline constexpr std::size_t kMaxRequestBytes = kMaxBodyBytes + std::size_t{32} * 1024;

// A round of `stac induct` running beside the page.
class Round {
 public:
  virtual ~Round() = default;
  // Its exit code once it has ended, nullopt while it runs; never blocks.
  virtual std::optional<int> poll() = 0;
  // The last lines it printed, for the page's message when it failed.
  [[nodiscard]] virtual std::string log_tail(int lines) const = 0;
};
// Starts `stac <induct_args...>` with its output in `log`, or says why it cannot.
using StartRound = std::function<rt::Result<std::unique_ptr<Round>>(
    const std::vector<std::string>& induct_args, const std::filesystem::path& log)>;

// What the page knows (the state's classes and sources, the datasets read, the round running);
// every request takes its mutex (a page for one person: a few requests a second at most).
class LabelPage {
 public:
  LabelPage(PageOptions options, StartRound start_round);
  ~LabelPage();
  LabelPage(const LabelPage&) = delete;
  LabelPage& operator=(const LabelPage&) = delete;

  // Reads the state: an error when it cannot be read or has no round yet (so no questions); a
  // torn last line of labels.jsonl is cut, a whole answer without its newline kept.
  rt::Status open();
  // The page's routes on `server`, with its limits (body size, timeouts, one request per
  // connection, kThreads), its security headers and the check every request passes first (Host
  // this server, Origin the page's own, a POST application/json with a Content-Length).
  void serve_on(httplib::Server& server);

 private:
  class State;
  std::unique_ptr<State> state_;
};

// `stac label`: locks the state folder for this server (one per state), opens the page, listens
// on options.address:port and serves until SIGINT or SIGTERM. `on_listening(url)` is called once
// it listens (the URL to open). An error says what to change.
rt::Status serve(const PageOptions& options, StartRound start_round,
                 const std::function<void(const std::string& url)>& on_listening);

// An address as a URL names it: an IPv6 address in brackets.
std::string url_host(const std::string& address);

}  // namespace stac::label
