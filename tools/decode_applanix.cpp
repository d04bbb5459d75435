// stac decode applanix: an Applanix POS LV capture (pcap, or a raw Real-Time Data stream) ->
// one csv row per Group 1 navigation solution, and a summary of what the stream held.
#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/applanix/capture_reader.hpp"
#include "formats/capture_input.hpp"
#include "tools/commands.hpp"

namespace stac::tools {

using namespace stac::formats;
namespace {

struct ApplanixDecodeOptions {
  std::string in;
  std::string out;
  int port = 0;  // 0: the POS ports 5600-5603
};

constexpr const char* kHeader =
    "time1,time_types,lat,lon,alt,vn,ve,vd,roll,pitch,heading,wander,track,speed,"
    "rate_lon,rate_tra,rate_down,acc_lon,acc_tra,acc_down,alignment\n";

struct FileCloser {
  void operator()(std::FILE* f) const noexcept { std::fclose(f); }
};

void write_row(std::FILE* f, const applanix::TimeDistance& t, const applanix::Group1& g) {
  // Doubles with 17 significant digits (exact round trip), floats with 9.
  std::fprintf(f,
               "%.17g,%u,%.17g,%.17g,%.17g,%.9g,%.9g,%.9g,%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,"
               "%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%u\n",
               t.time1_s, unsigned{t.time_types}, g.latitude_deg, g.longitude_deg, g.altitude_m,
               double{g.north_velocity_mps}, double{g.east_velocity_mps},
               double{g.down_velocity_mps}, g.roll_deg, g.pitch_deg, g.heading_deg, g.wander_deg,
               double{g.track_deg}, double{g.speed_mps}, double{g.rate_longitudinal_dps},
               double{g.rate_transverse_dps}, double{g.rate_down_dps},
               double{g.accel_longitudinal_mps2}, double{g.accel_transverse_mps2},
               double{g.accel_down_mps2}, unsigned{g.alignment_status});
}

unsigned long long ull(std::uint64_t v) {
  return static_cast<unsigned long long>(v);
}

int run_decode_applanix(const ApplanixDecodeOptions& o) {
  if (o.port < 0 || o.port > 65535) return fail("--port must be 1..65535");
  std::optional<std::uint16_t> port;
  if (o.port > 0) port = static_cast<std::uint16_t>(o.port);
  auto reader = applanix::CaptureReader::open(o.in, port);
  if (!reader) return fail(reader.error().message);
  std::unique_ptr<std::FILE, FileCloser> out(std::fopen(o.out.c_str(), "w"));
  if (!out) return fail(o.out + ": cannot create the csv file");
  std::fputs(kHeader, out.get());

  applanix::Parsed p;
  std::uint64_t rows = 0, implausible = 0;
  std::optional<std::uint32_t> week;
  while (reader->next(p)) {
    if (const auto* g = std::get_if<applanix::Group1>(&p.content)) {
      if (!applanix::plausible(*g) || !std::isfinite(p.time.time1_s)) {
        ++implausible;  // NaN, infinite or impossible values: never a row
        continue;
      }
      write_row(out.get(), p.time, *g);
      ++rows;
    }
  }
  week = reader->parser().gps_week();
  const bool write_failed = std::ferror(out.get()) != 0;
  if (std::fclose(out.release()) != 0 || write_failed)
    return fail(o.out + ": write failed (disk full?)");
  const std::string capture_error = reader->error();

  const auto& pc = reader->parser().counters();
  const auto& cc = reader->counters();
  const auto& tc = reader->tcp_counters();
  std::fprintf(stderr, "stac decode applanix: %s -> %s\n", o.in.c_str(), o.out.c_str());
  if (reader->is_pcap()) {
    std::fprintf(stderr,
                 "  capture   %llu frames, %llu UDP datagrams and %llu TCP segments on %s\n"
                 "  tcp       %llu streams, %llu bytes, %llu retransmitted, %llu out of order, "
                 "%llu gaps (%llu bytes)\n",
                 ull(reader->pcap_counters().frames), ull(cc.datagrams), ull(cc.segments),
                 port ? ("port " + std::to_string(*port)).c_str() : "ports 5600-5603",
                 ull(tc.streams), ull(tc.bytes), ull(tc.retransmitted), ull(tc.out_of_order),
                 ull(tc.gaps), ull(tc.gap_bytes));
  } else {
    std::fprintf(stderr, "  raw stream %llu bytes\n", ull(cc.raw_bytes));
  }
  std::string ids;
  auto counts = std::vector<applanix::StreamParser::IdCount>(
      reader->parser().group_counts().begin(), reader->parser().group_counts().end());
  std::sort(counts.begin(), counts.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  for (const auto& c : counts) {
    ids += " " + std::to_string(c.id) + ":" + std::to_string(c.count);
  }
  std::fprintf(stderr,
               "  groups    %llu (id:count%s)\n"
               "  $MSG      %llu control messages\n"
               "  rows      %llu Group 1 solutions (%llu with impossible values left out); GPS "
               "week %s\n"
               "  rejected  bad checksum %llu, bad length %llu, no terminator %llu, oversize %llu,"
               " malformed %llu, truncated %llu, garbage bytes %llu\n",
               ull(pc.groups), ids.c_str(), ull(pc.control_messages), ull(rows), ull(implausible),
               week ? std::to_string(*week).c_str() : "unknown (no Group 3)", ull(pc.bad_checksum),
               ull(pc.bad_length), ull(pc.bad_terminator), ull(pc.oversize), ull(pc.malformed),
               ull(pc.truncated), ull(pc.garbage_bytes));
  if (!capture_error.empty()) return fail(capture_breaks_off(capture_error));
  if (rows == 0) {
    return fail(o.in + ": no Group 1 navigation solution found" +
                (reader->is_pcap() ? " (wrong --port?)" : ""));
  }
  return 0;
}

}  // namespace

CLI::App* add_decode_applanix_command(CLI::App& decode) {
  auto o = std::make_shared<ApplanixDecodeOptions>();
  CLI::App* cmd = decode.add_subcommand(
      "applanix", "Decode an Applanix POS LV capture into one csv row per Group 1 solution");
  cmd->description(
      "Decode an Applanix POS LV capture (pcap with UDP or TCP, or a raw stream file) into one "
      "csv\n"
      "row per Group 1: time1 (s; of the week for GPS/UTC time types), time_types (raw byte),\n"
      "lat, lon (deg), alt (m), vn, ve, vd (m/s), roll, pitch, heading, wander, track (deg),\n"
      "speed (m/s), rate_lon, rate_tra, rate_down (deg/s), acc_lon, acc_tra, acc_down (m/s^2),\n"
      "alignment (0 full navigation ... 8 no solution). A summary goes to stderr.");
  cmd->add_option("--in", o->in, "pcap/pcapng capture or raw $GRP stream file")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", o->out, "csv file to write")->required();
  cmd->add_option("--port", o->port,
                  "UDP destination / TCP source port of the POS data (default: 5600-5603)");
  cmd->callback([o] {
    if (const int code = run_decode_applanix(*o); code != 0) throw CLI::RuntimeError(code);
  });
  return cmd;
}

}  // namespace stac::tools
