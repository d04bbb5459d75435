// stac label (issue 29): the page in a real headless browser (Debian's chromium driven by
// puppeteer-core, tests/web/label_page.mjs) over a state `stac induct` made from short simulated
// drives without the oracle. Answers given by key land in labels.jsonl at once, and the last one
// starts a round (retrospection, new questions) that the page then shows. Then what a hostile
// client tries over real loopback sockets (issue 47): huge bodies, other sites and host names,
// framing, slow connections, a labeller killed during a round, and an IPv6 address.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
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
#include "shared_drives.hpp"
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
  std::string host;  // the URL's host and port, as a Host header names them
  int port = 0;
  LabelServer(const std::string& args, const fs::path& log) {
    std::vector<std::string> words{"label"};
    std::istringstream in(args);
    for (std::string w; in >> w;) words.push_back(w);
    auto c = stac::tools::ChildProcess::start_program(::stac::testing::stac_cli(), words, log);
    if (!c) return;
    child.emplace(std::move(*c));
    const std::regex serving("on (http://((127\\.0\\.0\\.1|\\[::1\\]):([0-9]+))/)");
    for (int i = 0; i < 300 && url.empty() && !child->poll(); ++i) {
      std::smatch m;
      const std::string text = child->log();
      if (std::regex_search(text, m, serving)) {
        url = m[1];
        host = m[2];
        port = std::stoi(m[4]);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
};

// A connection to ADDRESS:PORT (IPv4 or IPv6, numeric); -1 when it fails.
int connect_to(const std::string& address, int port) {
  sockaddr_storage to{};
  socklen_t size = 0;
  auto* v4 = reinterpret_cast<sockaddr_in*>(&to);
  auto* v6 = reinterpret_cast<sockaddr_in6*>(&to);
  if (::inet_pton(AF_INET, address.c_str(), &v4->sin_addr) == 1) {
    v4->sin_family = AF_INET;
    v4->sin_port = htons(static_cast<std::uint16_t>(port));
    size = sizeof *v4;
  } else if (::inet_pton(AF_INET6, address.c_str(), &v6->sin6_addr) == 1) {
    v6->sin6_family = AF_INET6;
    v6->sin6_port = htons(static_cast<std::uint16_t>(port));
    size = sizeof *v6;
  } else {
    return -1;
  }
  const int fd = ::socket(to.ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&to), size) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

struct Reply {
  int status = 0;  // 0: no reply within the time given
  std::string head, body;
  double seconds = 0;  // from the request sent to the reply read
  [[nodiscard]] std::string header(const std::string& name) const {
    const std::regex line("\r\n" + name + ": ([^\r]*)\r\n", std::regex::icase);
    std::smatch m;
    return std::regex_search(head, m, line) ? std::string(m[1]) : std::string();
  }
};

// A reply read from `fd` until the server closes the connection, the body its Content-Length
// announces is in, or timeout_s passes.
Reply read_reply(int fd, double timeout_s) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(timeout_s);
  std::string in;
  Reply r;
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now()).count();
    pollfd p{fd, POLLIN, 0};
    if (left <= 0 || ::poll(&p, 1, static_cast<int>(left)) <= 0) break;
    char buf[65536];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    in.append(buf, static_cast<std::size_t>(n));
    const std::size_t blank = in.find("\r\n\r\n");
    if (blank == std::string::npos) continue;
    r.head = in.substr(0, blank + 2);
    r.body = in.substr(blank + 4);
    const std::string length = r.header("Content-Length");
    if (!length.empty() && r.body.size() >= std::stoul(length)) break;
  }
  r.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::smatch m;
  if (std::regex_search(in, m, std::regex("^HTTP/1\\.1 ([0-9]{3}) "))) r.status = std::stoi(m[1]);
  return r;
}

