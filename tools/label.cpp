// stac label: the local web page where a person answers group induction's questions (issue 29,
// docs/learning.md; the page is label/). Each round it asks for runs as `stac induct --state DIR
// --rounds 1 --requery` in a child process of this one.
#include <csignal>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "label/label_page.hpp"
#include "tools/commands.hpp"
#include "tools/support/child_process.hpp"

namespace stac::tools {

namespace {

// A round as a child `stac induct`; a labeller killed by SIGKILL leaves no round writing the
// state behind it (OnParentDeath::kTerminate).
class ChildRound final : public label::Round {
 public:
  explicit ChildRound(ChildProcess child) : child_(std::move(child)) {}
  std::optional<int> poll() override { return child_.poll(); }
  [[nodiscard]] std::string log_tail(int lines) const override { return child_.log_tail(lines); }

 private:
  ChildProcess child_;
};

rt::Result<std::unique_ptr<label::Round>> start_child_round(const std::vector<std::string>& args,
                                                            const std::filesystem::path& log) {
  auto child = ChildProcess::start(args, log, OnParentDeath::kTerminate);
  if (!child) return rt::make_error(child.error().message);
  return std::unique_ptr<label::Round>(std::make_unique<ChildRound>(std::move(child).value()));
}

}  // namespace

void add_label_command(CLI::App& app) {
  auto o = std::make_shared<label::PageOptions>();
  CLI::App* cmd = app.add_subcommand(
      "label", "Answer group induction's questions on a local web page (with stac induct)");
  cmd->description(
      "A web page on http://127.0.0.1:PORT/ for the questions `stac induct` wrote to\n"
      "DIR/queries.jsonl: each track's points from a few of its segments (top, side and front\n"
      "views), its path, and the model's class and confidence, with a button and a key per class,\n"
      "background and skip. Each answer is appended to DIR/labels.jsonl at once (fsynced). When\n"
      "every question is answered (or on \"train now\"), `stac induct --state DIR --rounds 1\n"
      "--requery` runs beside it: retrospection on the new labels, a round, new questions.\n"
      "Run it from the folder `stac induct` ran in (the state names its datasets as given).\n"
      "Limits (a page for one person; docs/learning.md): a request body of at most 64 KiB\n"
      "(413), a connection of at most 96 KiB in all; a POST only as application/json from\n"
      "the page's own origin and every request with this server's address as its Host\n"
      "(403: another site's form or script, DNS rebinding); one request per connection,\n"
      "closed when it sends nothing for 2 s or a read or write stalls 5 s; 32 requests\n"
      "served at once; no other page may frame it.\n"
      "A killed `stac label` ends the round it started (SIGTERM).");
  cmd->add_option("--state", o->state, "the state folder of `stac induct`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--address", o->address,
                  "address to serve on (127.0.0.1 or ::1: this machine only; 0.0.0.0: every "
                  "interface, reached by an address, not a host name)")
      ->capture_default_str();
  cmd->add_option("--port", o->port, "TCP port (0: any free port, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--ask", o->ask,
                  "questions per class after each round about the least confident tracks (and, "
                  "unless --ask-confident says otherwise, as many about confident positives)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{10'000}));
  cmd->add_option("--ask-confident", o->ask_confident,
                  "questions per class about confident positives never shown (default: "
                  "--ask; 0: only the least confident)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{10'000}));
  cmd->add_option("--warm-rounds", o->warm_rounds, "boosting rounds added per round")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000}));
  cmd->add_option("--reset-rounds", o->reset_rounds, "boosting rounds after retrospection")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000}));
  cmd->callback([o] {
    const rt::Status served = label::serve(*o, start_child_round, [&](const std::string& url) {
      std::printf("stac label: serving %s on %s (Ctrl-C to stop)\n", o->state.c_str(), url.c_str());
      std::fflush(stdout);
    });
    if (!served) throw CLI::RuntimeError(fail(served.error().message));
  });
}

}  // namespace stac::tools
