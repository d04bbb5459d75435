// DDS Security on loopback (docs/dds.md, "Security"): the CAs, identities, governance and
// permissions made by deploy/dds-security.sh, Cyclone's security plugins from Debian, STAC's
// publisher in this process and `stac echo` / the C example as separate processes. Every test has
// its own domain id; negative cases publish for a few seconds and check that nothing got through.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dds/domain.hpp"
#include "dds/identity.hpp"
#include "dds/publisher.hpp"
#include "dds_test_support.hpp"
#include "test_paths.hpp"

namespace stac::dds {
namespace {

namespace fs = std::filesystem;
using testing::run_to_end;

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
    s.replace(at, from.size(), to);
  return s;
}

class DdsSecurity : public ::testing::Test {
 protected:
  // The vehicle's CAs with the publisher 'stac' and the subscriber 'viewer'; a second, foreign set
  // of CAs whose 'rogue' grants itself publishing; 'viewer' with a tampered certificate.
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("stac-dds-security-" + std::to_string(getpid()));
    fs::remove_all(dir_);
    const std::string script =
        std::string(::stac::testing::source_dir()) + "/deploy/dds-security.sh";
    const std::string quiet = " >" + (dir_.string() + ".log") + " 2>&1";
    ASSERT_EQ(std::system((script + " " + dir_.string() + " --subscriber viewer" + quiet).c_str()),
              0)
        << read_file(dir_.string() + ".log");
    ASSERT_EQ(
        std::system(
            (script + " " + (dir_ / "foreign").string() + " --publisher rogue" + quiet).c_str()),
        0)
        << read_file(dir_.string() + ".log");

    // One base64 character of the certificate's signature changed: still a well-formed PEM.
    fs::copy(dir_ / "viewer", dir_ / "tampered");
    std::string cert = read_file(dir_ / "viewer" / "cert.pem");
    const std::size_t end = cert.find("-----END");
    ASSERT_NE(end, std::string::npos);
    const std::size_t at = end - 12;
    cert[at] = cert[at] == 'A' ? 'B' : 'A';
    write_file(dir_ / "tampered" / "cert.pem", cert);
    write_file(dir_ / "tampered" / "cyclonedds.xml",
               replace_all(read_file(dir_ / "viewer" / "cyclonedds.xml"),
                           (dir_ / "viewer" / "cert.pem").string(),
                           (dir_ / "tampered" / "cert.pem").string()));

    // 'stac' (which may publish and subscribe) with the private key of 'viewer': both made by the
    // vehicle's CA, each well formed, but the key is not the certificate's.
    fs::copy(dir_ / "stac", dir_ / "mismatched");
    fs::copy_file(dir_ / "viewer" / "key.pem", dir_ / "mismatched" / "key.pem",
                  fs::copy_options::overwrite_existing);
    write_file(dir_ / "mismatched" / "cyclonedds.xml",
               replace_all(read_file(dir_ / "stac" / "cyclonedds.xml"),
                           (dir_ / "stac" / "key.pem").string(),
                           (dir_ / "mismatched" / "key.pem").string()));
  }
  static void TearDownTestSuite() {
    fs::remove_all(dir_);
    fs::remove(dir_.string() + ".log");
  }

