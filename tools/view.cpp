// stac view: STAC's DDS topics in Foxglove (or Lichtblick), live: a Foxglove WebSocket server
// that subscribes to point_cloud, tracked_objects, ego_pose and health and serves them as
// foxglove.PointCloud, SceneUpdate, FrameTransform and a JSON health topic (docs/view.md).
#include <csignal>
#include <cstdio>
#include <string>

#include "dds/reading.hpp"
#include "settings/dds_settings.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"
#include "tools/support/cli_checks.hpp"
#include "view/view_bridge.hpp"

namespace stac::tools {
using namespace stac::settings;

namespace {

struct ViewOptions {
  std::string config, dds_config, address = "127.0.0.1";
  int port = 8765;
  int domain = -1;
  double seconds = 0;
  double client_buffer_mb = 16;
};

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_stop(int) {
  g_stop = 1;
}

int run_view(const ViewOptions& o) {
  auto settings = load_dds_settings(config_path(o.config));
  if (!settings) return fail(settings.error().message);
  dds::PublisherConfig c = *settings;
  override_dds(c, o.domain, o.dds_config);
  view::ServerOptions server;
  server.address = o.address;
  server.port = static_cast<std::uint16_t>(o.port);
  server.max_client_buffer_bytes = static_cast<std::size_t>(o.client_buffer_mb * 1024 * 1024);
  auto bridge = view::ViewBridge::start(c, server);
  if (!bridge) return fail(bridge.error().message);
  std::fprintf(
      stderr,
      "stac view: serving DDS domain %u on %s\n"
      "stac view: in Foxglove or Lichtblick: Open connection -> Foxglove WebSocket -> %s\n",
      c.domain_id, (*bridge)->url().c_str(), (*bridge)->url().c_str());
  struct sigaction sa {};
  sa.sa_handler = on_stop;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  const dds_time_t end =
      o.seconds > 0 ? dds_time() + static_cast<dds_duration_t>(o.seconds * 1e9) : DDS_NEVER;
  while (g_stop == 0 && dds_time() < end) dds_sleepfor(DDS_MSECS(50));
  const std::string summary = (*bridge)->summary();
  bridge->reset();
  std::fprintf(stderr, "stac view: %s", summary.c_str());
  return 0;
}

}  // namespace

void add_view_command(CLI::App& app) {
  auto o = std::make_shared<ViewOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view", "STAC's DDS topics live in Foxglove or Lichtblick (a Foxglove WebSocket server)");
  cmd->description(
      "Subscribes to STAC's DDS topics (of a `stac run`, `stac-node`, `stac demo` or\n"
      "`stac process --dds`) and serves them over the Foxglove WebSocket protocol: the point\n"
      "cloud (foxglove.PointCloud, coloured by class), the tracks (foxglove.SceneUpdate: boxes\n"
      "coloured by class, id, class and speed as text, velocity arrows, paths), the ego pose\n"
      "(foxglove.FrameTransform map -> base_link) and the health (JSON). A client that falls\n"
      "behind loses messages (counted), never slows STAC. Stops on Ctrl-C (docs/view.md).");
  cmd->add_option("--address", o->address,
                  "address to listen on (127.0.0.1; the vehicle network's to watch from elsewhere)")
      ->capture_default_str();
  cmd->add_option("--port", o->port, "WebSocket port (0: any free one, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--domain", o->domain, "DDS domain (default: dds.domain_id)")
      ->check(CLI::Range(0, 230));
  cmd->add_option("--dds-config", o->dds_config, "Cyclone XML (default: dds.config_file)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--seconds", o->seconds, "stop after this many seconds (default: at Ctrl-C)")
      ->check(CLI::Range(0.0, 1e9));
  cmd->add_option("--client-buffer-mb", o->client_buffer_mb,
                  "unsent data a client may have before its messages are dropped (MB)")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1024.0));
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->callback([o] {
    if (const int code = run_view(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools
