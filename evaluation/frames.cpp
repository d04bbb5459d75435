#include "evaluation/frames.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

#include "ego/local_frame.hpp"

namespace stac::evaluation {
namespace {

std::string where(const std::array<double, 3>& g) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%.7f, %.7f, %.2f m", g[0], g[1], g[2]);
  return buf;
}

double wrap(double a) {
  return std::remainder(a, 2.0 * std::numbers::pi);
}

// A rigid change of the horizontal frame, applied to the truth's poses, boxes and velocities.
template <class Place>
void apply(std::vector<TruthScanRecord>& truth, Place place) {
  for (TruthScanRecord& s : truth) {
    place(s.ego.x, s.ego.y, s.ego.z, s.ego.yaw, nullptr, nullptr);
    for (TruthObjectRecord& o : s.objects) place(o.x, o.y, o.z, o.yaw, &o.vx, &o.vy);
  }
}

// From ENU at `from` into ENU at `to`, through geodetic coordinates.
void enu_to_enu(std::vector<TruthScanRecord>& truth, const std::array<double, 3>& from,
                const std::array<double, 3>& to) {
  const ego::LocalFrame a(ego::Geodetic{from[0], from[1], from[2]});
  ego::LocalFrame b(ego::Geodetic{to[0], to[1], to[2]});
  apply(truth, [&](double& x, double& y, double& z, double& yaw, double* vx, double* vy) {
    const Eigen::Vector3d p(x, y, z);
    const Eigen::Vector3d q = b.to_local(a.to_geodetic(p));
    // The angle between the frames' east axes at this place (meridian convergence).
    const Eigen::Vector3d east = b.to_local(a.to_geodetic(p + Eigen::Vector3d::UnitX())) - q;
    const double turn = std::atan2(east.y(), east.x());
    x = q.x(), y = q.y(), z = q.z();
    yaw = wrap(yaw + turn);
    if (vx != nullptr) {
      const double c = std::cos(turn), s = std::sin(turn), u = *vx, v = *vy;
      *vx = c * u - s * v;
      *vy = s * u + c * v;
    }
  });
}

}  // namespace

rt::Result<std::string> truth_in_tracks_frame(std::vector<TruthScanRecord>& truth,
                                              const std::vector<TracksScan>& tracks) {
  if (tracks.empty() || truth.empty()) return std::string("frames: nothing to compare");
  const TracksScan& first = tracks.front();
  for (const TracksScan& t : tracks) {
    if (t.frame != first.frame || t.origin != first.origin) {
      return rt::make_error("the tracks file changes its frame at scan " + std::to_string(t.scan) +
                            " (one file, one frame: was it pieced together?)");
    }
  }
  const std::optional<std::array<double, 3>>& truth_origin = truth.front().origin;
  for (const TruthScanRecord& s : truth) {
    if (s.origin != truth_origin) {
      return rt::make_error("the truth file changes its origin at scan " + std::to_string(s.scan) +
                            " (one file, one frame)");
    }
  }
  switch (first.frame) {
    case TracksFrame::kUnknown:
      return std::string(
          "frames: the tracks file does not record its frame (written by an older stac "
          "process); taken to be the truth's");
    case TracksFrame::kEnu: {
      if (!truth_origin) {
        return "frames: the truth does not record its origin; taken to be the tracks' (" +
               where(first.origin) + ")";
      }
      const ego::LocalFrame tracks_frame(
          ego::Geodetic{first.origin[0], first.origin[1], first.origin[2]});
      ego::LocalFrame truth_frame(
          ego::Geodetic{(*truth_origin)[0], (*truth_origin)[1], (*truth_origin)[2]});
      const Eigen::Vector3d truth_at =
          truth_frame.to_local(tracks_frame.to_geodetic(Eigen::Vector3d::Zero()));
      const double apart = truth_at.norm();
      if (apart < 1e-3) return "frames: the same (ENU at " + where(first.origin) + ")";
      if (apart > kMaxOriginDistanceM) {
        char km[32];
        std::snprintf(km, sizeof(km), "%.0f", apart / 1000.0);
        return rt::make_error("the truth's origin (" + where(*truth_origin) + ") is " + km +
                              " km from the tracks' (" + where(first.origin) +
                              "): not the same drive? Process the capture that the truth "
                              "belongs to");
      }
      enu_to_enu(truth, *truth_origin, first.origin);
      char m[64];
      std::snprintf(m, sizeof(m), "%.2f", apart);
      return "frames: the truth moved from ENU at " + where(*truth_origin) +
             " into the tracks' ENU at " + where(first.origin) + " (" + m + " m apart)";
    }
    case TracksFrame::kVehicle: {
      const EgoRecord e0 = truth.front().ego;
      for (const TruthScanRecord& s : truth) {
        const double moved = std::hypot(s.ego.x - e0.x, s.ego.y - e0.y, s.ego.z - e0.z);
        if (moved > kParkedToleranceM || std::abs(wrap(s.ego.yaw - e0.yaw)) > kParkedToleranceRad) {
          char m[32];
          std::snprintf(m, sizeof(m), "%.1f", moved);
          return rt::make_error(
              std::string("the tracks are in the vehicle frame (their capture had no INS "
                          "stream, or --no-deskew), but the ego moves in the truth (") +
              m + " m by scan " + std::to_string(s.scan) +
              "): tracks of a moving vehicle need its poses; process a capture with the INS "
              "stream, without --no-deskew");
        }
      }
      const double c = std::cos(e0.yaw), sn = std::sin(e0.yaw);
      apply(truth, [&](double& x, double& y, double& z, double& yaw, double* vx, double* vy) {
        const double dx = x - e0.x, dy = y - e0.y;
        x = c * dx + sn * dy;
        y = -sn * dx + c * dy;
        z -= e0.z;
        yaw = wrap(yaw - e0.yaw);
        if (vx != nullptr) {
          const double u = *vx, v = *vy;
          *vx = c * u + sn * v;
          *vy = -sn * u + c * v;
        }
      });
      return std::string(
          "frames: the tracks are in the vehicle frame (no pose); the truth moved into the "
          "vehicle frame of its first scan (the ego is parked)");
    }
  }
  return std::string();
}

}  // namespace stac::evaluation
