// The labelling page (label_page.hpp): the state it serves, its routes, its limits and the
// check every request passes, and the server `stac label` runs.
#include "label/label_page.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <pthread.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>
#include <utility>

#include "formats/dataset_file.hpp"
#include "formats/durable_file.hpp"
#include "formats/induction_state.hpp"
#include "label_page_html.hpp"
#include "rt/formatted.hpp"

// Last: httplib.h brings <resolv.h>, whose _res macro breaks Eigen's headers included after it.
#include <httplib.h>

namespace stac::label {

using namespace stac::formats;
namespace fs = std::filesystem;

std::string url_host(const std::string& address) {
  return address.find(':') == std::string::npos ? address : "[" + address + "]";
}

namespace {

// Served on every response: no other page may frame this one, nothing is sniffed, and no URL
// leaves it as a Referer. The page's script and style are inline (label/label.html).
httplib::Headers security_headers() {
  return {{"X-Frame-Options", "DENY"},
          {"Content-Security-Policy",
           "default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'self' "
           "'unsafe-inline'; frame-ancestors 'none'; base-uri 'none'; form-action 'none'"},
          {"X-Content-Type-Options", "nosniff"},
          {"Referrer-Policy", "no-referrer"}};
}

using rt::echoed;  // a value from a request, as an error message quotes it

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

// The Host header's name for each way this connection's page may be reached: the address served
// (--address, as printed), the address the connection came to (an IPv4 one also as IPv4-mapped
// IPv6 gives it) and, on loopback, localhost and both loopback addresses; the port served. A
// name of another site resolved to this machine (DNS rebinding) is none of them.
bool host_allowed(const std::string& host, const std::string& served, const std::string& local_addr,
                  int local_port) {
  const std::string h = lowercase(host);
  const std::size_t colon = h.rfind(':');
  const bool has_port = colon != std::string::npos && h.find(']', colon) == std::string::npos;
  const std::string name = has_port ? h.substr(0, colon) : h;
  if ((has_port ? h.substr(colon + 1) : "80") != std::to_string(local_port)) return false;
  std::string addr = lowercase(local_addr);
  if (addr.rfind("::ffff:", 0) == 0 && addr.find('.') != std::string::npos) addr.erase(0, 7);
  const bool loopback = addr.rfind("127.", 0) == 0 || addr == "::1";
  return name == url_host(addr) || name == url_host(lowercase(served)) ||
         (loopback && (name == "localhost" || name == "127.0.0.1" || name == "[::1]"));
}

struct Refusal {
  int status;
  std::string error;
};

// Why a request is refused before its body is read, if it is: a Host that is not this server
// (DNS rebinding), an Origin that is not the page's own, a POST that is no JSON (a cross-site
// form can send only form types without a CORS preflight, which is never granted), or a body
// over kMaxBodyBytes or without a Content-Length.
std::optional<Refusal> refusal(const httplib::Request& req, const std::string& served) {
  if (req.get_header_value_count("Host") != 1 ||
      !host_allowed(req.get_header_value("Host"), served, req.local_addr, req.local_port))
    return Refusal{403, "Host " + echoed(req.get_header_value("Host")) +
                            " is not this server; open the address stac label printed"};
  const std::string self = "http://" + lowercase(req.get_header_value("Host"));
  if (req.has_header("Origin") && lowercase(req.get_header_value("Origin")) != self)
    return Refusal{403, "requests from " + echoed(req.get_header_value("Origin")) +
                            " are refused; only the page at " + self + " may ask"};
  if (req.method != "POST") return std::nullopt;
  std::string type = lowercase(req.get_header_value("Content-Type"));
  type = type.substr(0, type.find(';'));
  type.erase(type.find_last_not_of(" \t") + 1);
  if (type != "application/json")
    return Refusal{403, "a POST here is Content-Type: application/json"};
  const std::string length = req.get_header_value("Content-Length");
  if (req.has_header("Transfer-Encoding") || length.empty() ||
      length.find_first_not_of("0123456789") != std::string::npos)
    return Refusal{411, "a POST here has a Content-Length (and no Transfer-Encoding)"};
  if (length.size() > 12 || std::stoull(length) > kMaxBodyBytes)
    return Refusal{413, "a body here is at most " + std::to_string(kMaxBodyBytes) + " bytes"};
  return std::nullopt;
}

struct Question {
  std::string source;
  std::uint64_t track = 0;
  nlohmann::json line;  // as queries.jsonl has it
};

std::vector<nlohmann::json> read_json_lines(const fs::path& file) {
  std::vector<nlohmann::json> out;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (!j.is_discarded() && j.is_object()) out.push_back(std::move(j));
  }
  return out;
}

}  // namespace

