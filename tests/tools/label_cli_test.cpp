// stac label (issue 29): the page in a real headless browser (Debian's chromium driven by
// puppeteer-core, tests/web/label_page.mjs) over a state `stac induct` made from short simulated
// drives without the oracle. Answers given by key land in labels.jsonl at once, and the last one
// starts a round (retrospection, new questions) that the page then shows.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "json_lines.hpp"
#include "stac_cli.hpp"
#include "test_paths.hpp"
#include "tools/support/child_process.hpp"

namespace {

using stac::testing::CliResult;
using stac::testing::stac;
namespace fs = std::filesystem;

// `stac label ARGS` started; its URL read from what it prints (port 0: any free port).
struct LabelServer {
  std::optional<stac::tools::ChildProcess> child;
  std::string url;
  LabelServer(const std::string& args, const fs::path& log) {
    std::vector<std::string> words{"label"};
    std::istringstream in(args);
    for (std::string w; in >> w;) words.push_back(w);
    auto c = stac::tools::ChildProcess::start_program(::stac::testing::stac_cli(), words, log);
    if (!c) return;
    child.emplace(std::move(*c));
    const std::regex serving("on (http://127\\.0\\.0\\.1:[0-9]+/)");
    for (int i = 0; i < 300 && url.empty() && !child->poll(); ++i) {
      std::smatch m;
      const std::string text = child->log();
      if (std::regex_search(text, m, serving)) url = m[1];
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
};

TEST(LabelCli, APersonAnswersInABrowserAndTheAnswersTrainARoundWithNewQuestions) {
  const fs::path dir = stac::testing::fresh_dir("stac_label_cli_" + std::to_string(::getpid()));
  const auto at = [&](const std::string& name) { return (dir / name).string(); };
  for (const auto& [name, args] :
       {std::pair<std::string, std::string>{"labels", "--scenario urban --seed 1 --duration 8"},
        {"chunk", "--scenario urban --seed 4 --duration 6"},
        {"empty", "--scenario empty --seed 3 --duration 4"}}) {
    const CliResult sim =
        stac("sim " + args + " --out " + at(name) + ".pcap --truth " + at(name) + ".jsonl");
    ASSERT_EQ(sim.code, 0) << sim.output;
    // The chunk as a user has it: no truth.
    const CliResult data = stac("dataset --in " + at(name) + ".pcap" +
                                (name == "chunk" ? "" : " --truth " + at(name) + ".jsonl") +
                                " --out " + at(name) + "_data");
    ASSERT_EQ(data.code, 0) << data.output;
  }
  const std::string state = at("state");
  const CliResult induct = stac(
      "induct --state " + state + " --classes car,pedestrian,bicyclist --background " +
      at("empty_data") + " --labels " + at("labels_data") + " --labels-per-class 2 --unlabeled " +
      at("chunk_data") + " --ask 2 --warm-rounds 30 --reset-rounds 80");
  ASSERT_EQ(induct.code, 0) << induct.output;
  const auto questions = stac::testing::read_json_lines(state + "/queries.jsonl");
  ASSERT_GE(questions.size(), 2u);
  const std::size_t seeded = stac::testing::read_json_lines(state + "/labels.jsonl").size();

  LabelServer server("--state " + state + " --port 0 --ask 2 --warm-rounds 30 --reset-rounds 80",
                     dir / "label.log");
  ASSERT_TRUE(server.child.has_value());
  ASSERT_FALSE(server.url.empty()) << server.child->log();
  const CliResult page = stac::testing::run_shell(
      "cd " + std::string(::stac::testing::source_dir()) +
      "/tests/web && timeout -s KILL 400 node label_page.mjs " + server.url + " 2>&1");
  ASSERT_EQ(page.code, 0) << page.output << "\n--- stac label:\n" << server.child->log();
  const auto report = page.output.find("{\"classes\"");  // the one JSON line it prints
  ASSERT_NE(report, std::string::npos) << page.output;
  const nlohmann::json seen = nlohmann::json::parse(
      page.output.substr(report, page.output.find('\n', report) - report), nullptr, false);
  ASSERT_FALSE(seen.is_discarded()) << page.output;

  // Each answer is in labels.jsonl, once, with the label of its key.
  const std::map<std::string, std::string> by_key = {
      {"1", "car"}, {"2", "pedestrian"}, {"b", "background"}, {"s", "skip"}};
  const auto lines = stac::testing::read_json_lines(state + "/labels.jsonl");
  ASSERT_EQ(lines.size(), seeded + questions.size()) << page.output;
  ASSERT_EQ(seen["answers"].size(), questions.size());
  for (std::size_t i = 0; i < questions.size(); ++i) {
    const nlohmann::json& a = seen["answers"][i];
    const nlohmann::json& line = lines[seeded + i];
    EXPECT_EQ(line["source"], a["source"]);
    EXPECT_EQ(line["track"], a["track"]);
    EXPECT_EQ(line["label"], by_key.at(a["key"].get<std::string>()));
  }
  // The round ran on them: retrospection, a round, new questions about other tracks.
  EXPECT_EQ(seen["rounds_after"].get<int>(), seen["rounds_before"].get<int>() + 1);
  std::size_t rounds = 0, retrospections = 0;
  for (const auto& h : stac::testing::read_json_lines(state + "/history.jsonl")) {
    rounds += h["event"] == "round" ? 1 : 0;
    retrospections += h["event"] == "retrospection" ? 1 : 0;
  }
  EXPECT_EQ(rounds, 2u);
  EXPECT_GE(retrospections, 1u);
  std::set<std::pair<std::string, std::uint64_t>> answered;
  for (const auto& l : lines)
    answered.insert({l["source"].get<std::string>(), l["track"].get<std::uint64_t>()});
  const auto next = stac::testing::read_json_lines(state + "/queries.jsonl");
  ASSERT_FALSE(next.empty());
  for (const auto& q : next)
    EXPECT_EQ(answered.count({q["source"].get<std::string>(), q["track"].get<std::uint64_t>()}), 0u)
        << q.dump() << " asked again";
  EXPECT_TRUE(fs::is_regular_file(state + "/models/round-0002.stacmodel"));

  // A second server on the same state, or on the same port, is refused with a message; SIGTERM
  // ends the first cleanly.
  const CliResult twice = stac::testing::stac_within(20, "label --state " + state + " --port 0");
  EXPECT_EQ(twice.code, 1) << twice.output;
  EXPECT_NE(twice.output.find("another `stac label` serves this state"), std::string::npos)
      << twice.output;
  std::string port = server.url.substr(server.url.rfind(':') + 1);
  port.pop_back();  // the '/'
  const fs::path other = dir / "other_state";
  fs::copy(state, other, fs::copy_options::recursive);
  fs::remove(other / "label.lock");
  const CliResult busy =
      stac::testing::stac_within(20, "label --state " + other.string() + " --port " + port);
  EXPECT_EQ(busy.code, 1) << busy.output;
  EXPECT_NE(busy.output.find("cannot listen on 127.0.0.1:" + port), std::string::npos)
      << busy.output;
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
  fs::remove_all(dir);
}

TEST(LabelCli, AFolderThatIsNoStateIsRefusedWithAMessage) {
  const fs::path dir = stac::testing::fresh_dir("stac_label_refused_" + std::to_string(::getpid()));
  const CliResult r = stac("label --state " + dir.string() + " --port 0");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find(dir.string()), std::string::npos) << r.output;
  const CliResult missing = stac("label --state " + (dir / "nothing").string());
  EXPECT_NE(missing.code, 0);
  EXPECT_NE(missing.output.find("--state"), std::string::npos) << missing.output;
  fs::remove_all(dir);
}

}  // namespace
