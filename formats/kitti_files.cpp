#include "formats/kitti_files.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace stac::formats {

rt::Result<std::size_t> kitti_scan_points(const std::string& path) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  if (ec) return rt::make_error(path + ": cannot read: " + ec.message());
  if (bytes == 0 || bytes % 16 != 0) {
    return rt::make_error(
        path + ": " + std::to_string(bytes) +
        " bytes is not a KITTI scan (float32 x,y,z,reflectance: a multiple of 16 bytes)");
  }
  return static_cast<std::size_t>(bytes / 16);
}

rt::Result<std::vector<std::filesystem::path>> kitti_scans_in(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> scans;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    if (entry.path().extension() == ".bin") scans.push_back(entry.path());
  }
  if (ec) return rt::make_error(folder.string() + ": cannot list: " + ec.message());
  std::sort(scans.begin(), scans.end());
  return scans;
}

rt::Result<std::vector<float>> load_kitti_scan(const std::string& path) {
  const auto points = kitti_scan_points(path);
  if (!points) return rt::Unexpected<rt::Error>{points.error()};
  const std::size_t bytes = *points * 16;
  std::vector<float> v(bytes / sizeof(float));
  std::ifstream f(path, std::ios::binary);
  if (!f.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(bytes))) {
    return rt::make_error(path + ": short read");
  }
  return v;
}

bool kitti_calib_values(const std::string& text, const std::string& key, std::size_t count,
                        std::vector<double>& out) {
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream ss(line);
    std::string word;
    if (!(ss >> word) || word != key + ":") continue;
    out.assign(count, 0.0);
    for (double& v : out)
      if (!(ss >> v) || !std::isfinite(v)) return false;
    return true;
  }
  return false;
}

bool is_rotation(const Eigen::Matrix3d& m) noexcept {
  return (m * m.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-3 &&
         std::abs(m.determinant() - 1.0) < 1e-3;
}

rt::Result<Eigen::Isometry3d> load_kitti_rect_T_velo(const std::string& calib_path) {
  std::ifstream in(calib_path);
  if (!in) return rt::make_error(calib_path + ": cannot read the KITTI calibration");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::vector<double> r0_values, tr_values;
  if (!kitti_calib_values(text, "R0_rect", 9, r0_values) ||
      !kitti_calib_values(text, "Tr_velo_to_cam", 12, tr_values)) {
    return rt::make_error(calib_path +
                          ": needs 'R0_rect:' (9 numbers) and 'Tr_velo_to_cam:' (12 numbers)");
  }
  const Eigen::Matrix3d r0 =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r0_values.data());
  const Eigen::Matrix<double, 3, 4> tr =
      Eigen::Map<const Eigen::Matrix<double, 3, 4, Eigen::RowMajor>>(tr_values.data());
  // Both rotations (a file of zeros would put every point at the camera and every object at
  // range 0).
  if (!is_rotation(r0))
    return rt::make_error(calib_path +
                          ": 'R0_rect:' is not a rotation (orthonormal, determinant 1)");
  if (!is_rotation(tr.leftCols<3>())) {
    return rt::make_error(
        calib_path + ": the rotation of 'Tr_velo_to_cam:' is not one (orthonormal, determinant 1)");
  }
  Eigen::Isometry3d velo_to_cam = Eigen::Isometry3d::Identity();
  velo_to_cam.linear() = tr.leftCols<3>();
  velo_to_cam.translation() = tr.col(3);
  Eigen::Isometry3d rect = Eigen::Isometry3d::Identity();
  rect.linear() = r0;
  return rect * velo_to_cam;
}

bool KittiObject::contains(const Eigen::Vector3d& p, double margin) const noexcept {
  // Into the object's frame: origin at the bottom centre, x along its length (rotation_y about
  // the camera's y axis, which points down), y down, z across.
  const Eigen::Vector3d d = p - bottom_centre;
  const double c = std::cos(rotation_y), s = std::sin(rotation_y);
  const double along = c * d.x() - s * d.z();
  const double across = s * d.x() + c * d.z();
  return std::abs(along) <= length / 2 + margin && std::abs(across) <= width / 2 + margin &&
         d.y() <= margin && d.y() >= -height - margin;
}

rt::Result<std::vector<KittiObject>> load_kitti_labels(const std::string& path) {
  std::ifstream in(path);
  if (!in) return rt::make_error(path + ": cannot read the KITTI labels");
  std::vector<KittiObject> out;
  int n = 0;
  for (std::string line; std::getline(in, line);) {
    ++n;
    if (line.empty()) continue;
    std::istringstream ss(line);
    KittiObject o;
    double alpha = 0, bbox[4];
    ss >> o.type >> o.truncated >> o.occluded >> alpha >> bbox[0] >> bbox[1] >> bbox[2] >>
        bbox[3] >> o.height >> o.width >> o.length >> o.bottom_centre.x() >> o.bottom_centre.y() >>
        o.bottom_centre.z() >> o.rotation_y;
    std::string extra;
    if (!ss || (ss >> extra)) {
      return rt::make_error(path + ":" + std::to_string(n) +
                            ": not a KITTI label line (type, 14 numbers)");
    }
    static constexpr const char* kTypes[] = {
        "Car",     "Van",  "Truck", "Pedestrian", "Person_sitting",
        "Cyclist", "Tram", "Misc",  "DontCare"};
    if (std::find(std::begin(kTypes), std::end(kTypes), o.type) == std::end(kTypes)) {
      return rt::make_error(path + ":" + std::to_string(n) + ": type '" + o.type +
                            "' is not a KITTI class (Car, Van, Truck, Pedestrian, Person_sitting, "
                            "Cyclist, Tram, Misc, DontCare)");
    }
    if (o.type != "DontCare" && (o.height < 0 || o.width < 0 || o.length < 0)) {
      return rt::make_error(path + ":" + std::to_string(n) +
                            ": negative dimensions (height, width, length)");
    }
    if (o.type != "DontCare") out.push_back(o);
  }
  return out;
}

}  // namespace stac::formats
