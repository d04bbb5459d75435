// Real Cyclone participants for tests, isolated: every test uses its own domain id, created with
// config/dds/loopback.xml (loopback only, no multicast) and a discovery tag unique to this process.
#pragma once

#include <dds/dds.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "dds/topics.hpp"
#include "test_paths.hpp"

namespace stac::testing {

// Reads a popen() child's output to its end and closes it; *code = its exit code (-1: killed).
inline std::string run_to_end(FILE* p, int* code) {
  std::string out;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof(buf), p)) out.append(buf, n);
  const int status = pclose(p);
  *code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

inline std::string loopback_uri() {
  static const bool tagged = [] {
    const std::string tag = "stac-test-" + std::to_string(getpid());
    return setenv("DDS_TEST_TAG", tag.c_str(), 1) == 0;
  }();
  (void)tagged;
  return std::string("file://") + ::stac::testing::source_dir() + "/config/dds/loopback.xml";
}

// A reader on the publisher's domain (same process: the domain already has the loopback config).
class TestReader {
 public:
  TestReader(std::uint32_t domain, const dds_topic_descriptor_t* type, const std::string& name,
             dds::Topic t) {
    participant_ = dds_create_participant(domain, nullptr, nullptr);
    topic_ = dds_create_topic(participant_, type, name.c_str(), nullptr, nullptr);
    reader_ = dds_create_reader(participant_, topic_, dds::reader_qos(t).get(), nullptr);
  }
  ~TestReader() {
    if (loan_ != nullptr) dds_return_loan(reader_, &loan_, 1);
    dds_delete(participant_);
  }
  [[nodiscard]] bool ok() const { return participant_ > 0 && topic_ > 0 && reader_ > 0; }

  // Waits (up to 10 s) until `writer` matches this reader.
  static bool wait_matched(dds_entity_t writer) {
    for (int i = 0; i < 1000; ++i) {
      dds_publication_matched_status_t s{};
      if (dds_get_publication_matched_status(writer, &s) == 0 && s.current_count > 0) return true;
      dds_sleepfor(DDS_MSECS(10));
    }
    return false;
  }

  // The next sample as T (valid until the next take or the reader's end), or nullptr after 10 s.
  template <class T>
  const T* take() {
    if (loan_ != nullptr) dds_return_loan(reader_, &loan_, 1);
    loan_ = nullptr;
    for (int i = 0; i < 1000; ++i) {
      dds_sample_info_t info{};
      void* samples[1] = {nullptr};
      const dds_return_t n = dds_take(reader_, samples, &info, 1, 1);
      if (n > 0) {
        loan_ = samples[0];
        if (info.valid_data) return static_cast<const T*>(loan_);
        dds_return_loan(reader_, &loan_, 1);
        loan_ = nullptr;
        continue;
      }
      dds_sleepfor(DDS_MSECS(10));
    }
    return nullptr;
  }
  dds_entity_t reader() const { return reader_; }
  dds_entity_t topic() const { return topic_; }

 private:
  dds_entity_t participant_ = 0, topic_ = 0, reader_ = 0;
  void* loan_ = nullptr;
};

}  // namespace stac::testing