// `request` (head and body as given: a head may announce a body never sent) on a new connection,
// and the reply.
Reply exchange(const std::string& address, int port, const std::string& request,
               double timeout_s = 10) {
  const int fd = connect_to(address, port);
  if (fd < 0) return {};
  (void)::send(fd, request.data(), request.size(), MSG_NOSIGNAL);
  Reply r = read_reply(fd, timeout_s);
  ::close(fd);
  return r;
}

// A request's text: HEAD_LINES (each ending in \r\n) after the request line and Host, then BODY.
std::string request(const std::string& method, const std::string& target, const std::string& host,
                    const std::string& head_lines = "", const std::string& body = "") {
  return method + " " + target + " HTTP/1.1\r\nHost: " + host + "\r\n" + head_lines +
         "Connection: close\r\n\r\n" + body;
}

// A POST as the page sends it (JSON), with EXTRA head lines.
std::string json_post(const std::string& target, const std::string& host, const std::string& body,
                      const std::string& extra = "") {
  return request("POST", target, host,
                 "Content-Type: application/json\r\nContent-Length: " +
                     std::to_string(body.size()) + "\r\n" + extra,
                 body);
}

// A state `stac induct` made from short simulated drives, shared by the test programs
// (tests/shared_drives.hpp); each test serves its own copy NAME.
const fs::path& shared_state() {
  static const fs::path shared = [] {
    const std::string drive = "--scenario urban --seed 1 --duration 4";
    // The drive twice: labelled (the first labels) and as a user has it (the questions).
    const auto made =
        stac::testing::shared_datasets({{drive, true, ""},
                                        {drive, false, ""},
                                        {"--scenario empty --seed 3 --duration 3", true, ""}});
    for (const auto& m : made) EXPECT_TRUE(m) << m.error;
    const auto& labels = made[0];
    const auto& chunk = made[1];
    const auto& empty = made[2];
    const auto state = stac::testing::shared_run(
        "induct --state {out}/state --classes car,pedestrian,bicyclist --background " + empty.path +
        " --labels " + labels.path + " --labels-per-class 2 --unlabeled " + chunk.path +
        " --ask 2 --warm-rounds 30 --reset-rounds 80");
    EXPECT_TRUE(state) << state.error;
    return fs::path(state.path) / "state";
  }();
  return shared;
}
fs::path state_copy(const std::string& name) {
  static const fs::path copies =
      stac::testing::fresh_dir("stac_label_limits_" + std::to_string(::getpid()));
  static const struct Cleanup {
    ~Cleanup() { fs::remove_all(copies); }
  } cleanup;
  const fs::path copy = copies / name;
  fs::remove_all(copy);
  fs::copy(shared_state(), copy, fs::copy_options::recursive);
  return copy;
}

// `stac label --port 0 EXTRA` on this test's own copy of the state.
struct ServedCopy {
  fs::path state;
  LabelServer server;
  explicit ServedCopy(const std::string& name, const std::string& extra = "")
      : state(state_copy(name)),
        server("--state " + state.string() + " --port 0" + extra,
               state.parent_path() / (name + ".log")) {}
  // Empty while it serves; else what it printed.
  [[nodiscard]] std::string failure() const {
    if (!server.child) return "stac label did not start";
    return server.url.empty() ? "no URL printed: " + server.child->log() : "";
  }
};

