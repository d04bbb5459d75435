// The cost of one tracked_objects sample at the publishing edge (issue 7: where the DDS publish ->
// receive time goes): converting and writing N objects with no reader matched (serialization),
// and writing then taking them in one process (serialization, local delivery, deserialization),
// on config/dds/loopback.xml. docs/benchmarks.md has the figures.
#include <benchmark/benchmark.h>
#include <dds/dds.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "dds/idl_types.hpp"
#include "dds/publisher.hpp"
#include "settings/build_tree.hpp"

namespace {

using stac::dds::Publisher;
using stac::dds::TrackedObjectIn;

std::vector<TrackedObjectIn> objects(int n) {
  std::vector<TrackedObjectIn> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    v[i].object_id = static_cast<std::uint64_t>(i + 1);
    v[i].position = {1.0 * i, -0.5 * i, 0.3};
    v[i].velocity = {5, 0.1, 0};
    v[i].dimensions = {4.5, 1.8, 1.5};
    v[i].state = 1;
  }
  return v;
}

std::unique_ptr<Publisher> publisher(std::uint32_t domain) {
  setenv("DDS_TEST_TAG", ("stac-bench-" + std::to_string(getpid())).c_str(), 1);
  stac::dds::PublisherConfig c;
  c.domain_id = domain;
  c.config_uri = std::string("file://") + stac::settings::kSourceDir + "/config/dds/loopback.xml";
  auto p = Publisher::create(c);
  if (!p) std::abort();
  return std::move(*p);
}

void BM_PublishTrackedObjects(benchmark::State& state) {
  static auto pub = publisher(150);
  const auto in = objects(static_cast<int>(state.range(0)));
  std::uint64_t scan = 0;
  for (auto _ : state) {
    if (!pub->publish_tracked_objects({0, scan++}, in)) state.SkipWithError("write failed");
  }
}
BENCHMARK(BM_PublishTrackedObjects)->Arg(50)->Arg(200)->Arg(512)->Unit(benchmark::kMicrosecond);

void BM_PublishAndTakeInProcess(benchmark::State& state) {
  static auto pub = publisher(151);
  static const dds_entity_t reader = [] {
    const dds_entity_t participant = dds_create_participant(151, nullptr, nullptr);
    const dds_entity_t topic =
        dds_create_topic(participant, stac::dds::IdlTypes<false>::tracked_objects(),
                         "stac/tracked_objects", nullptr, nullptr);
    return dds_create_reader(participant, topic,
                             stac::dds::reader_qos(stac::dds::Topic::kTrackedObjects).get(),
                             nullptr);
  }();
  const auto in = objects(static_cast<int>(state.range(0)));
  std::uint64_t scan = 0;
  for (auto _ : state) {
    if (!pub->publish_tracked_objects({0, scan++}, in)) state.SkipWithError("write failed");
    void* samples[1] = {nullptr};
    dds_sample_info_t info{};
    const dds_return_t n = dds_take(reader, samples, &info, 1, 1);
    if (n != 1) state.SkipWithError("nothing to take");
    if (n > 0) dds_return_loan(reader, samples, n);
  }
}
BENCHMARK(BM_PublishAndTakeInProcess)->Arg(50)->Arg(200)->Arg(512)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
