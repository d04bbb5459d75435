// The sensor of a capture: its model from its packets, its calibration from a file or from the
// status bytes it sent (`stac status`, `--calib stream`, `--sensor auto`).
#include "formats/capture_sensor.hpp"

#include <cstdio>
#include <string>

#include "drivers/velodyne/packet.hpp"
#include "formats/capture_input.hpp"

namespace stac::formats {

rt::Result<CaptureStatus> read_capture_status(const std::filesystem::path& capture,
                                              std::uint16_t port, velodyne::Model model,
                                              bool until_calibration) {
  if (velodyne::traits(model).trailer != velodyne::TrailerKind::kGpsStatus) {
    return rt::make_error(std::string("the ") + std::string(velodyne::traits(model).name) +
                          " sends no status cycle (only the HDL-64E S2.1 and S3 do): give its "
                          "calibration file (--calib or velodyne.calibration)");
  }
  auto reader =
      io::PcapReader::open(capture, io::PcapFilter{.udp_dst_port = port, .udp_src_port = {}});
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  CaptureStatus out{velodyne::StatusDecoder(model), 0, {}};
  io::Datagram d;
  while (reader->next(d)) {
    const velodyne::RawPacket* packet = velodyne::as_packet(d.payload);
    if (packet == nullptr) continue;
    ++out.packets;
    out.status.add(packet->trailer[4], packet->trailer[5]);
    if (until_calibration && out.status.has_calibration()) break;
  }
  if (!reader->error().empty()) return rt::make_error(capture_breaks_off(reader->error()));
  out.pcap = reader->counters();
  return out;
}

rt::Result<velodyne::Calibration> stream_calibration(const std::filesystem::path& capture,
                                                     std::uint16_t port, velodyne::Model model) {
  auto status = read_capture_status(capture, port, model, true);
  if (!status) return rt::Unexpected<rt::Error>{status.error()};
  auto calibration = status->status.calibration();
  if (!calibration) {
    return rt::make_error(capture.string() + ": " + calibration.error().message +
                          "; pass --calib with the unit's db.xml or ROS yaml instead");
  }
  return calibration;
}

rt::Result<velodyne::Calibration> capture_calibration(const std::filesystem::path& calibration_file,
                                                      const std::filesystem::path& capture,
                                                      std::uint16_t port, velodyne::Model model) {
  auto c = calibration_file.empty() ? stream_calibration(capture, port, model)
                                    : velodyne::load_calibration(calibration_file);
  if (!c) return c;
  if (auto fits = velodyne::check_calibration_for(*c, model); !fits)
    return rt::Unexpected<rt::Error>{fits.error()};
  return velodyne::lasers_of(*c, model);
}

rt::Result<velodyne::PacketIdentity> capture_identity(const std::filesystem::path& capture,
                                                      std::uint16_t port) {
  auto reader =
      io::PcapReader::open(capture, io::PcapFilter{.udp_dst_port = port, .udp_src_port = {}});
  if (!reader) return rt::Unexpected<rt::Error>{reader.error()};
  io::Datagram d;
  for (int n = 0; n < 200 && reader->next(d); ++n) {
    const velodyne::PacketIdentity id = velodyne::identify_packet(d.payload);
    if (id.kind != velodyne::PacketIdentity::Kind::kUnknown) return id;
  }
  return velodyne::PacketIdentity{};
}

rt::Status apply_sensor_option(settings::VelodyneSettings& s, const std::string& option,
                               bool calibration_given) {
  if (option.empty()) return {};
  if (option == "auto") {
    s.model_auto = true;
    return {};
  }
  const auto m = velodyne::parse_model(option);
  if (!m) {
    return rt::make_error("'" + option + "' is not a sensor model: use " +
                          std::string(velodyne::model_names()) + ", or auto");
  }
  return settings::use_velodyne_model(s, *m, calibration_given);
}

namespace {

std::string describe(const velodyne::PacketIdentity& id) {
  if (id.kind == velodyne::PacketIdentity::Kind::kHdl64) return "an HDL-64E (lower-bank blocks)";
  char product[8];
  std::snprintf(product, sizeof product, "0x%02X", id.product_id);
  if (id.model) {
    return "a " + std::string(velodyne::traits(*id.model).name) + " (product byte " + product + ")";
  }
  return std::string("an unknown model (product byte ") + product + ")";
}

}  // namespace

rt::Result<velodyne::Calibration> capture_sensor(settings::VelodyneSettings& s,
                                                 const std::filesystem::path& capture,
                                                 bool calibration_given) {
  auto id = capture_identity(capture, s.port);
  if (!id) return rt::Unexpected<rt::Error>{id.error()};
  const velodyne::Model configured = s.assembler.decoder.model;
  if (s.model_auto) {
    velodyne::Model model = velodyne::Model::kS2_1;
    if (id->model) {
      model = *id->model;
    } else if (id->kind == velodyne::PacketIdentity::Kind::kFactory) {
      return rt::make_error(capture.string() + ": its packets name " + describe(*id) +
                            ", which STAC does not know; set velodyne.model (or --model)");
    } else if (id->kind == velodyne::PacketIdentity::Kind::kUnknown) {
      // No lower-bank block and no factory bytes (an HDL-32E before firmware 2.2.20?): not an
      // HDL-64E's packets, and nothing says whose.
      return rt::make_error(capture.string() +
                            ": its first packets do not say which model sent them; set "
                            "velodyne.model (or --model, --sensor)");
    }
    if (auto u = settings::use_velodyne_model(s, model, calibration_given); !u)
      return rt::Unexpected<rt::Error>{u.error()};
    // The capture's word is taken: packets naming another model are another sensor's.
    s.assembler.drop_other_models = true;
    std::fprintf(stderr, "stac: %s: velodyne.model auto: %s%s\n", capture.string().c_str(),
                 id->kind == velodyne::PacketIdentity::Kind::kHdl64
                     ? "HDL-64E packets (they do not say S2, S2.1 or S3): decoded as an S2.1"
                     : ("packets of " + describe(*id)).c_str(),
                 "");
  } else if (id->kind != velodyne::PacketIdentity::Kind::kUnknown &&
             !velodyne::identity_matches(*id, configured)) {
    std::fprintf(stderr,
                 "stac: warning: %s: its packets name %s, but the model is %s: decoded as the %s "
                 "as configured (velodyne.model: auto, or --model, follows the packets)\n",
                 capture.string().c_str(), describe(*id).c_str(),
                 std::string(velodyne::traits(configured).name).c_str(),
                 std::string(velodyne::traits(configured).name).c_str());
  }
  return capture_calibration(s.calibration, capture, s.port, s.assembler.decoder.model);
}

}  // namespace stac::formats
