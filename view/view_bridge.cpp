#include "view/view_bridge.hpp"

#include <cstdio>

#include "dds/reading.hpp"
#include "view/foxglove_messages.hpp"

namespace stac::view {
namespace {

enum ChannelIndex : std::size_t { kCloud, kScene, kTransform, kHealth, kChannels };

}  // namespace

struct ViewBridge::State {
  std::string address;
  std::unique_ptr<FoxgloveServer> server;
  std::unique_ptr<dds::TopicReaders> readers;
  std::vector<Channel> channels;
  TrackPaths paths;  // tracked_objects' callback only
};

ViewBridge::ViewBridge(std::unique_ptr<State> state) : state_(std::move(state)) {}

ViewBridge::~ViewBridge() {
  state_->readers.reset();  // waits for running callbacks; none after
  state_->server.reset();
}

rt::Result<std::unique_ptr<ViewBridge>> ViewBridge::start(const dds::PublisherConfig& dds,
                                                          const ServerOptions& options) {
  auto state = std::make_unique<State>();
  State& s = *state;
  s.address = options.address;
  auto readers = dds::TopicReaders::create(dds);
  if (!readers) return rt::Unexpected<rt::Error>{readers.error()};
  const auto topic_of = [&](dds::Topic t) {
    std::string name = "/";
    return name.append((*readers)->topic_name(t));
  };
  s.channels = {{topic_of(dds::Topic::kPointCloud), "foxglove.PointCloud", kPointCloudSchema},
                {topic_of(dds::Topic::kTrackedObjects), "foxglove.SceneUpdate", kSceneUpdateSchema},
                {topic_of(dds::Topic::kEgoPose), "foxglove.FrameTransform", kFrameTransformSchema},
                {topic_of(dds::Topic::kHealth), "stac.Health", kHealthSchema}};
  std::string error;
  s.server = FoxgloveServer::start(options, s.channels, error);
  if (!s.server) return rt::make_error(error);
  FoxgloveServer& server = *s.server;
  // Every sample as its channel's message, built only while someone is subscribed to it.
  TrackPaths& paths = s.paths;
  const auto on_sample = [&server, &paths](const auto& sample, dds_time_t,
                                           const dds_sample_info_t&) {
    const auto send = [&](std::size_t ch, const auto& make) {
      if (server.subscribed(ch)) server.publish(ch, stamp_ns(sample.stamp), make().dump());
    };
    if constexpr (requires { sample.objects; }) {
      paths.update(sample);  // kept while nobody watches, so a new viewer sees whole paths
      send(kScene, [&] { return scene_update_message(sample, paths); });
    } else if constexpr (requires { sample.points; }) {
      send(kCloud, [&] { return point_cloud_message(sample); });
    } else if constexpr (requires { sample.stages; }) {
      send(kHealth, [&] { return health_message(sample); });
    } else if constexpr (requires { sample.orientation; }) {
      send(kTransform, [&] { return frame_transform_message(sample); });
    }
  };
  const auto listen_all = [&](auto ros2) -> rt::Status {
    constexpr bool kRos2 = decltype(ros2)::value;
    // Shallow histories: a viewer wants the newest scan, not a backlog.
    for (const auto& [topic, depth] : {std::pair{dds::Topic::kPointCloud, 2},
                                       {dds::Topic::kTrackedObjects, 4},
                                       {dds::Topic::kEgoPose, 8},
                                       {dds::Topic::kHealth, 8}}) {
      auto reader = dds::listen_topic<kRos2>(**readers, topic, depth, on_sample);
      if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    }
    return {};
  };
  const rt::Status listening =
      dds.ros2_names ? listen_all(std::true_type{}) : listen_all(std::false_type{});
  if (!listening) return rt::Unexpected<rt::Error>{listening.error()};
  s.readers = std::move(*readers);
  return std::unique_ptr<ViewBridge>(new ViewBridge(std::move(state)));
}

std::string ViewBridge::url() const {
  return "ws://" + state_->address + ":" + std::to_string(state_->server->port());
}

bool ViewBridge::any_subscribed() const noexcept {
  for (std::size_t c = 0; c < kChannels; ++c)
    if (state_->server->subscribed(c)) return true;
  return false;
}

ServerCounts ViewBridge::counts() const {
  return state_->server->counts();
}

std::string ViewBridge::summary() const {
  const ServerCounts c = counts();
  std::string out = "clients " + std::to_string(c.clients_accepted) + " (refused " +
                    std::to_string(c.clients_refused) + ", bad messages " +
                    std::to_string(c.bad_client_messages) + ")\n";
  for (std::size_t i = 0; i < c.channels.size(); ++i) {
    const ChannelCounts& k = c.channels[i];
    char line[256];
    std::snprintf(line, sizeof line,
                  "  %-26s %-24s built %llu, sent %llu, dropped %llu (slow client) + %llu "
                  "(backlog)\n",
                  state_->channels[i].topic.c_str(), state_->channels[i].schema_name.c_str(),
                  static_cast<unsigned long long>(k.published),
                  static_cast<unsigned long long>(k.sent),
                  static_cast<unsigned long long>(k.dropped_slow_client),
                  static_cast<unsigned long long>(k.dropped_backlog));
    out += line;
  }
  for (const ClientCounts& k : c.clients) {
    char line[256];
    std::snprintf(line, sizeof line, "  client %llu (%s): sent %llu, dropped %llu (slow client)\n",
                  static_cast<unsigned long long>(k.number), k.peer.c_str(),
                  static_cast<unsigned long long>(k.sent),
                  static_cast<unsigned long long>(k.dropped_slow_client));
    out += line;
  }
  return out;
}

}  // namespace stac::view