class LabelPage::State {
 public:
  State(PageOptions o, StartRound start)
      : o_(std::move(o)), dir_(o_.state), start_(std::move(start)) {}

  rt::Status open() {
    auto s = read_induction_state(dir_);
    if (!s) return rt::make_error(s.error().message);
    if (!s->has_model)
      return rt::make_error(dir_.string() + ": no round has run yet; run `stac induct --state " +
                            dir_.string() +
                            " ... --unlabeled DATASET` first, it writes the questions");
    classes_ = s->classes;
    rounds_ = s->rounds;
    sources_ = s->sources;
    // A torn last line is cut; a person's whole last answer without its newline is kept, and a
    // whole JSON line that is no answer is refused naming it.
    if (auto c = complete_or_cut_tail(dir_ / "labels.jsonl", is_answer_line, is_json_line); !c)
      return rt::make_error(c.error().message);
    if (questions().empty())
      std::fprintf(stderr,
                   "stac label: %s has no open question; answered ones start a round with "
                   "\"train now\"\n",
                   (dir_ / "queries.jsonl").c_str());
    return {};
  }

  void routes(httplib::Server& server) {
    server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
      const std::optional<Refusal> r = refusal(req, o_.address);
      if (!r) return httplib::Server::HandlerResponse::Unhandled;
      res.status = r->status;
      res.set_content(nlohmann::json{{"error", r->error}}.dump(), "application/json");
      return httplib::Server::HandlerResponse::Handled;
    });
    server.Get("/", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(kLabelPage, "text/html; charset=utf-8");
    });
    server.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
      const std::lock_guard lock(mutex_);
      res.set_content(state_json().dump(), "application/json");
    });
    server.Get("/api/track", [this](const httplib::Request& req, httplib::Response& res) {
      const std::lock_guard lock(mutex_);
      reply(res, track_json(req.get_param_value("source"), req.get_param_value("track")));
    });
    server.Post("/api/answer", [this](const httplib::Request& req, httplib::Response& res) {
      const std::lock_guard lock(mutex_);
      reply(res, answer(req.body));
    });
    server.Post("/api/train", [this](const httplib::Request&, httplib::Response& res) {
      const std::lock_guard lock(mutex_);
      reply(res, start_round());
    });
  }

  static void reply(httplib::Response& res, const rt::Result<nlohmann::json>& r) {
    if (r) {
      res.set_content(r->dump(), "application/json");
    } else {
      res.status = 400;
      res.set_content(nlohmann::json{{"error", r.error().message}}.dump(), "application/json");
    }
  }

  // The questions of queries.jsonl, and which of them labels.jsonl answers.
  std::vector<Question> questions() const {
    std::vector<Question> out;
    for (nlohmann::json& j : read_json_lines(dir_ / "queries.jsonl")) {
      if (!j.contains("source") || !j["source"].is_string() || !j.contains("track") ||
          !j["track"].is_number_unsigned())
        continue;
      out.push_back({j["source"].get<std::string>(), j["track"].get<std::uint64_t>(), j});
    }
    return out;
  }
  std::map<std::pair<std::string, std::uint64_t>, std::string> answers() const {
    std::map<std::pair<std::string, std::uint64_t>, std::string> out;
    for (const nlohmann::json& j : read_json_lines(dir_ / "labels.jsonl"))
      if (j.contains("source") && j["source"].is_string() && j.contains("track") &&
          j["track"].is_number_unsigned() && j.contains("label") && j["label"].is_string())
        out.try_emplace({j["source"].get<std::string>(), j["track"].get<std::uint64_t>()},
                        j["label"].get<std::string>());
    return out;
  }

  // A round that ended: its result read back (new questions, the round count), once.
  void poll_round() {
    if (!round_) return;
    const auto code = round_->poll();
    if (!code) return;
    if (*code == 0) {
      if (auto s = read_induction_state(dir_); s) rounds_ = s->rounds, sources_ = s->sources;
      last_round_ = "round " + std::to_string(rounds_) + " done";
    } else {
      last_round_ = "the round failed (exit " + std::to_string(*code) + "): " + round_->log_tail(3);
    }
    std::fprintf(stderr, "stac label: %s\n", last_round_.c_str());
    round_.reset();
  }

  nlohmann::json state_json() {
    poll_round();
    const auto answered = answers();
    nlohmann::json qs = nlohmann::json::array();
    std::size_t open = 0;
    for (const Question& q : questions()) {
      nlohmann::json j = q.line;
      const auto it = answered.find({q.source, q.track});
      j["answer"] = it == answered.end() ? nlohmann::json(nullptr) : nlohmann::json(it->second);
      open += it == answered.end() ? 1 : 0;
      qs.push_back(std::move(j));
    }
    return {{"state", dir_.string()},
            {"classes", classes_},
            {"rounds", rounds_},
            {"questions", qs},
            {"open", open},
            {"answers", answered.size()},
            {"training", round_ != nullptr},
            {"last_round", last_round_}};
  }

  rt::Result<const Dataset*> dataset(const std::string& path) {
    if (auto it = datasets_.find(path); it != datasets_.end()) return &it->second;
    auto d = read_dataset(path);
    if (!d) return rt::make_error(d.error().message);
    // The questions name its tracks by number: a dataset remade since the state read it would
    // show other tracks under them (sources_ is this server's copy; the state is never written).
    if (auto b = bind_source_dataset(sources_, path, d->checksum); !b)
      return rt::make_error(b.error().message);
    return &datasets_.emplace(path, std::move(d).value()).first->second;
  }

  static bool asked(const std::vector<Question>& qs, const std::string& source,
                    std::uint64_t track) {
    return std::any_of(qs.begin(), qs.end(),
                       [&](const Question& q) { return q.source == source && q.track == track; });
  }

  rt::Result<nlohmann::json> track_json(const std::string& source, const std::string& track_text) {
    char* end = nullptr;
    const unsigned long long track = std::strtoull(track_text.c_str(), &end, 10);
    if (track_text.empty() || end == nullptr || *end != '\0' || !asked(questions(), source, track))
      return rt::make_error("no question about track " + echoed(track_text) + " of " +
                            echoed(source));
    auto d = dataset(source);
    if (!d) return rt::make_error(d.error().message);
    if (track >= (*d)->tracks.size())
      return rt::make_error(echoed(source) + " has " + std::to_string((*d)->tracks.size()) +
                            " tracks");
    const DatasetTrack& t = (*d)->tracks[track];
    nlohmann::json path = nlohmann::json::array(), snapshots = nlohmann::json::array();
    for (std::size_t k = 0; k + 1 < t.path.size(); k += 2)
      path.push_back({t.path[k], t.path[k + 1]});
    for (const TrackSnapshot& snap : t.snapshots) {
      nlohmann::json points = nlohmann::json::array();
      for (std::size_t k = 0; k + 3 < snap.points.size(); k += 4)
        points.push_back({std::round(snap.points[k] * 100.0f) / 100.0f,
                          std::round(snap.points[k + 1] * 100.0f) / 100.0f,
                          std::round(snap.points[k + 2] * 100.0f) / 100.0f,
                          std::round(snap.points[k + 3])});
      snapshots.push_back({{"segment", snap.segment}, {"points", points}});
    }
    nlohmann::json out = {{"source", source},       {"track", track}, {"id", t.id},
                          {"segments", t.segments}, {"path", path},   {"snapshots", snapshots}};
    if (t.snapshots.empty())
      out["note"] =
          "this dataset has no points to show (made before dataset format 5); remake it with "
          "this build's `stac dataset` to see the track";
    return out;
  }

  rt::Result<nlohmann::json> answer(const std::string& body) {
    poll_round();
    if (round_)
      return rt::make_error("a round is running; answer when its new questions are shown");
    const nlohmann::json j = nlohmann::json::parse(body, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("source") || !j["source"].is_string() ||
        !j.contains("track") || !j["track"].is_number_unsigned() || !j.contains("label") ||
        !j["label"].is_string())
      return rt::make_error(
          "an answer is {\"source\": DATASET, \"track\": INDEX, \"label\": NAME}");
    const std::string source = j["source"].get<std::string>();
    const auto track = j["track"].get<std::uint64_t>();
    const std::string label = j["label"].get<std::string>();
    if (label != "background" && label != "skip" &&
        std::find(classes_.begin(), classes_.end(), label) == classes_.end())
      return rt::make_error("label " + echoed(label) + " is none of " +
                            classification::joined(classes_) + ", background, skip");
    // Each file read once per answer.
    const std::vector<Question> qs = questions();
    if (!asked(qs, source, track))
      return rt::make_error("no question about track " + std::to_string(track) + " of " +
                            echoed(source));
    auto answered = answers();
    if (answered.count({source, track}) != 0)
      return rt::make_error("track " + std::to_string(track) + " of " + source +
                            " is answered already (the first answer holds)");
    const nlohmann::json line = {{"source", source}, {"track", track}, {"label", label}};
    if (auto a = append_line_durably(dir_ / "labels.jsonl", line.dump()); !a)
      return rt::make_error(a.error().message);
    std::fprintf(stderr, "stac label: %s track %llu: %s\n", source.c_str(),
                 static_cast<unsigned long long>(track), label.c_str());
    answered.emplace(std::pair{source, track}, label);
    nlohmann::json out = {{"saved", true}};
    std::size_t open = 0;
    for (const Question& q : qs) open += answered.count({q.source, q.track}) == 0 ? 1 : 0;
    out["open"] = open;
    if (open == 0) {
      auto r = start_round();
      if (!r) return r;
      out["training"] = true;
    }
    return out;
  }

  rt::Result<nlohmann::json> start_round() {
    poll_round();
    if (round_) return nlohmann::json{{"training", true}};
    std::vector<std::string> args = {"induct",
                                     "--state",
                                     dir_.string(),
                                     "--rounds",
                                     "1",
                                     "--requery",
                                     "--ask",
                                     std::to_string(o_.ask),
                                     "--warm-rounds",
                                     std::to_string(o_.warm_rounds),
                                     "--reset-rounds",
                                     std::to_string(o_.reset_rounds)};
    if (o_.ask_confident) {
      args.emplace_back("--ask-confident");
      args.push_back(std::to_string(*o_.ask_confident));
    }
    // A labeller killed by SIGKILL leaves no round writing the state behind it.
    auto round = start_(args, dir_ / "label-round.log");
    if (!round) return rt::make_error("cannot start the round: " + round.error().message);
    round_ = std::move(round).value();
    last_round_ = "round " + std::to_string(rounds_ + 1) + " running";
    std::fprintf(stderr, "stac label: %s (log %s)\n", last_round_.c_str(),
                 (dir_ / "label-round.log").c_str());
    return nlohmann::json{{"training", true}};
  }

 private:
  PageOptions o_;
  fs::path dir_;
  StartRound start_;
  std::mutex mutex_;
  classification::ClassNames classes_;
  std::uint32_t rounds_ = 0;
  std::vector<InductionSource> sources_;  // the state's, with the checksums of its datasets
  std::map<std::string, Dataset> datasets_;
  std::unique_ptr<Round> round_;
  std::string last_round_;
};

LabelPage::LabelPage(PageOptions options, StartRound start_round)
    : state_(std::make_unique<State>(std::move(options), std::move(start_round))) {}
LabelPage::~LabelPage() = default;

rt::Status LabelPage::open() {
  return state_->open();
}

void LabelPage::serve_on(httplib::Server& server) {
  // httplib's default adds SO_REUSEPORT, with which a second server on a port in use would
  // share it silently; SO_REUSEADDR alone lets a restart take the port at once, nothing more.
  server.set_socket_options([](socket_t sock) {
    const int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  // The limits (kMaxBodyBytes and the rest; docs/learning.md "Limits"). One request per
  // connection: a refused request's unread body is never taken for the next request, and no idle
  // keep-alive connection holds one of the threads.
  server.set_payload_max_length(kMaxBodyBytes);
  server.set_read_timeout(kReadTimeoutS, 0);
  server.set_write_timeout(kReadTimeoutS, 0);
  server.set_keep_alive_timeout(kIdleTimeoutS);
  server.set_keep_alive_max_count(1);
  server.new_task_queue = [] { return new httplib::ThreadPool(kThreads); };
  server.set_default_headers(security_headers());
  state_->routes(server);
}

namespace {

// One connection's bytes as httplib reads them, with a budget: cpp-httplib 0.11.4 (Debian 12's)
// reads a request line or a header line whole before it checks its length, and any number of
// header lines, so an endless line would cost memory until the client stops. Here the
// connection (one request: keep-alive is off) ends when kMaxRequestBytes are read.
class BoundedSocketStream final : public httplib::Stream {
 public:
  BoundedSocketStream(int fd, int read_timeout_ms, int write_timeout_ms)
      : fd_(fd), read_timeout_ms_(read_timeout_ms), write_timeout_ms_(write_timeout_ms) {}

  bool is_readable() const override { return wait(POLLIN, read_timeout_ms_); }
  bool is_writable() const override { return wait(POLLOUT, write_timeout_ms_); }
  ssize_t read(char* ptr, size_t size) override {
    if (at_ == end_) {
      if (left_ == 0 || !is_readable()) return -1;  // over the budget, or stalled: the end
      const ssize_t n = recv_some(buffer_.data(), std::min(buffer_.size(), left_));
      if (n <= 0) return n;
      left_ -= static_cast<std::size_t>(n);
      at_ = 0;
      end_ = static_cast<std::size_t>(n);
    }
    const std::size_t n = std::min(size, end_ - at_);
    std::copy_n(buffer_.data() + at_, n, ptr);
    at_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    if (!is_writable()) return -1;
    ssize_t n = 0;
    do {
      n = ::send(fd_, ptr, size, MSG_NOSIGNAL);
    } while (n < 0 && errno == EINTR);
    return n;
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t size = sizeof(a);
    if (::getpeername(fd_, reinterpret_cast<sockaddr*>(&a), &size) == 0) numeric(a, size, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage a{};
    socklen_t size = sizeof(a);
    if (::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &size) == 0) numeric(a, size, ip, port);
  }
  socket_t socket() const override { return fd_; }

 private:
  bool wait(short events, int timeout_ms) const {
    pollfd p{fd_, events, 0};
    int n = 0;
    do {
      n = ::poll(&p, 1, timeout_ms);
    } while (n < 0 && errno == EINTR);
    return n > 0;
  }
  ssize_t recv_some(char* into, std::size_t size) const {
    ssize_t n = 0;
    do {
      n = ::recv(fd_, into, size, 0);
    } while (n < 0 && errno == EINTR);
    return n;
  }
  // The address as httplib gives it (getnameinfo, numeric: an IPv4 client of an IPv6 socket as
  // ::ffff:a.b.c.d).
  static void numeric(const sockaddr_storage& a, socklen_t size, std::string& ip, int& port) {
    std::array<char, NI_MAXHOST> host{};
    if (::getnameinfo(reinterpret_cast<const sockaddr*>(&a), size, host.data(), host.size(),
                      nullptr, 0, NI_NUMERICHOST) == 0)
      ip = host.data();
    port = a.ss_family == AF_INET6 ? ntohs(reinterpret_cast<const sockaddr_in6&>(a).sin6_port)
                                   : ntohs(reinterpret_cast<const sockaddr_in&>(a).sin_port);
  }

  int fd_;
  int read_timeout_ms_, write_timeout_ms_;
  std::size_t left_ = kMaxRequestBytes;
  std::array<char, 4096> buffer_{};
  std::size_t at_ = 0, end_ = 0;
};

// httplib's server with each connection read through a BoundedSocketStream: one request, after
// at most kIdleTimeoutS of silence, then the connection closed.
class BoundedServer final : public httplib::Server {
  bool process_and_close_socket(socket_t sock) override {
    bool served = false;
    pollfd p{sock, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(keep_alive_timeout_sec_) * 1000) > 0) {
      BoundedSocketStream stream(sock, static_cast<int>(read_timeout_sec_) * 1000,
                                 static_cast<int>(write_timeout_sec_) * 1000);
      bool closed = false;
      served = process_request(stream, true, closed, {});
    }
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
    return served;
  }
};

}  // namespace

rt::Status serve(const PageOptions& options, StartRound start_round,
                 const std::function<void(const std::string& url)>& on_listening) {
  // One server per state: a second one would ask the same questions and start rounds beside
  // the first. The lock goes with the process, however it ends.
  const fs::path lock_path = options.state / "label.lock";
  const int lock = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX | LOCK_NB) != 0) {
    if (lock >= 0) ::close(lock);
    return rt::make_error(options.state.string() + ": another `stac label` serves this state (" +
                          lock_path.string() + " is locked); use that one, or stop it first");
  }
  struct Unlock {
    int fd;
    ~Unlock() { ::close(fd); }
  } unlock{lock};
  LabelPage page(options, std::move(start_round));
  if (auto r = page.open(); !r) return r;
  BoundedServer server;
  page.serve_on(server);
  const int port = options.port == 0
                       ? server.bind_to_any_port(options.address)
                       : (server.bind_to_port(options.address, options.port) ? options.port : -1);
  if (port < 0)
    return rt::make_error("cannot listen on " + url_host(options.address) + ":" +
                          std::to_string(options.port) +
                          " (in use, or not an address of this machine); choose another with "
                          "--port or --address");
  // SIGINT and SIGTERM end the server from a thread of their own (stop() is not
  // async-signal-safe); blocked here, before the server's threads exist, so they inherit it.
  sigset_t stop_signals{};
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::atomic<bool> serving{true};
  std::thread stopper([&] {
    const timespec tick{0, 200'000'000};
    while (serving.load())
      if (sigtimedwait(&stop_signals, nullptr, &tick) > 0) {
        server.stop();
        break;
      }
  });
  on_listening("http://" + url_host(options.address) + ":" + std::to_string(port) + "/");
  const bool ok = server.listen_after_bind();
  serving.store(false);  // the stopper ends within a tick (when the server failed by itself)
  stopper.join();
  if (!ok) return rt::make_error("the server stopped with an error");
  return {};
}

}  // namespace stac::label