TEST(LabelCli, APersonAnswersInABrowserAndTheAnswersTrainARoundWithNewQuestions) {
  const fs::path dir = stac::testing::fresh_dir("stac_label_cli_" + std::to_string(::getpid()));
  const auto at = [&](const std::string& name) { return (dir / name).string(); };
  // Shared drives' datasets (tests/shared_drives.hpp); the chunk as a user has it: no truth.
  const auto made =
      stac::testing::shared_datasets({{"--scenario urban --seed 1 --duration 8", true, ""},
                                      {"--scenario urban --seed 4 --duration 6", false, ""},
                                      {"--scenario empty --seed 3 --duration 4", true, ""}});
  for (const auto& m : made) ASSERT_TRUE(m) << m.error;
  const std::map<std::string, std::string> data = {
      {"labels", made[0].path}, {"chunk", made[1].path}, {"empty", made[2].path}};
  const std::string state = at("state");
  const CliResult induct = stac(
      "induct --state " + state + " --classes car,pedestrian,bicyclist --background " +
      data.at("empty") + " --labels " + data.at("labels") + " --labels-per-class 2 --unlabeled " +
      data.at("chunk") + " --ask 2 --warm-rounds 30 --reset-rounds 80");
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

// The state the server shows, as the page asks for it (null when refused).
nlohmann::json state_of(const LabelServer& server) {
  const Reply r = exchange("127.0.0.1", server.port, request("GET", "/api/state", server.host));
  return r.status == 200 ? nlohmann::json::parse(r.body, nullptr, false) : nlohmann::json();
}

TEST(LabelCli, ABodyOverItsLimitIsRefusedAtOnceAndAnErrorQuotesAtMost80Characters) {
  ServedCopy served("body_limit");
  ASSERT_EQ(served.failure(), "");
  const fs::path& state = served.state;
  LabelServer& server = served.server;
  const auto send = [&](const std::string& text) {
    return exchange("127.0.0.1", server.port, text, 5);
  };
  // 500 MB announced, none sent: refused before any of it is read (it was read into memory).
  const Reply huge =
      send(request("POST", "/api/answer", server.host,
                   "Content-Type: application/json\r\nContent-Length: 500000000\r\n"));
  EXPECT_EQ(huge.status, 413) << huge.head << " after " << huge.seconds << " s";
  EXPECT_LT(huge.seconds, 3.0);
  const nlohmann::json error = nlohmann::json::parse(huge.body, nullptr, false);
  EXPECT_TRUE(error.is_object() && error.contains("error")) << huge.body;
  // One byte over 64 KiB, sent whole.
  const Reply over = send(json_post("/api/answer", server.host, std::string(64 * 1024 + 1, ' ')));
  EXPECT_EQ(over.status, 413) << over.head;
  // A body of no announced length (chunked: a 256 MB chunk announced) is refused too.
  const Reply chunked = send(request("POST", "/api/answer", server.host,
                                     "Content-Type: application/json\r\n"
                                     "Transfer-Encoding: chunked\r\n",
                                     "10000000\r\n"));
  EXPECT_EQ(chunked.status, 411) << chunked.head << " after " << chunked.seconds << " s";
  EXPECT_LT(chunked.seconds, 3.0);

  // Under the limit, a 50 000-character label and source are quoted in 80 characters at most.
  const nlohmann::json q = stac::testing::read_json_lines(state / "queries.jsonl").at(0);
  const std::string long_label(50'000, 'x');
  const Reply label = send(json_post(
      "/api/answer", server.host,
      nlohmann::json{{"source", q["source"]}, {"track", q["track"]}, {"label", long_label}}
          .dump()));
  EXPECT_EQ(label.status, 400) << label.head;
  EXPECT_LT(label.body.size(), 300u) << label.body.substr(0, 300);
  EXPECT_NE(label.body.find("label " + std::string(80, 'x') + "... (50000 bytes) is none of"),
            std::string::npos)
      << label.body.substr(0, 300);
  const Reply track =
      send(request("GET", "/api/track?track=1&source=" + std::string(6000, 'y'), server.host));
  EXPECT_EQ(track.status, 400) << track.head;
  EXPECT_LT(track.body.size(), 300u) << track.body.substr(0, 300);
  EXPECT_EQ(stac::testing::read_json_lines(state / "labels.jsonl").size(),
            stac::testing::read_json_lines(shared_state() / "labels.jsonl").size());
  // The server still serves.
  EXPECT_TRUE(state_of(server).is_object()) << server.child->log();
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
}

// A process's peak resident memory (kB, /proc/PID/status VmHWM); 0 when it cannot be read.
long peak_kb(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return 0;
}

// cpp-httplib 0.11.4 reads a request line or a header line whole before it checks its length: an
// endless one (and endless header lines) cost the server memory until the client stopped (a
// 100 MB line: 130 MB more resident). The connection now ends after label::kMaxRequestBytes.
TEST(LabelCli, AnEndlessRequestLineOrHeadEndsTheConnectionAndCostsNoMemory) {
  ServedCopy served("endless");
  ASSERT_EQ(served.failure(), "");
  LabelServer& server = served.server;
  ASSERT_TRUE(state_of(server).is_object()) << server.child->log();
  const long before = peak_kb(server.child->pid());
  ASSERT_GT(before, 0);
  // Sends up to `total` bytes of `unit` after `start`; how many went before the server closed.
  const auto flood = [&](const std::string& start, const std::string& unit, std::size_t total) {
    const int fd = connect_to("127.0.0.1", server.port);
    EXPECT_GE(fd, 0);
    std::size_t sent = static_cast<std::size_t>(
        std::max<ssize_t>(0, ::send(fd, start.data(), start.size(), MSG_NOSIGNAL)));
    std::string chunk;
    while (chunk.size() < 65536) chunk += unit;
    while (sent < total) {
      const ssize_t n = ::send(fd, chunk.data(), chunk.size(), MSG_NOSIGNAL);
      if (n <= 0) break;
      sent += static_cast<std::size_t>(n);
    }
    ::close(fd);
    return sent;
  };
  constexpr std::size_t kFlood = std::size_t{64} << 20;  // 64 MB
  EXPECT_LT(flood("GET /", "a", kFlood), kFlood / 4) << "an endless request line was read on";
  EXPECT_LT(flood("GET /api/state HTTP/1.1\r\nHost: " + server.host + "\r\nX-Long: ", "b", kFlood),
            kFlood / 4)
      << "an endless header line was read on";
  EXPECT_LT(flood("GET /api/state HTTP/1.1\r\nHost: " + server.host + "\r\n", "X-A: b\r\n", kFlood),
            kFlood / 4)
      << "endless header lines were read on";
  const long after = peak_kb(server.child->pid());
  EXPECT_LT(after - before, 20'000)
      << "peak resident memory grew from " << before << " kB to " << after << " kB";
  // The page still serves.
  EXPECT_TRUE(state_of(server).is_object()) << server.child->log();
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
}

TEST(LabelCli, ARequestFromAnotherSiteOrByAnotherHostNameIsRefused) {
  ServedCopy served("origin");
  ASSERT_EQ(served.failure(), "");
  const fs::path& state = served.state;
  LabelServer& server = served.server;
  const std::string port = std::to_string(server.port);
  const auto send = [&](const std::string& text) {
    return exchange("127.0.0.1", server.port, text);
  };
  // DNS rebinding: another site's name resolved to 127.0.0.1 reads nothing.
  for (const std::string& host : {"attacker.example:" + port, std::string("attacker.example"),
                                  "127.0.0.1:" + std::to_string(server.port + 1)}) {
    const Reply r = send(request("GET", "/api/state", host));
    EXPECT_EQ(r.status, 403) << host << ": " << r.head;
    EXPECT_EQ(r.body.find("questions"), std::string::npos) << r.body;
  }
  EXPECT_EQ(send(request("GET", "/", "attacker.example:" + port)).status, 403);
  for (const std::string& host : {"127.0.0.1:" + port, "localhost:" + port, "LOCALHOST:" + port})
    EXPECT_EQ(send(request("GET", "/api/state", host)).status, 200) << host;

  // Cross-site requests: what a form on another page can send (no CORS preflight), JSON from
  // another origin. None saves an answer or starts a round.
  const nlohmann::json q = stac::testing::read_json_lines(state / "queries.jsonl").at(0);
  const std::string answer = nlohmann::json{
      {"source", q["source"]},
      {"track", q["track"]},
      {"label", "background"}}.dump();
  const std::size_t seeded = stac::testing::read_json_lines(state / "labels.jsonl").size();
  const auto post = [&](const std::string& target, const std::string& type,
                        const std::string& extra = "") {
    return send(request("POST", target, server.host,
                        "Content-Type: " + type +
                            "\r\nContent-Length: " + std::to_string(answer.size()) + "\r\n" + extra,
                        answer));
  };
  for (const std::string& type : std::vector<std::string>{
           "text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x"}) {
    EXPECT_EQ(post("/api/answer", type).status, 403) << type;
    EXPECT_EQ(post("/api/train", type).status, 403) << type;
  }
  EXPECT_EQ(send(request("POST", "/api/train", server.host, "Content-Length: 2\r\n", "{}")).status,
            403);  // no Content-Type
  for (const std::string& origin : {std::string("http://attacker.example"), std::string("null"),
                                    "http://127.0.0.1:" + std::to_string(server.port + 1)}) {
    EXPECT_EQ(post("/api/answer", "application/json", "Origin: " + origin + "\r\n").status, 403)
        << origin;
    EXPECT_EQ(post("/api/train", "application/json", "Origin: " + origin + "\r\n").status, 403)
        << origin;
  }
  EXPECT_EQ(stac::testing::read_json_lines(state / "labels.jsonl").size(), seeded);
  const nlohmann::json before = state_of(server);
  ASSERT_TRUE(before.is_object());
  EXPECT_EQ(before["training"], false);
  EXPECT_FALSE(fs::exists(state / "label-round.log"));

  // The page's own request (JSON, its own origin) is served.
  const Reply own = post("/api/answer", "application/json; charset=utf-8",
                         "Origin: http://" + server.host + "\r\n");
  EXPECT_EQ(own.status, 200) << own.head << own.body;
  EXPECT_EQ(stac::testing::read_json_lines(state / "labels.jsonl").size(), seeded + 1);
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
}

TEST(LabelCli, EveryResponseForbidsFramingSniffingAndReferrers) {
  ServedCopy served("headers");
  ASSERT_EQ(served.failure(), "");
  LabelServer& server = served.server;
  for (const std::string& text :
       {request("GET", "/", server.host), request("GET", "/api/state", server.host),
        request("GET", "/nothing", server.host), request("GET", "/api/track", server.host),
        request("GET", "/", "attacker.example"),
        json_post("/api/answer", server.host, "not json")}) {
    const Reply r = exchange("127.0.0.1", server.port, text);
    const std::string what = text.substr(0, text.find('\r')) + " -> " + std::to_string(r.status);
    EXPECT_NE(r.status, 0) << what;
    EXPECT_EQ(r.header("X-Frame-Options"), "DENY") << what;
    EXPECT_NE(r.header("Content-Security-Policy").find("frame-ancestors 'none'"), std::string::npos)
        << what;
    EXPECT_NE(r.header("Content-Security-Policy").find("default-src 'self'"), std::string::npos)
        << what;
    EXPECT_EQ(r.header("X-Content-Type-Options"), "nosniff") << what;
    EXPECT_EQ(r.header("Referrer-Policy"), "no-referrer") << what;
  }
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
}

TEST(LabelCli, IdleAndHalfSentConnectionsDoNotStarveThePage) {
  ServedCopy served("slow");
  ASSERT_EQ(served.failure(), "");
  LabelServer& server = served.server;
  // 20 connections that send nothing and 8 that send half a request head, then stall.
  std::vector<int> silent, half;
  for (int i = 0; i < 20; ++i) silent.push_back(connect_to("127.0.0.1", server.port));
  for (int i = 0; i < 8; ++i) {
    half.push_back(connect_to("127.0.0.1", server.port));
    const std::string part = "GET /api/state HTTP/1.1\r\nHost: " + server.host + "\r\nAcc";
    (void)::send(half.back(), part.data(), part.size(), MSG_NOSIGNAL);
  }
  for (const int fd : silent) ASSERT_GE(fd, 0);
  for (const int fd : half) ASSERT_GE(fd, 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const Reply r = exchange("127.0.0.1", server.port, request("GET", "/api/state", server.host), 10);
  EXPECT_EQ(r.status, 200) << r.head;
  EXPECT_LT(r.seconds, 2.0);
  // The server closes a connection that sends nothing after 2 s, one that stalls mid-head after
  // 5 s (a read's timeout).
  for (const int fd : silent) {
    const Reply closed = read_reply(fd, 4);
    EXPECT_LT(closed.seconds, 4.0);
    ::close(fd);
  }
  for (const int fd : half) {
    const Reply closed = read_reply(fd, 7);
    EXPECT_LT(closed.seconds, 7.0);
    ::close(fd);
  }
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
}

// The process ids whose parent is `parent`, and whether a process runs (a zombie does not).
std::vector<pid_t> children_of(pid_t parent) {
  std::vector<pid_t> out;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(e.path() / "stat");
    std::string stat;
    std::getline(in, stat);
    std::istringstream fields(stat.substr(stat.rfind(')') + 1));
    char state = 0;
    pid_t ppid = 0;
    if (fields >> state >> ppid && ppid == parent) out.push_back(std::stoi(name));
  }
  return out;
}
bool runs(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string stat;
  if (!std::getline(in, stat)) return false;
  const std::size_t close = stat.rfind(')');
  return close != std::string::npos && close + 2 < stat.size() && stat[close + 2] != 'Z';
}

TEST(LabelCli, AKilledLabellerLeavesNoRoundRunning) {
  ServedCopy served("killed");
  ASSERT_EQ(served.failure(), "");
  const fs::path& state = served.state;
  LabelServer& server = served.server;
  // The round blocks as long as the test wants: the labels it reads first come from a pipe no one
  // writes (the server read them when it started).
  fs::remove(state / "labels.jsonl");
  ASSERT_EQ(::mkfifo((state / "labels.jsonl").c_str(), 0644), 0);
  const Reply train =
      exchange("127.0.0.1", server.port, json_post("/api/train", server.host, "{}"));
  ASSERT_EQ(train.status, 200) << train.head << train.body;
  pid_t round = -1;
  for (int i = 0; i < 100 && round < 0; ++i) {
    for (const pid_t pid : children_of(server.child->pid())) {
      std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline");
      const std::string cmdline{std::istreambuf_iterator<char>(in), {}};
      if (cmdline.find(std::string("induct\0--state", 14)) != std::string::npos) round = pid;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_GT(round, 0) << "no `stac induct` child of stac label";
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ASSERT_TRUE(runs(round)) << "the round ended by itself: " << server.child->log();

  EXPECT_EQ(server.child->stop(SIGKILL, 10), -1);
  bool ended = false;
  for (int i = 0; i < 50 && !ended; ++i) {
    ended = !runs(round);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_TRUE(ended) << "the round (pid " << round << ") still runs after stac label was killed";
  if (!ended) ::kill(round, SIGKILL);
}

TEST(LabelCli, AnIPv6AddressIsPrintedInBracketsAndServed) {
  const int probe = ::socket(AF_INET6, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in6 loopback{};
  loopback.sin6_family = AF_INET6;
  loopback.sin6_addr = in6addr_loopback;
  const bool has_ipv6 =
      probe >= 0 && ::bind(probe, reinterpret_cast<sockaddr*>(&loopback), sizeof loopback) == 0;
  if (probe >= 0) ::close(probe);
  if (!has_ipv6) GTEST_SKIP() << "this machine has no IPv6 loopback (::1)";
  ServedCopy served("ipv6", " --address ::1");
  ASSERT_EQ(served.failure(), "");
  LabelServer& server = served.server;
  EXPECT_EQ(server.url, "http://[::1]:" + std::to_string(server.port) + "/");
  const Reply r = exchange("::1", server.port, request("GET", "/api/state", server.host));
  EXPECT_EQ(r.status, 200) << r.head;
  EXPECT_EQ(exchange("::1", server.port, request("GET", "/api/state", "attacker.example")).status,
            403);
  EXPECT_EQ(server.child->stop(SIGTERM, 20), 0) << server.child->log();
}

}  // namespace