  static std::string xml(const std::string& identity) {
    return (dir_ / identity / "cyclonedds.xml").string();
  }
  static rt::Result<std::unique_ptr<Publisher>> publisher(const std::string& xml_file,
                                                          std::uint32_t domain) {
    testing::loopback_uri();  // the discovery tag of this process
    PublisherConfig c;
    c.domain_id = domain;
    c.config_uri = "file://" + xml_file;
    return Publisher::create(c);
  }
  // `stac echo tracked_objects` as another process, started now (popen).
  static FILE* echo(const std::string& xml_file, std::uint32_t domain, int count, double timeout) {
    testing::loopback_uri();
    const std::string cmd = std::string(::stac::testing::stac_cli()) +
                            " echo tracked_objects --count " + std::to_string(count) +
                            " --timeout " + std::to_string(timeout) + " --domain " +
                            std::to_string(domain) + " --dds-config " + xml_file + " 2>&1";
    return popen(cmd.c_str(), "r");
  }
  // Publishes one object per scan every 100 ms for `seconds`; returns the most readers the
  // tracked_objects writer was ever matched with.
  static std::uint32_t publish_for(Publisher& pub, double seconds) {
    TrackedObjectIn o;
    o.object_id = 99;
    o.position = {5, 6, 0};
    std::vector<TrackedObjectIn> objects{o};
    std::uint32_t most = 0;
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    for (std::uint64_t scan = 0; std::chrono::steady_clock::now() < until; ++scan) {
      dds_publication_matched_status_t s{};
      if (dds_get_publication_matched_status(pub.writer(Topic::kTrackedObjects), &s) == 0)
        most = std::max(most, s.current_count);
      EXPECT_TRUE(pub.publish_tracked_objects({static_cast<std::int64_t>(scan), scan}, objects));
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return most;
  }
  // Waits up to 60 s (the handshakes of a loaded machine) for a matched reader.
  static bool wait_matched(Publisher& pub) {
    for (int i = 0; i < 600; ++i) {
      dds_publication_matched_status_t s{};
      if (dds_get_publication_matched_status(pub.writer(Topic::kTrackedObjects), &s) == 0 &&
          s.current_count > 0)
        return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  }
  // STAC's secure publisher on `domain` sends object 41 at (1.5, -2.25) in scans 0..2, each
  // acknowledged, to the subscriber `child` (popen, already started); returns its output.
  static std::string serve_three_scans(FILE* child, std::uint32_t domain, int* code) {
    EXPECT_NE(child, nullptr);
    if (child == nullptr) return "";
    auto pub = publisher(xml("stac"), domain);
    EXPECT_TRUE(pub) << pub.error().message;
    if (pub && wait_matched(**pub)) {
      TrackedObjectIn o;
      o.object_id = 41;
      o.position = {1.5, -2.25, 0};
      std::vector<TrackedObjectIn> objects{o};
      for (std::uint64_t scan = 0; scan < 3; ++scan) {
        EXPECT_TRUE(
            (*pub)->publish_tracked_objects({static_cast<std::int64_t>(scan), scan}, objects));
        EXPECT_EQ(dds_wait_for_acks((*pub)->writer(Topic::kTrackedObjects), DDS_SECS(20)), 0);
      }
    } else {
      ADD_FAILURE() << "the subscriber never matched STAC's secure writer";
    }
    return run_to_end(child, code);
  }

  static fs::path dir_;
};
fs::path DdsSecurity::dir_;

TEST_F(DdsSecurity, AnAuthenticatedSubscriberReceivesEveryScan) {
  int code = -1;
  const std::string out = serve_three_scans(echo(xml("viewer"), 141, 3, 60), 141, &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("tracked_objects scan 2 "), std::string::npos) << out;
  EXPECT_NE(out.find("#41"), std::string::npos) << out;
}

TEST_F(DdsSecurity, TheCSubscriberReadsWithItsIdentity) {
  testing::loopback_uri();
  const std::string cmd = "CYCLONEDDS_URI=file://" + xml("viewer") + " " +
                          ::stac::testing::c_subscriber() + " 3 142 2>&1";
  int code = -1;
  const std::string out = serve_three_scans(popen(cmd.c_str(), "r"), 142, &code);
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("scan 2: 1 objects\n  id 41 at x=1.50 y=-2.25"), std::string::npos) << out;
}

TEST_F(DdsSecurity, AnUnauthenticatedParticipantDiscoversNothingAndReadsNothing) {
  // A plain participant (no security) on the same domain, tag and loopback.
  const std::string plain = std::string(::stac::testing::source_dir()) + "/config/dds/loopback.xml";
  FILE* child = echo(plain, 143, 1, 6);
  ASSERT_NE(child, nullptr);
  auto pub = publisher(xml("stac"), 143);
  ASSERT_TRUE(pub) << pub.error().message;
  EXPECT_EQ(publish_for(**pub, 6), 0u) << "the secure writer matched an unauthenticated reader";
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("0 of 1 samples"), std::string::npos) << out;
}

