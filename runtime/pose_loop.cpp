// The pose thread: the Applanix INS (TCP client or UDP) and the vehicle's odometry (SocketCAN or
// cannelloni read here between INS reads, or the can thread's ring for gs_usb) into the ego
// estimator and the pose history perception reads. Also the CAN input's opening.
#include <chrono>
#include <thread>
#include <vector>

#include "drivers/can/dbc.hpp"
#include "rt/clock.hpp"
#include "runtime/live.hpp"

namespace stac::runtime {

can::CanInputCounters PoseInputs::can_counters() const {
  if (socketcan) return socketcan->counters();
  if (cannelloni) return cannelloni->counters();
  return gs_usb ? gs_usb->counters() : can::CanInputCounters{};
}

void PoseInputs::stop() {
  if (tcp) tcp->stop();
  if (udp) udp->stop();
  if (socketcan) socketcan->stop();
  if (cannelloni) cannelloni->stop();
  if (gs_usb) gs_usb->stop();
}

void pose_loop(Component::Live& live) noexcept {
  PoseInputs& in = live.inputs;
  ego::EgoEstimator& estimator = *live.estimator;
  applanix::StreamParser parser;
  std::vector<std::uint8_t> bytes(16384);
  std::uint64_t session = 0;
  bool can_closed = false;
  applanix::Parsed m;
  const int timeout_ms = in.can() ? 5 : 50;  // the INS and CAN handled in turn when CAN is read
  // CAN frames carry the host's receive time, poses the INS's (UTC). On a vehicle whose host
  // follows UTC the two agree; in a replay of an earlier drive, or with a host clock that is off,
  // they do not, and dead-reckoned poses stamped in the host's time would sit months away from
  // the INS's (the history would then refuse every later fix). So odometry is moved onto the pose
  // clock by the offset the newest fix shows on arrival (its stamp minus its receive time: the
  // clocks' difference less the INS's few milliseconds of latency); 0 until the first fix.
  std::int64_t receive_to_pose_ns = 0;
  const auto add_odometry = [&](const can::OdometryUpdate& u) {
    can::OdometryUpdate on_pose_clock = u;
    on_pose_clock.stamp_ns += receive_to_pose_ns;
    estimator.add_odometry(on_pose_clock);
  };
  const auto take = [&](const applanix::StreamParser& p) {
    const std::uint64_t fixes = estimator.counters().ins_fixes;
    estimator.add_ins(m, p);
    // Only a fix that became a pose shows the INS alive (not a rejected or unusable one).
    if (estimator.counters().ins_fixes != fixes) {
      live.watchdog.beat(kIns, rt::monotonic_ns());
      receive_to_pose_ns = estimator.last_fix_ns() - rt::realtime_ns();
    }
  };
  const auto publish_counters = [&](const applanix::ParserCounters& pc) {
    live.counts.set(Count::kInsBadChecksum, pc.bad_checksum);
    live.counts.set(Count::kInsBadFraming,
                    pc.bad_length + pc.bad_terminator + pc.oversize + pc.truncated);
    live.counts.set(Count::kInsMalformed, pc.malformed);
    live.counts.set(Count::kInsGarbageBytes, pc.garbage_bytes);
    if (in.tcp) {
      const applanix::TcpClientCounters& tc = in.tcp->counters();
      live.counts.set(Count::kInsConnectFailures, tc.connect_failures);
      live.counts.set(Count::kInsDisconnects, tc.disconnects + tc.stalls + tc.no_message);
    }
  };
  for (;;) {
    bool stopped = false;
    if (in.tcp) {
      const int n = in.tcp->receive(bytes, timeout_ms);
      if (n == applanix::TcpClient::kStopped) stopped = true;
      if (in.tcp->session() != session) {
        session = in.tcp->session();
        parser.end_of_stream();
      }
      if (n > 0) {
        parser.feed({bytes.data(), static_cast<std::size_t>(n)});
        while (parser.next(m)) {
          in.tcp->note_message();  // the stream holds the INS's messages
          take(parser);
        }
      }
      publish_counters(parser.counters());
    } else if (in.udp) {
      const int n = in.udp->receive(timeout_ms);
      if (n == io::UdpReceiver::kStopped) stopped = true;
      while (n > 0 && in.udp->next(m)) take(in.udp->parser());
      publish_counters(in.udp->parser().counters());
    }
    if ((in.socketcan || in.cannelloni) && !can_closed) {
      const int wait_ms = in.ins() ? 0 : timeout_ms;
      const can::InputEvent e =
          in.socketcan ? read_can(*in.socketcan, wait_ms, add_odometry, *live.can_report)
                       : read_can(*in.cannelloni, wait_ms, add_odometry, *live.can_report);
      if (e == can::InputEvent::kStopped) stopped = true;
      if (e == can::InputEvent::kGone) {  // marked lost; the INS goes on
        can_closed = true;
        if (!in.ins()) return;
      }
    }
    if (in.odometry) {  // gs_usb: what the can thread read
      const bool can_done = in.can_done.load(std::memory_order_acquire);
      for (can::OdometryUpdate u; in.odometry->try_pop(u);) add_odometry(u);
      if (!in.ins()) {  // nothing else to wait on
        if (can_done) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(timeout_ms));
      }
    }
    live.ego_source.store(estimator.source(live.history->newest_stamp_ns()),
                          std::memory_order_relaxed);
    if (stopped) return;
  }
}

std::string can_description(const can::CanConfig& c) {
  if (c.transport == can::Transport::kSocketCan) return c.socketcan.interface;
  if (c.transport == can::Transport::kCannelloni) {
    return "cannelloni on udp://" + c.cannelloni.bind_address + ":" +
           std::to_string(c.cannelloni.port);
  }
  return "gs_usb channel " + std::to_string(c.gs_usb.channel) + " at " +
         std::to_string(c.gs_usb.bitrate_bps) + " bit/s" +
         (c.gs_usb.listen_only ? " (listen-only)" : "");
}

// The DBC signal map's decoder over the configured transport. SocketCAN gets the mapped ids as
// its kernel filter; a gs_usb adapter and a cannelloni gateway deliver the whole bus and the
// decoder drops the rest.
rt::Status open_can(can::CanConfig& c, PoseInputs& inputs) {
  auto db = can::load_dbc(c.dbc);
  if (!db) return rt::Unexpected<rt::Error>{db.error()};
  auto decoder = can::OdometryDecoder::create(*db, c.signals);
  if (!decoder) return rt::Unexpected<rt::Error>{decoder.error()};
  if (c.transport == can::Transport::kSocketCan) {
    c.socketcan.filters = decoder->filters();
    auto reader = can::SocketCanReader::open(c.socketcan);
    if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    inputs.socketcan.emplace(std::move(*reader), std::move(*decoder));
  } else if (c.transport == can::Transport::kCannelloni) {
    auto reader = can::CannelloniReader::open(c.cannelloni);
    if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
    c.cannelloni.port = reader->port();  // port 0: the one bound
    inputs.cannelloni.emplace(std::move(*reader), std::move(*decoder));
  } else {
    auto device = can::GsUsbDevice::open(c.gs_usb);
    if (!device) return rt::Unexpected<rt::Error>{device.error()};
    inputs.gs_usb.emplace(std::move(*device), std::move(*decoder));
    inputs.odometry.emplace(kOdometryRing);
  }
  return {};
}

}  // namespace stac::runtime
