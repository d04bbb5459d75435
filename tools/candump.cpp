// stac candump: a candump log of the vehicle bus -> speed, yaw rate and the dead-reckoned path
// (csv).
#include "drivers/can/candump.hpp"

#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>

#include "drivers/can/config.hpp"
#include "drivers/can/dbc.hpp"
#include "drivers/can/odometry.hpp"
#include "settings/settings.hpp"
#include "tools/commands.hpp"

namespace stac::tools {

using namespace stac::settings;
namespace {

struct CandumpOptions {
  std::string in;
  std::string out;
  std::string dbc;     // empty: the config's can.dbc
  std::string config;  // empty: $STAC_CONFIG or config/stac.yaml
};

int run_candump(const CandumpOptions& o) {
  const auto config = load_can_settings(config_path(o.config));
  if (!config) return fail(config.error().message);
  const std::filesystem::path dbc_file = o.dbc.empty() ? config->dbc : std::filesystem::path(o.dbc);
  const auto db = can::load_dbc(dbc_file);
  if (!db) return fail(db.error().message);
  auto decoder = can::OdometryDecoder::create(*db, config->signals);
  if (!decoder) return fail(decoder.error().message + " (see can: in the configuration)");
  auto reader = can::CandumpReader::open(o.in);
  if (!reader) return fail(reader.error().message);
  std::ofstream out(o.out, std::ios::trunc);
  if (!out) return fail(o.out + ": cannot create the csv file");
  out << "time,speed_mps,yaw_rate_dps,x_m,y_m,yaw_deg,status\n";

  can::DeadReckoning dr(config->dead_reckoning);
  bool have_speed = false, have_yaw = false;
  double speed = 0, yaw_rate = 0;
  std::uint64_t rows = 0;
  can::Frame f;
  char line[256];
  while (true) {
    auto more = reader->next(f);
    if (!more) return fail(more.error().message);
    if (!*more) break;
    const can::OdometryUpdate u = decoder->decode(f);
    if (!u.has_speed && !u.has_yaw_rate) continue;
    const std::uint64_t earlier_before = dr.out_of_order();
    dr.update(u);
    // A frame earlier than the one before (the log's time ran back: logs joined, a clock set
    // back) is not integrated; a row for it would show a pose and "ok" for a time already past.
    if (dr.out_of_order() != earlier_before) continue;
    if (u.has_speed) {
      speed = u.speed_mps;
      have_speed = true;
    }
    if (u.has_yaw_rate) {
      yaw_rate = u.yaw_rate_dps;
      have_yaw = true;
    }
    if (!have_speed || !have_yaw) continue;
    const can::Pose2& p = dr.pose();
    const int n = std::snprintf(
        line, sizeof(line), "%" PRId64 ".%06" PRId64 ",%.4f,%.4f,%.4f,%.4f,%.4f,%s\n",
        u.stamp_ns / 1'000'000'000, (u.stamp_ns % 1'000'000'000) / 1000, speed, yaw_rate, p.x_m,
        p.y_m, p.yaw_rad * 180.0 / std::numbers::pi, can::to_string(dr.status(u.stamp_ns)));
    out.write(line, n);
    ++rows;
  }
  out.close();
  if (!out) return fail(o.out + ": write failed");
  const auto& rc = reader->counters();
  const auto& dc = decoder->counters();
  std::printf("candump: %" PRIu64 " frames (%" PRIu64 " CAN FD skipped), %" PRIu64
              " with speed or yaw rate, %" PRIu64 " rows -> %s\n",
              rc.frames, rc.can_fd, dc.decoded, rows, o.out.c_str());
  if (dc.short_frames > 0)
    std::printf("candump: %" PRIu64 " frames too short for their signal, dropped\n",
                dc.short_frames);
  if (dc.implausible > 0)
    std::printf("candump: %" PRIu64
                " frames with a speed or yaw rate no vehicle has (over 200 m/s, 720 deg/s, or "
                "not a number), dropped\n",
                dc.implausible);
  if (dr.gaps() > 0)
    std::printf("candump: %" PRIu64 " intervals not integrated (input stale)\n", dr.gaps());
  if (dr.out_of_order() > 0)
    std::printf("candump: warning: %" PRIu64
                " frames earlier than a frame before them (the log's time ran back: logs joined, "
                "or the clock set back), not integrated and not written\n",
                dr.out_of_order());
  if (rc.frames == 0)
    return fail(o.in + ": no CAN frame in the log (candump -l format: '(time) can0 123#DEADBEEF')");
  return 0;
}

}  // namespace

void add_candump_command(CLI::App& app) {
  auto o = std::make_shared<CandumpOptions>();
  CLI::App* cmd = app.add_subcommand(
      "candump",
      "Decode a candump log of the vehicle CAN bus into speed, yaw rate and a dead-reckoned path");
  cmd->description(
      "Decode a candump log (`candump -l` format) of the vehicle CAN bus through the DBC signal "
      "map\n"
      "of the can: configuration. csv: one row per frame carrying speed or yaw rate (once both\n"
      "are known) with columns time (s, from the log),speed_mps,yaw_rate_dps (positive = left\n"
      "turn),x_m,y_m,yaw_deg (dead reckoning from the first frame: x forward, y left),status\n"
      "(ok, stale or no_input).");
  cmd->add_option("--in", o->in, "candump log to read")->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "csv file to write")->required();
  cmd->add_option("--dbc", o->dbc, "DBC file (default: the config's can.dbc)");
  cmd->add_option("--config", o->config, stac::settings::kConfigOptionHelp);
  cmd->callback([o] {
    if (const int code = run_candump(*o); code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace stac::tools
