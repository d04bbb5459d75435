// What a browser (or anything else on the machine) sends `stac label`'s page
// (label/label_page.hpp): the input is the bytes of one connection, served in-process by
// cpp-httplib with the page's own routes, limits and request check, a request after another until
// the bytes run out, as the real server would on a socket. The page serves a state made at
// start-up: two questions about the two tracks of a small dataset (/tmp/stac_label_fuzz/drive, as
// the seeds name it); a round asked for ends at once (no program is started). Beyond the
// sanitizers, after every input: each reply is bounded (no request makes the page echo it back
// whole), and labels.jsonl holds only whole answers, one per question asked, with a label the page
// offers (the first answer holds; nothing else is ever written there).
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "formats/dataset_file.hpp"
#include "formats/induction_state.hpp"
#include "label/label_page.hpp"
#include "perception/classification/model.hpp"

// Last: httplib.h brings <resolv.h>, whose _res macro breaks Eigen's headers included after it.
#include <httplib.h>

namespace {

namespace fs = std::filesystem;
using namespace stac;

constexpr int kPort = 8642;
constexpr std::size_t kMaxRequests = 16;            // per input
constexpr std::size_t kMaxReplyBytes = 256 * 1024;  // the largest honest reply is a few KiB

// One connection's bytes: what the client sent, then the end; what the server writes is kept.
class InputStream final : public httplib::Stream {
 public:
  explicit InputStream(std::string_view in) : in_(in) {}
  bool is_readable() const override { return true; }
  bool is_writable() const override { return true; }
  ssize_t read(char* ptr, size_t size) override {
    const std::size_t n = std::min(size, in_.size() - at_);
    std::copy_n(in_.data() + at_, n, ptr);
    at_ += n;
    return static_cast<ssize_t>(n);
  }
  ssize_t write(const char* ptr, size_t size) override {
    written_.append(ptr, size);
    return static_cast<ssize_t>(size);
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = 40000;
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    ip = "127.0.0.1";
    port = kPort;
  }
  socket_t socket() const override { return INVALID_SOCKET; }

  [[nodiscard]] bool done() const { return at_ >= in_.size(); }
  std::string take_written() { return std::exchange(written_, {}); }

 private:
  std::string_view in_;
  std::size_t at_ = 0;
  std::string written_;
};

// A server whose request handling can be driven by a stream (httplib keeps it protected).
class FuzzServer final : public httplib::Server {
 public:
  bool serve_one(httplib::Stream& stream) {
    bool closed = false;
    return process_request(stream, false, closed, [](httplib::Request&) {});
  }
};

// A round that has ended well at once.
class DoneRound final : public label::Round {
 public:
  std::optional<int> poll() override { return 0; }
  [[nodiscard]] std::string log_tail(int) const override { return {}; }
};

struct Fixture {
  fs::path dir;
  std::unique_ptr<label::LabelPage> page;
  FuzzServer server;
};

// /tmp/stac_label_fuzz, the folder the seeds name, unless another harness process holds it (a
// second campaign beside this one): then a folder of its own.
fs::path fixture_dir() {
  const fs::path fixed = "/tmp/stac_label_fuzz";
  fs::create_directories(fixed);
  const int lock = ::open((fixed / "lock").c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock >= 0 && ::flock(lock, LOCK_EX | LOCK_NB) == 0) return fixed;  // held until exit
  char dir_template[] = "/tmp/stac_label_fuzz_XXXXXX";
  if (::mkdtemp(dir_template) == nullptr) std::abort();
  return dir_template;
}

Fixture& fixture() {
  static Fixture* f = [] {
    auto* made = new Fixture;
    made->dir = fixture_dir();
    const fs::path data = made->dir / "drive";
    formats::Dataset dataset;
    dataset.labelled = false;
    dataset.sources = {"drive.pcap"};
    for (std::uint64_t id = 0; id < 2; ++id) {
      formats::DatasetTrack t;
      t.id = id + 7;
      t.segments = 2;
      t.path = {1.0f, 2.0f, 1.5f, 2.5f};
      t.snapshots = {{0, {0.1f, 0.2f, 0.3f, 40.0f, -0.1f, 0.0f, 1.2f, 80.0f}}};
      dataset.tracks.push_back(std::move(t));
    }
    if (!formats::write_dataset(data, dataset)) std::abort();
    formats::InductionState state;
    // The shipped model (a state's model must be one this build can use).
    std::ifstream model_file(STAC_SOURCE_DIR "/config/models/stac_default.stacmodel",
                             std::ios::binary);
    const std::vector<std::uint8_t> model_bytes{std::istreambuf_iterator<char>(model_file),
                                                std::istreambuf_iterator<char>()};
    auto model = classification::deserialize(model_bytes);
    if (!model) std::abort();
    state.model = std::move(model).value();
    state.classes = state.model.classes;
    state.sources.push_back({data.string(), formats::SourceRole::kUnlabeled});
    state.rounds = 1;
    state.has_model = true;
    if (!formats::write_induction_state(made->dir, state)) std::abort();
    std::ofstream queries(made->dir / "queries.jsonl");
    for (int track = 0; track < 2; ++track)
      queries << nlohmann::json{{"source", data.string()},
                                {"track", track},
                                {"class", "pedestrian"},
                                {"confidence", 0.5}}
                     .dump()
              << '\n';
    queries.close();
    label::PageOptions options;
    options.state = made->dir;
    options.port = kPort;
    made->page = std::make_unique<label::LabelPage>(
        options, [](const std::vector<std::string>&, const fs::path&) {
          return rt::Result<std::unique_ptr<label::Round>>(std::make_unique<DoneRound>());
        });
    if (auto opened = made->page->open(); !opened) {
      std::fprintf(stderr, "label_http_fuzz: %s\n", opened.error().message.c_str());
      std::abort();
    }
    made->page->serve_on(made->server);
    return made;
  }();
  return *f;
}

// labels.jsonl: whole answer lines only, each about a question asked with an offered label, at
// most one per question.
void check_answers(const Fixture& f) {
  std::ifstream in(f.dir / "labels.jsonl", std::ios::binary);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (!text.empty() && text.back() != '\n') std::abort();
  const std::set<std::string> offered = {"car", "pedestrian", "bicyclist", "background", "skip"};
  std::set<std::uint64_t> answered;
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = text.find('\n', at);
    const nlohmann::json j = nlohmann::json::parse(text.substr(at, end - at), nullptr, false);
    at = end + 1;
    if (j.is_discarded() || !j.is_object() || j.size() != 3) std::abort();
    if (j.value("source", "") != (f.dir / "drive").string()) std::abort();
    if (!j["track"].is_number_unsigned() || j["track"].get<std::uint64_t>() > 1) std::abort();
    if (!j["label"].is_string() || offered.count(j["label"].get<std::string>()) == 0) std::abort();
    if (!answered.insert(j["track"].get<std::uint64_t>()).second) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& f = fixture();
  fs::remove(f.dir / "labels.jsonl");  // each input starts with no answer
  InputStream stream(std::string_view(reinterpret_cast<const char*>(data), size));
  for (std::size_t n = 0; n < kMaxRequests && !stream.done(); ++n) {
    const bool served = f.server.serve_one(stream);
    if (stream.take_written().size() > kMaxReplyBytes) std::abort();
    if (!served) break;
  }
  check_answers(f);
  return 0;
}
