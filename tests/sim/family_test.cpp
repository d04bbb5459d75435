// The Velodyne family beside the HDL-64E (docs/velodyne.md): the HDL-32E, VLP-16, Puck Hi-Res and
// VLP-32C. Each model's simulated packets decode back to every beam the simulator cast; the
// decoder's timing and azimuths equal the manuals' tables and ros-drivers' formulas, written
// out here independently of drivers/velodyne/model.hpp; dual return, model identity, and the
// calibrations' fit to a model.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <tuple>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/decoder.hpp"
#include "drivers/velodyne/packet_builder.hpp"
#include "drivers/velodyne/scan_assembler.hpp"
#include "shared_data.hpp"
#include "sim/run.hpp"
#include "test_paths.hpp"

namespace stac::sim {
namespace {

using stac::testing::shared_data;
using velodyne::Model;

constexpr const char* kHdl32 = "velodyne/calib/veloview_HDL-32.xml";
constexpr const char* kVlp16 = "velodyne/calib/veloview_VLP-16.xml";
constexpr const char* kSztaki = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";

std::filesystem::path repo_file(const std::string& relative) {
  return std::filesystem::path(::stac::testing::source_dir()) / relative;
}

struct Family {
  std::filesystem::path calibration;
  const char* shared;  // the calibration's path in ../shared/data, or nullptr
};

Family family(Model m) {
  switch (m) {
    case Model::kHdl32e:
      return {shared_data(kHdl32), kHdl32};
    case Model::kVlp16:
      return {shared_data(kVlp16), kVlp16};
    case Model::kPuckHiRes:
      return {repo_file("config/calib/puck_hi_res.yaml"), nullptr};
    default:
      return {repo_file("config/calib/vlp32c.yaml"), nullptr};
  }
}

velodyne::Calibration load_for(Model m) {
  const Family f = family(m);
  auto c = velodyne::load_calibration(f.calibration);
  EXPECT_TRUE(c) << c.error().message;
  EXPECT_TRUE(velodyne::check_calibration_for(*c, m));
  return velodyne::lasers_of(*c, m);
}

// Manual firing time (us) of channel j of block b, single return: HDL-32E manual (1.152 us a
// laser, 46.08 us a sequence), VLP-16 manual Table 9-4 (2.304 us, 55.296 us, two sequences a
// block), VLP-32C manual Table 9-5 (pairs 2.304 us apart, 55.296 us a sequence).
double manual_time_us(Model m, int b, int j, bool dual) {
  const int sequence = dual ? b / 2 : b;
  switch (m) {
    case Model::kHdl32e:
      return 46.08 * sequence + 1.152 * j;
    case Model::kVlp32c:
      return 55.296 * sequence + 2.304 * (j / 2);
    default:
      return 110.592 * sequence + 55.296 * (j / 16) + 2.304 * (j % 16);
  }
}

// ros-drivers unpack_vlp16: a return's azimuth is the block's plus the step to the next firing
// times its firing time over the 110.592 us block; the generic unpack (HDL-32E, VLP-32C) keeps
// the block's rotation for every channel.
int manual_azimuth(Model m, int rotation, int step, int j) {
  if (m == Model::kHdl32e || m == Model::kVlp32c) return rotation;
  const double f = rotation + step * (2.304 * (j % 16) + 55.296 * (j / 16)) / 110.592;
  return static_cast<int>(std::lround(f)) % 36000;
}

// A short simulated urban drive of model `m` (`seconds` long, `seed`), its calibration `cal`.
std::unique_ptr<SimRun> family_run(Model m, const velodyne::Calibration& cal, std::uint64_t seed,
                                   double seconds, bool dual = false, bool exact = false) {
  RunConfig rc;
  rc.scenario = "urban";
  rc.seed = seed;
  rc.duration_s = seconds;
  rc.lidar.model = m;
  rc.lidar.dual_return = dual;
  if (exact) {  // every beam's hit exactly: no range noise, no random dropout
    rc.lidar.range_noise_m = 0.0;
    rc.lidar.dropout = 0.0;
  }
  auto run = SimRun::create(cal, rc);
  EXPECT_TRUE(run) << run.error().message;
  return run ? std::move(*run) : nullptr;
}

class FamilyModel : public ::testing::TestWithParam<Model> {};

TEST_P(FamilyModel, FiringTimesAreTheManualsTables) {
  const Model m = GetParam();
  velodyne::Calibration cal;
  cal.num_lasers = velodyne::traits(m).lasers;
  velodyne::PacketDecoder d(cal, velodyne::DecoderConfig{.model = m});
  for (bool dual : {false, true}) {
    for (int b = 0; b < 12; ++b) {
      for (int j = 0; j < 32; ++j) {
        EXPECT_NEAR(d.firing_offset_ns(b, j, dual), manual_time_us(m, b, j, dual) * 1000.0, 0.5)
            << velodyne::traits(m).name << " block " << b << " channel " << j;
      }
    }
  }
  // Packets a second: 12 blocks' worth of sequences, whatever the rotation rate.
  const double packet_us = manual_time_us(m, 1, 0, false) * 12;
  EXPECT_NEAR(velodyne::traits(m).packets_per_second_single, 1e6 / packet_us, 0.01);
  EXPECT_NEAR(velodyne::traits(m).packets_per_second_dual, 2e6 / packet_us, 0.01);
}

// Closing the loop per model: decoding the simulated packets (with the azimuth step between
// blocks that the scan assembler takes from the packet) gives back every beam the simulator
// cast, within the range quantisation; each azimuth is the manual's.
TEST_P(FamilyModel, DecoderReturnsEverySimulatedHit) {
  const Model m = GetParam();
  if (family(m).shared != nullptr) STAC_REQUIRE_SHARED_DATA(family(m).shared);
  const velodyne::Calibration cal = load_for(m);
  const auto run = family_run(m, cal, 11, 0.25, false, true);
  ASSERT_TRUE(run);
  velodyne::DecoderConfig dc{.model = m, .min_range_m = 0.0f, .max_range_m = 250.0f};
  velodyne::PacketDecoder decoder(cal, dc);
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t compared = 0, interpolated = 0;
  double worst = 0.0;
  for (std::uint32_t k = 0; k < run->packet_count(); ++k) {
    std::map<std::tuple<int, int, int>, BeamRecord> beams;  // block, laser, azimuth
    std::int64_t first = 0;
    run->packet(k, bytes, first, {}, [&](const BeamRecord& b) {
      if (b.returned) beams[{b.block, b.laser, b.rotation}] = b;
    });
    const velodyne::RawPacket* p = velodyne::as_packet(bytes);
    ASSERT_NE(p, nullptr);
    ASSERT_FALSE(decoder.dual_return(*p));  // (the trailer is stac sim's: tested there)
    std::size_t decoded = 0;
    for (int block = 0; block < 12; ++block) {
      ASSERT_EQ(p->blocks[block].bank, velodyne::kUpperBank);
      const int r = p->blocks[block].rotation;
      const int next = block < 11 ? p->blocks[block + 1].rotation : r;
      int step = block < 11 ? (next - r + 36000) % 36000
                            : (r - p->blocks[block - 1].rotation + 36000) % 36000;
      if (step > 18000) step -= 36000;
      velodyne::Point out[32];
      const int n = decoder.decode_block(p->blocks[block], block, false, 0, out, step);
      for (int i = 0; i < n; ++i) {
        const auto it = beams.find({block, out[i].laser, out[i].azimuth});
        ASSERT_NE(it, beams.end())
            << "a decoded point the simulator did not cast: block " << block << " laser "
            << int{out[i].laser} << " azimuth " << out[i].azimuth;
        const BeamRecord& beam = it->second;
        EXPECT_EQ(out[i].azimuth, manual_azimuth(m, r, step, beam.channel));
        interpolated += out[i].azimuth != r ? 1 : 0;
        const double* s = beam.sensor_xyz;
        worst = std::max(worst, std::hypot(out[i].x - s[0], out[i].y - s[1], out[i].z - s[2]));
        ++compared;
        ++decoded;
      }
    }
    ASSERT_EQ(decoded, beams.size()) << "packet " << k;
  }
  EXPECT_GT(compared, 20'000u);
  // Half a range unit (1 mm; the VLP-32C's 4 mm units: 2 mm) plus float rounding.
  EXPECT_LT(worst, velodyne::traits(m).distance_resolution_m / 2 + 0.001);
  if (velodyne::traits(m).layout == velodyne::Layout::kTwoSequences) {
    EXPECT_GT(interpolated, compared / 2);
  } else {
    EXPECT_EQ(interpolated, 0u);
  }
}

// Dual return: pairs of blocks share a rotation, the even block holding the last return and
// the odd one the strongest (VLP-16 and VLP-32C manuals, "Dual Return Mode"); the return-mode
// byte says 0x39. The scan assembler frames both into one scan, the points typed.
TEST_P(FamilyModel, DualReturnPairsLastThenStrongest) {
  const Model m = GetParam();
  if (family(m).shared != nullptr) STAC_REQUIRE_SHARED_DATA(family(m).shared);
  const velodyne::Calibration cal = load_for(m);
  const auto run = family_run(m, cal, 4, 0.35, true);
  ASSERT_TRUE(run);
  velodyne::ScanAssemblerConfig ac;
  ac.decoder.model = m;
  velodyne::ScanAssembler assembler(cal, ac);
  velodyne::Scan scan(velodyne::scan_capacity(ac));
  assembler.begin(scan);
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t last = 0, strongest = 0, differ = 0, scans = 0;
  const double period = 1.0 / velodyne::traits(m).packets_per_second_dual;
  for (std::uint32_t k = 0; k < run->packet_count(); ++k) {
    std::int64_t first = 0;
    run->packet(k, bytes, first, {});
    bytes[1204] = velodyne::kReturnDual;  // the trailer is the caller's (stac sim writes it)
    bytes[1205] = velodyne::traits(m).product_id;
    const velodyne::RawPacket* p = velodyne::as_packet(bytes);
    for (int b = 0; b < 12; b += 2) {
      ASSERT_EQ(p->blocks[b].rotation, p->blocks[b + 1].rotation);
      for (int j = 0; j < 32; ++j) {
        // Where they differ the last return is the farther echo (the strongest block then holds
        // the stronger one, or the second strongest when the strongest is the last).
        // (Copies: gtest binds references, and the packet's fields are packed, unaligned.)
        const unsigned last_raw = p->blocks[b].returns[j].distance;
        const unsigned strongest_raw = p->blocks[b + 1].returns[j].distance;
        if (last_raw != strongest_raw) {
          ++differ;
          EXPECT_GT(last_raw, strongest_raw);
        }
      }
    }
    if (assembler.add_packet(bytes, std::llround(k * period * 1e9))) {
      ++scans;
      EXPECT_TRUE(scan.header.dual_return);
      for (const velodyne::Point& pt : scan.points) {
        (pt.return_type == static_cast<std::uint8_t>(velodyne::ReturnType::kLast) ? last
                                                                                  : strongest)++;
      }
      assembler.begin(scan);
    }
  }
  EXPECT_GE(scans, 2u);
  EXPECT_GT(strongest, 10'000u);
  EXPECT_EQ(last, strongest);  // every return has its last-return twin (one echo: the same)
  EXPECT_GT(differ, 0u);
  EXPECT_EQ(assembler.counters().model_mismatch, 0u);
  EXPECT_EQ(assembler.counters().invalid_block, 0u);
}

// An assembler of model `m` that keeps every return (no range cut).
velodyne::ScanAssemblerConfig every_return(Model m) {
  velodyne::ScanAssemblerConfig ac;
  ac.decoder.model = m;
  ac.decoder.min_range_m = 0.0f;
  ac.decoder.max_range_m = 250.0f;
  return ac;
}

// The scan assembler frames a model's packets into whole turns with every point, and counts
// packets whose bytes name another model (decoded as configured: the configuration forces it).
TEST_P(FamilyModel, AssemblerFramesTurnsAndCountsAnotherModelsPackets) {
  const Model m = GetParam();
  if (family(m).shared != nullptr) STAC_REQUIRE_SHARED_DATA(family(m).shared);
  const velodyne::Calibration cal = load_for(m);
  const auto run = family_run(m, cal, 3, 0.45);
  ASSERT_TRUE(run);
  const velodyne::ScanAssemblerConfig ac = every_return(m);
  velodyne::ScanAssembler assembler(cal, ac);
  velodyne::Scan scan(velodyne::scan_capacity(ac));
  assembler.begin(scan);
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t returned = 0, points = 0, complete = 0;
  const double period = 1.0 / velodyne::traits(m).packets_per_second_single;
  for (std::uint32_t k = 0; k < run->packet_count(); ++k) {
    std::int64_t first = 0;
    run->packet(k, bytes, first, {}, [&](const BeamRecord& b) { returned += b.returned; });
    bytes[1204] = velodyne::kReturnStrongest;
    bytes[1205] = k % 10 == 9 ? 0x77 : velodyne::traits(m).product_id;  // 1 in 10: another
    if (assembler.add_packet(bytes, std::llround(k * period * 1e9))) {
      points += scan.points.size();
      complete += scan.header.complete() ? 1 : 0;
      for (const velodyne::Point& pt : scan.points) {
        ASSERT_LT(pt.laser, velodyne::traits(m).lasers);
        ASSERT_LT(pt.ring, velodyne::traits(m).lasers);
      }
      assembler.begin(scan);
    }
  }
  if (assembler.flush()) points += scan.points.size();
  EXPECT_GE(complete, 3u);
  EXPECT_EQ(points, returned);  // nothing lost between the sensor and the scans
  EXPECT_EQ(assembler.counters().model_mismatch, run->packet_count() / 10);
  EXPECT_EQ(assembler.last_identity().product_id, 0x77);
  EXPECT_FALSE(assembler.last_identity().model.has_value());
}

// With the model taken from the capture's packets (drop_other_models, `--model auto` offline), a
// packet naming another model STAC knows is another sensor's: dropped and counted, never decoded
// as this model's lasers; one naming an unknown product is still decoded (the bytes may lie).
TEST_P(FamilyModel, WithTheModelFromThePacketsAnotherKnownModelsPacketsAreDropped) {
  const Model m = GetParam();
  if (family(m).shared != nullptr) STAC_REQUIRE_SHARED_DATA(family(m).shared);
  const velodyne::Calibration cal = load_for(m);
  const auto run = family_run(m, cal, 3, 0.45);
  ASSERT_TRUE(run);
  velodyne::ScanAssemblerConfig ac = every_return(m);
  ac.drop_other_models = true;
  velodyne::ScanAssembler assembler(cal, ac);
  velodyne::Scan scan(velodyne::scan_capacity(ac));
  assembler.begin(scan);
  const Model other = m == Model::kHdl32e ? Model::kVlp32c : Model::kHdl32e;
  std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
  std::size_t kept_returns = 0, points = 0, others = 0, unknown = 0;
  const double period = 1.0 / velodyne::traits(m).packets_per_second_single;
  for (std::uint32_t k = 0; k < run->packet_count(); ++k) {
    std::int64_t first = 0;
    std::size_t returned = 0;
    run->packet(k, bytes, first, {}, [&](const BeamRecord& b) { returned += b.returned; });
    bytes[1204] = velodyne::kReturnStrongest;
    bytes[1205] = velodyne::traits(m).product_id;
    if (k % 10 == 9) {
      bytes[1205] = velodyne::traits(other).product_id;  // 1 in 10: a known other model
      ++others;
    } else {
      if (k % 10 == 4) bytes[1205] = 0x77, ++unknown;  // 1 in 10: a product STAC does not know
      kept_returns += returned;
    }
    if (assembler.add_packet(bytes, std::llround(k * period * 1e9))) {
      points += scan.points.size();
      assembler.begin(scan);
    }
  }
  if (assembler.flush()) points += scan.points.size();
  EXPECT_EQ(points, kept_returns);  // every return of the kept packets, none of the others'
  EXPECT_EQ(assembler.counters().other_model_dropped, others);
  EXPECT_EQ(assembler.counters().model_mismatch, others + unknown);
}

INSTANTIATE_TEST_SUITE_P(Models, FamilyModel,
                         ::testing::Values(Model::kHdl32e, Model::kVlp16, Model::kPuckHiRes,
                                           Model::kVlp32c),
                         [](const ::testing::TestParamInfo<Model>& p) {
                           std::string name(velodyne::traits(p.param).name);
                           std::erase_if(name, [](char c) { return !std::isalnum(c); });
                           return name;
                         });

TEST(VelodyneFamily, PacketIdentityNamesTheModel) {
  velodyne::PacketBuilder b;
  for (int k = 0; k < 12; ++k) b.set_block(k, velodyne::kUpperBank, 100);
  auto bytes = b.mutable_bytes();
  bytes[1204] = velodyne::kReturnLast;
  bytes[1205] = 0x28;
  velodyne::PacketIdentity id = velodyne::identify_packet(b.bytes());
  EXPECT_EQ(id.kind, velodyne::PacketIdentity::Kind::kFactory);
  EXPECT_EQ(id.model, Model::kVlp32c);
  EXPECT_TRUE(velodyne::identity_matches(id, Model::kVlp32c));
  EXPECT_FALSE(velodyne::identity_matches(id, Model::kVlp16));
  EXPECT_FALSE(velodyne::identity_matches(id, Model::kS3));
  bytes[1205] = 0x22;  // the VLP-16's and the Puck LITE's
  id = velodyne::identify_packet(b.bytes());
  EXPECT_TRUE(velodyne::identity_matches(id, Model::kVlp16));
  EXPECT_TRUE(velodyne::identity_matches(id, Model::kPuckLite));
  bytes[1204] = 0x00;  // not a return mode (old HDL-32E firmware): the bytes name nothing
  id = velodyne::identify_packet(b.bytes());
  EXPECT_EQ(id.kind, velodyne::PacketIdentity::Kind::kUnknown);
  EXPECT_TRUE(velodyne::identity_matches(id, Model::kHdl32e));  // nothing to disagree with
  EXPECT_TRUE(velodyne::identity_matches(id, Model::kS2_1));
  bytes[1204] = velodyne::kReturnStrongest;
  bytes[1205] = 0x00;  // a return mode but no product: names no model (not an HDL-64E S2)
  id = velodyne::identify_packet(b.bytes());
  EXPECT_EQ(id.kind, velodyne::PacketIdentity::Kind::kFactory);
  EXPECT_FALSE(id.model.has_value());
  EXPECT_FALSE(velodyne::identity_matches(id, Model::kS2));
  // Dual return: the mode byte, or (a zero mode byte, HDL-32E firmware before 2.2.20) pairs of
  // blocks sharing their azimuths, as VeloView tells it.
  const velodyne::RawPacket* packet = velodyne::as_packet(b.bytes());
  ASSERT_NE(packet, nullptr);
  bytes[1204] = 0x00;
  EXPECT_TRUE(velodyne::is_dual_return(*packet, true, true));  // all 12 blocks at 100
  bytes[1204] = velodyne::kReturnStrongest;
  EXPECT_FALSE(velodyne::is_dual_return(*packet, true, true));
  bytes[1204] = velodyne::kReturnDual;
  EXPECT_TRUE(velodyne::is_dual_return(*packet, true, true));
  b.set_block(1, velodyne::kUpperBank, 101);  // a pair apart: not dual
  EXPECT_FALSE(velodyne::is_dual_return(*packet, true, true));
  b.set_block(1, velodyne::kLowerBank, 100);  // an HDL-64E's lower bank
  id = velodyne::identify_packet(b.bytes());
  EXPECT_EQ(id.kind, velodyne::PacketIdentity::Kind::kHdl64);
  EXPECT_TRUE(velodyne::identity_matches(id, Model::kS2_1));
  EXPECT_FALSE(velodyne::identity_matches(id, Model::kHdl32e));
  EXPECT_EQ(velodyne::identify_packet(std::span(b.bytes().data(), 1000)).kind,
            velodyne::PacketIdentity::Kind::kUnknown);
}

TEST(VelodyneFamily, ModelNamesParse) {
  EXPECT_EQ(velodyne::parse_model("VLP-16"), Model::kVlp16);
  EXPECT_EQ(velodyne::parse_model("vlp16"), Model::kVlp16);
  EXPECT_EQ(velodyne::parse_model("Puck Hi-Res"), Model::kPuckHiRes);
  EXPECT_EQ(velodyne::parse_model("puck lite"), Model::kPuckLite);
  EXPECT_EQ(velodyne::parse_model("HDL-32E"), Model::kHdl32e);
  EXPECT_EQ(velodyne::parse_model("hdl32e"), Model::kHdl32e);
  EXPECT_EQ(velodyne::parse_model("VLP-32C"), Model::kVlp32c);
  EXPECT_EQ(velodyne::parse_model("HDL-64E S3"), Model::kS3);
  EXPECT_FALSE(velodyne::parse_model("VLS-128"));
  EXPECT_FALSE(velodyne::parse_model(""));
}

// A VeloView file pads a 16- or 32-laser sensor's lasers to 64, the padding disabled: it fits
// its model and no other; an HDL-64E's file fits no 16- or 32-laser model.
TEST(VelodyneFamily, CalibrationMustFitTheModel) {
  STAC_REQUIRE_SHARED_DATA(kVlp16);
  STAC_REQUIRE_SHARED_DATA(kHdl32);
  STAC_REQUIRE_SHARED_DATA(kSztaki);
  auto vlp16 = velodyne::load_calibration(shared_data(kVlp16));
  auto hdl32 = velodyne::load_calibration(shared_data(kHdl32));
  auto hdl64 = velodyne::load_calibration(shared_data(kSztaki));
  auto vlp32c = velodyne::load_calibration(repo_file("config/calib/vlp32c.yaml"));
  ASSERT_TRUE(vlp16 && hdl32 && hdl64 && vlp32c);
  EXPECT_TRUE(velodyne::check_calibration_for(*vlp16, Model::kVlp16));
  EXPECT_TRUE(velodyne::check_calibration_for(*hdl32, Model::kHdl32e));
  EXPECT_TRUE(velodyne::check_calibration_for(*vlp32c, Model::kVlp32c));
  EXPECT_TRUE(velodyne::check_calibration_for(*hdl64, Model::kS3));
  const auto wrong = velodyne::check_calibration_for(*vlp16, Model::kS2_1);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("enables only lasers 0..15"), std::string::npos)
      << wrong.error().message;
  EXPECT_FALSE(velodyne::check_calibration_for(*vlp16, Model::kHdl32e));
  const auto too_many = velodyne::check_calibration_for(*hdl64, Model::kVlp16);
  ASSERT_FALSE(too_many);
  EXPECT_NE(too_many.error().message.find("enables laser 63"), std::string::npos);
  EXPECT_FALSE(velodyne::check_calibration_for(*vlp32c, Model::kS2_1));  // 32 listed, 64 needed
  // An HDL-32E's file for a VLP-32C: 32 lasers, but 2 mm units where the VLP-32C sends 4 mm.
  const auto units = velodyne::check_calibration_for(*hdl32, Model::kVlp32c);
  ASSERT_FALSE(units);
  EXPECT_NE(units.error().message.find("distance units of 2.0"), std::string::npos)
      << units.error().message;
  EXPECT_DOUBLE_EQ(vlp32c->distance_resolution_m, 0.004);
  EXPECT_EQ(vlp32c->num_lasers, 32);
  // The VLP-32C's laser 14: 0.667 deg up, the manual's azimuth offset +4.2 deg (rot -4.2).
  EXPECT_NEAR(vlp32c->lasers[14].vert_correction_rad * 180 / std::numbers::pi, 0.667, 1e-9);
  EXPECT_NEAR(vlp32c->lasers[14].rot_correction_rad * 180 / std::numbers::pi, -4.2, 1e-9);
  // Rings: ranks of the elevation, so the VLP-16's interleaved lasers come out in order.
  velodyne::PacketDecoder d(velodyne::lasers_of(*vlp16, Model::kVlp16),
                            velodyne::DecoderConfig{.model = Model::kVlp16});
  EXPECT_EQ(d.ring_of(0), 0);    // -15 deg
  EXPECT_EQ(d.ring_of(1), 8);    // +1 deg
  EXPECT_EQ(d.ring_of(15), 15);  // +15 deg
}

}  // namespace
}  // namespace stac::sim