TEST_F(DdsSecurity, AReadOnlyIdentityCannotCreateAWriter) {
  auto pub = publisher(xml("viewer"), 144);
  ASSERT_FALSE(pub) << "a subscriber's permissions let it create a STAC writer";
}

TEST_F(DdsSecurity, AParticipantOfAnotherAuthorityCannotInjectSamples) {
  // 'rogue' signed its own permissions to publish: its own participant accepts them, STAC's
  // subscribers must not.
  FILE* child = echo(xml("viewer"), 145, 1, 6);
  ASSERT_NE(child, nullptr);
  auto rogue = publisher((dir_ / "foreign" / "rogue" / "cyclonedds.xml").string(), 145);
  ASSERT_TRUE(rogue) << rogue.error().message;
  EXPECT_EQ(publish_for(**rogue, 6), 0u) << "a reader of the vehicle's CA matched the rogue writer";
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("0 of 1 samples"), std::string::npos) << out;
}

TEST_F(DdsSecurity, ATamperedCertificateIsRefused) {
  FILE* child = echo(xml("tampered"), 146, 1, 6);
  ASSERT_NE(child, nullptr);
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_NE(code, 0) << out;
  EXPECT_EQ(out.find("listening on"), std::string::npos) << out;
  EXPECT_NE(out.find("participant"), std::string::npos) << out;
}

// Cyclone 0.10 starts a participant whose private key is not its certificate's (no peer can
// authenticate it: a `stac run` serving nobody, rc 0); STAC refuses it first, naming both files.
TEST_F(DdsSecurity, APrivateKeyThatIsNotTheCertificatesIsRefusedAtStart) {
  auto pub = publisher(xml("mismatched"), 154);
  ASSERT_FALSE(pub) << "a publisher started with another identity's private key";
  EXPECT_NE(pub.error().message.find("is not the key of the identity certificate"),
            std::string::npos)
      << pub.error().message;
  EXPECT_NE(pub.error().message.find((dir_ / "mismatched" / "key.pem").string()), std::string::npos)
      << pub.error().message;
  // The same for a reader (`stac echo`); and XML given inline is read as a file is.
  FILE* child = echo(xml("mismatched"), 154, 1, 6);
  ASSERT_NE(child, nullptr);
  int code = -1;
  const std::string out = run_to_end(child, &code);
  EXPECT_NE(code, 0) << out;
  EXPECT_NE(out.find("is not the key of the identity certificate"), std::string::npos) << out;
  auto good = publisher(xml("stac"), 155);  // the right key still starts
  EXPECT_TRUE(good) << good.error().message;
  EXPECT_FALSE(check_identity_keys(read_file(xml("mismatched"))));
  EXPECT_TRUE(check_identity_keys(read_file(xml("stac"))));
}

// `stac-node --check` (check_domain) refuses what only a participant shows: a certificate its CA
// did not sign (issue 47: it said "complete"); the right identity passes, and a configuration
// without Security makes no participant.
TEST_F(DdsSecurity, TheCheckMakesAParticipantToRefuseAnIdentityCycloneRefuses) {
  testing::loopback_uri();
  PublisherConfig tampered;
  tampered.domain_id = 156;
  tampered.config_uri = "file://" + xml("tampered");
  EXPECT_TRUE(uses_security(tampered.config_uri));
  const rt::Status refused = check_domain(tampered);
  ASSERT_FALSE(refused) << "the check took a tampered certificate";
  EXPECT_NE(refused.error().message.find("DDS Security: file://" + xml("tampered")),
            std::string::npos)
      << refused.error().message;
  PublisherConfig good = tampered;
  good.domain_id = 157;
  good.config_uri = "file://" + xml("stac");
  EXPECT_TRUE(check_domain(good));
  EXPECT_FALSE(uses_security(testing::loopback_uri()));
}

}  // namespace
}  // namespace stac::dds
