#include "drivers/velodyne/calibration.hpp"

#include <tinyxml2.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>

namespace stac::velodyne {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kCmToM = 0.01;

std::string where(const std::filesystem::path& path, int laser) {
  std::ostringstream s;
  s << path.string() << ": laser " << laser << ": ";
  return s.str();
}

// Sanity limits for an HDL-64E: a value outside them is a broken file, not a sensor.
rt::Status check_ranges(const std::filesystem::path& path, const Calibration& c) {
  for (int i = 0; i < c.num_lasers; ++i) {
    const LaserCalibration& l = c.lasers[i];
    auto bad = [&](const char* field, double value, const char* limit) {
      std::ostringstream s;
      s << where(path, l.laser_id) << "'" << field << "' = " << value << " is outside " << limit;
      return rt::make_error(s.str());
    };
    if (!std::isfinite(l.vert_correction_rad) || std::abs(l.vert_correction_rad) > 45 * kDegToRad)
      return bad("vert_correction", l.vert_correction_rad, "+-45 deg");
    if (!std::isfinite(l.rot_correction_rad) || std::abs(l.rot_correction_rad) > 45 * kDegToRad)
      return bad("rot_correction", l.rot_correction_rad, "+-45 deg");
    for (auto [name, v] : {std::pair{"dist_correction", l.dist_correction_m},
                           std::pair{"dist_correction_x", l.dist_correction_x_m},
                           std::pair{"dist_correction_y", l.dist_correction_y_m},
                           std::pair{"vert_offset_correction", l.vert_offset_m},
                           std::pair{"horiz_offset_correction", l.horiz_offset_m}}) {
      if (!std::isfinite(v) || std::abs(v) > 5.0) return bad(name, v, "+-5 m");
    }
    if (!std::isfinite(l.focal_distance_m) || l.focal_distance_m < 0 || l.focal_distance_m > 200)
      return bad("focal_distance", l.focal_distance_m, "0..200 m");
    if (!std::isfinite(l.focal_slope) || std::abs(l.focal_slope) > 100)
      return bad("focal_slope", l.focal_slope, "+-100");
    if (l.min_intensity < 0 || l.min_intensity > 255)
      return bad("min_intensity", l.min_intensity, "0..255");
    if (l.max_intensity < l.min_intensity || l.max_intensity > 255)
      return bad("max_intensity", l.max_intensity, "min_intensity..255");
  }
  if (!(c.distance_resolution_m > 0 && c.distance_resolution_m < 0.1)) {
    std::ostringstream s;
    s << path.string() << ": distance resolution " << c.distance_resolution_m
      << " m is outside (0, 0.1) m";
    return rt::make_error(s.str());
  }
  return {};
}

// Places the parsed lasers by id and checks that ids 0..n-1 each appear once.
rt::Result<Calibration> finish(const std::filesystem::path& path,
                               const std::vector<LaserCalibration>& lasers,
                               double distance_resolution_m) {
  Calibration c;
  c.source = path.string();
  c.distance_resolution_m = distance_resolution_m;
  if (lasers.size() != 16 && lasers.size() != 32 &&
      lasers.size() != static_cast<std::size_t>(kMaxLasers)) {  // missing ones' returns: lost
    return rt::make_error(path.string() +
                          ": a Velodyne calibration lists 16, 32 or 64 lasers, this file " +
                          std::to_string(lasers.size()) + " (cut short?)");
  }
  c.num_lasers = static_cast<int>(lasers.size());
  std::set<int> seen;
  for (const LaserCalibration& l : lasers) {
    if (l.laser_id < 0 || l.laser_id >= c.num_lasers) {
      return rt::make_error(where(path, l.laser_id) + "'laser_id' must be in 0.." +
                            std::to_string(c.num_lasers - 1));
    }
    if (!seen.insert(l.laser_id).second) {
      return rt::make_error(where(path, l.laser_id) + "'laser_id' appears twice");
    }
    c.lasers[static_cast<std::size_t>(l.laser_id)] = l;
  }
  auto ok = check_ranges(path, c);
  if (!ok) return rt::Unexpected<rt::Error>{ok.error()};
  return c;
}

// ---- ROS yaml (metres, radians) ----

rt::Result<double> yaml_number(const YAML::Node& node, const char* key, const std::string& ctx,
                               std::optional<double> fallback) {
  const YAML::Node v = node[key];
  if (!v) {
    if (fallback) return *fallback;
    return rt::make_error(ctx + "missing '" + key + "'");
  }
  try {
    return v.as<double>();
  } catch (const YAML::Exception&) {
    return rt::make_error(ctx + "'" + key + "' is not a number");
  }
}

// ---- db.xml (boost serialization: cm, degrees) ----

rt::Result<double> xml_number(const tinyxml2::XMLElement* parent, const char* tag,
                              const std::string& ctx) {
  const tinyxml2::XMLElement* e = parent->FirstChildElement(tag);
  if (e == nullptr) return rt::make_error(ctx + "missing <" + std::string(tag) + ">");
  if (e->NextSiblingElement(tag) != nullptr)  // which of them would the unit's be?
    return rt::make_error(ctx + "<" + std::string(tag) + "> appears twice");
  // The whole text must be the number ("-7.15abc" is a broken file, not -7.15).
  const char* text = e->GetText();
  char* end = nullptr;
  const double v = text != nullptr ? std::strtod(text, &end) : 0.0;
  while (end != nullptr && *end != '\0' && std::isspace(static_cast<unsigned char>(*end))) ++end;
  if (text == nullptr || end == text || *end != '\0') {
    return rt::make_error(ctx + "<" + std::string(tag) + "> is not a number: '" +
                          (text != nullptr ? std::string(text) : std::string{}) + "'");
  }
  return v;
}

// Reads the <item> values of a top-level array such as <minIntensity_>; empty when absent. An
// array given twice or an item that is not an integer is refused.
rt::Result<std::vector<int>> xml_int_items(const tinyxml2::XMLElement* db, const char* tag,
                                           const std::string& ctx) {
  std::vector<int> out;
  const tinyxml2::XMLElement* arr = db->FirstChildElement(tag);
  if (arr == nullptr) return out;
  if (arr->NextSiblingElement(tag) != nullptr)
    return rt::make_error(ctx + "<" + std::string(tag) + "> appears twice");
  for (const auto* it = arr->FirstChildElement("item"); it; it = it->NextSiblingElement("item")) {
    int v = 0;
    if (it->QueryIntText(&v) != tinyxml2::XML_SUCCESS)
      return rt::make_error(ctx + "<" + std::string(tag) + "> item " + std::to_string(out.size()) +
                            " is not an integer");
    out.push_back(v);
  }
  return out;
}

}  // namespace

namespace {

rt::Result<Calibration> from_ros_yaml(const YAML::Node& root, const std::filesystem::path& path);
rt::Result<Calibration> from_db_xml(const tinyxml2::XMLDocument& doc,
                                    const std::filesystem::path& path);

}  // namespace

rt::Result<Calibration> load_ros_yaml(const std::filesystem::path& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path.string());
  } catch (const YAML::Exception& e) {
    return rt::make_error(path.string() + ": not readable as YAML: " + e.what());
  }
  return from_ros_yaml(root, path);
}

rt::Result<Calibration> parse_ros_yaml(const std::string& text, const std::filesystem::path& name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return rt::make_error(name.string() + ": not readable as YAML: " + e.what());
  }
  return from_ros_yaml(root, name);
}

rt::Result<Calibration> load_db_xml(const std::filesystem::path& path) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(path.string().c_str()) != tinyxml2::XML_SUCCESS) {
    return rt::make_error(path.string() + ": not readable as XML: " + doc.ErrorStr());
  }
  return from_db_xml(doc, path);
}

rt::Result<Calibration> parse_db_xml(const std::string& text, const std::filesystem::path& name) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) {
    return rt::make_error(name.string() + ": not readable as XML: " + doc.ErrorStr());
  }
  return from_db_xml(doc, name);
}

namespace {

// A laser id as a file writes it: a whole number 0..kMaxLasers-1 (checked before it becomes an
// int: a float beyond int's range cannot be cast).
bool laser_number(double v) noexcept {
  return v >= 0 && v < kMaxLasers && v == std::floor(v);
}

std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

rt::Result<Calibration> from_ros_yaml(const YAML::Node& root, const std::filesystem::path& path) {
  if (!root.IsMap() || !root["lasers"] || !root["lasers"].IsSequence()) {
    return rt::make_error(path.string() + ": missing the 'lasers' list of a ROS calibration");
  }
  double resolution = 0.002;
  if (root["distance_resolution"]) {
    auto r = yaml_number(root, "distance_resolution", path.string() + ": ", std::nullopt);
    if (!r) return rt::Unexpected<rt::Error>{r.error()};
    resolution = *r;
  }
  if (root["num_lasers"]) {  // when written, it must agree with the list
    auto n = yaml_number(root, "num_lasers", path.string() + ": ", std::nullopt);
    if (!n) return rt::Unexpected<rt::Error>{n.error()};
    if (*n != static_cast<double>(root["lasers"].size())) {
      return rt::make_error(path.string() + ": 'num_lasers' is " +
                            root["num_lasers"].as<std::string>() + " but the 'lasers' list holds " +
                            std::to_string(root["lasers"].size()));
    }
  }
  std::vector<LaserCalibration> lasers;
  int index = 0;
  for (const YAML::Node& node : root["lasers"]) {
    std::string ctx = path.string() + ": laser entry " + std::to_string(index++) + ": ";
    if (!node.IsMap())
      return rt::make_error(ctx + "not a map of laser_id, rot_correction, ... (line " +
                            std::to_string(node.Mark().line + 1) + ")");
    auto id = yaml_number(node, "laser_id", ctx, std::nullopt);
    if (!id) return rt::Unexpected<rt::Error>{id.error()};
    if (!laser_number(*id))
      return rt::make_error(ctx + "'laser_id' " + number_text(*id) + " is not a laser number (0.." +
                            std::to_string(kMaxLasers - 1) + ")");
    LaserCalibration l;
    l.laser_id = static_cast<int>(*id);
    ctx = where(path, l.laser_id);
    struct Field {
      const char* key = nullptr;
      double* dst = nullptr;
      std::optional<double> fallback;
    };
    double min_i = 0, max_i = 255, two_pt = 0;
    const Field fields[] = {
        {"rot_correction", &l.rot_correction_rad, std::nullopt},
        {"vert_correction", &l.vert_correction_rad, std::nullopt},
        {"dist_correction", &l.dist_correction_m, std::nullopt},
        {"dist_correction_x", &l.dist_correction_x_m, 0.0},
        {"dist_correction_y", &l.dist_correction_y_m, 0.0},
        {"vert_offset_correction", &l.vert_offset_m, 0.0},
        {"horiz_offset_correction", &l.horiz_offset_m, 0.0},
        {"focal_distance", &l.focal_distance_m, 0.0},
        {"focal_slope", &l.focal_slope, 0.0},
        {"min_intensity", &min_i, 0.0},
        {"max_intensity", &max_i, 255.0},
    };
    for (const Field& f : fields) {
      auto v = yaml_number(node, f.key, ctx, f.fallback);
      if (!v) return rt::Unexpected<rt::Error>{v.error()};
      *f.dst = *v;
    }
    if (node["two_pt_correction_available"]) {
      try {
        two_pt = node["two_pt_correction_available"].as<bool>() ? 1 : 0;
      } catch (const YAML::Exception&) {
        return rt::make_error(ctx + "'two_pt_correction_available' is not true/false");
      }
    }
    // Checked for 0..255 once they are ints (finish()); one beyond int's range cannot be cast.
    for (const auto& [key, v] :
         {std::pair{"min_intensity", min_i}, std::pair{"max_intensity", max_i}})
      if (!(std::abs(v) <= 1e9))
        return rt::make_error(ctx + "'" + key + "' = " + number_text(v) + " is outside 0..255");
    l.min_intensity = static_cast<int>(min_i);
    l.max_intensity = static_cast<int>(max_i);
    // A file that claims two-point correction with zero X/Y corrections (the utexas S1 file)
    // would bend every point by up to dist_correction: read it as "not available".
    l.two_pt_correction_available =
        two_pt != 0 && (l.dist_correction_x_m != 0.0 || l.dist_correction_y_m != 0.0);
    lasers.push_back(l);
  }
  return finish(path, lasers, resolution);
}

rt::Result<Calibration> from_db_xml(const tinyxml2::XMLDocument& doc,
                                    const std::filesystem::path& path) {
  const tinyxml2::XMLElement* root = doc.FirstChildElement("boost_serialization");
  const tinyxml2::XMLElement* db = root ? root->FirstChildElement("DB") : nullptr;
  if (db == nullptr) return rt::make_error(path.string() + ": missing <boost_serialization><DB>");
  double lsb_cm = 0.2;
  if (db->FirstChildElement("distLSB_")) {
    auto v = xml_number(db, "distLSB_", path.string() + ": ");
    if (!v) return rt::Unexpected<rt::Error>{v.error()};
    lsb_cm = *v;
  }
  const tinyxml2::XMLElement* points = db->FirstChildElement("points_");
  if (points == nullptr) return rt::make_error(path.string() + ": missing <points_>");
  if (points->NextSiblingElement("points_") != nullptr)
    return rt::make_error(path.string() + ": <points_> appears twice");
  const std::string file_ctx = path.string() + ": ";
  auto enabled_r = xml_int_items(db, "enabled_", file_ctx);
  if (!enabled_r) return rt::Unexpected<rt::Error>{enabled_r.error()};
  auto min_r = xml_int_items(db, "minIntensity_", file_ctx);
  if (!min_r) return rt::Unexpected<rt::Error>{min_r.error()};
  auto max_r = xml_int_items(db, "maxIntensity_", file_ctx);
  if (!max_r) return rt::Unexpected<rt::Error>{max_r.error()};
  const std::vector<int>& enabled = *enabled_r;
  const std::vector<int>& min_i = *min_r;
  const std::vector<int>& max_i = *max_r;

  std::vector<LaserCalibration> lasers;
  int index = 0;
  for (const auto* item = points->FirstChildElement("item"); item;
       item = item->NextSiblingElement("item"), ++index) {
    const tinyxml2::XMLElement* px = item->FirstChildElement("px");
    std::string ctx = path.string() + ": points_ item " + std::to_string(index) + ": ";
    if (px == nullptr) return rt::make_error(ctx + "missing <px>");
    auto id = xml_number(px, "id_", ctx);  // VeloView writes ids as floats ("0.0")
    if (!id) return rt::Unexpected<rt::Error>{id.error()};
    if (!laser_number(std::round(*id)))
      return rt::make_error(ctx + "'id_' " + number_text(*id) + " is not a laser number (0.." +
                            std::to_string(kMaxLasers - 1) + ")");
    LaserCalibration l;
    l.laser_id = static_cast<int>(std::lround(*id));
    ctx = where(path, l.laser_id);
    struct Field {
      const char* tag;
      double* dst;
      double scale;
    };
    const Field fields[] = {
        {"rotCorrection_", &l.rot_correction_rad, kDegToRad},
        {"vertCorrection_", &l.vert_correction_rad, kDegToRad},
        {"distCorrection_", &l.dist_correction_m, kCmToM},
        {"distCorrectionX_", &l.dist_correction_x_m, kCmToM},
        {"distCorrectionY_", &l.dist_correction_y_m, kCmToM},
        {"vertOffsetCorrection_", &l.vert_offset_m, kCmToM},
        {"horizOffsetCorrection_", &l.horiz_offset_m, kCmToM},
        {"focalDistance_", &l.focal_distance_m, kCmToM},
        {"focalSlope_", &l.focal_slope, 1.0},
    };
    for (const Field& f : fields) {
      auto v = xml_number(px, f.tag, ctx);
      if (!v) return rt::Unexpected<rt::Error>{v.error()};
      *f.dst = *v * f.scale;
    }
    const auto at = [&](const std::vector<int>& v, int fallback) {
      return index < static_cast<int>(v.size()) ? v[static_cast<std::size_t>(index)] : fallback;
    };
    l.enabled = at(enabled, 1) != 0;
    l.min_intensity = at(min_i, 0);
    l.max_intensity = at(max_i, 255);
    l.two_pt_correction_available = l.dist_correction_x_m != 0.0 || l.dist_correction_y_m != 0.0;
    lasers.push_back(l);
  }
  // A per-laser list must cover every laser (10 of 64 entries is a cut file, not defaults).
  for (const auto& [tag, list] :
       {std::pair<const char*, const std::vector<int>*>{"enabled_", &enabled},
        {"minIntensity_", &min_i},
        {"maxIntensity_", &max_i}}) {
    if (!list->empty() && list->size() != lasers.size())
      return rt::make_error(file_ctx + "<" + tag + "> lists " + std::to_string(list->size()) +
                            " entries for " + std::to_string(lasers.size()) + " lasers");
  }
  return finish(path, lasers, lsb_cm * kCmToM);
}

}  // namespace

rt::Result<Calibration> load_calibration(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return rt::make_error(path.string() + ": cannot open the calibration file");
  std::string head(512, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  if (head.find("<?xml") != std::string::npos ||
      head.find("<boost_serialization") != std::string::npos) {
    return load_db_xml(path);
  }
  if (head.find("lasers") != std::string::npos ||
      head.find("distance_resolution") != std::string::npos ||
      head.find("num_lasers") != std::string::npos) {
    return load_ros_yaml(path);
  }
  return rt::make_error(path.string() +
                        ": neither a Velodyne db.xml nor a ROS calibration yaml (expected "
                        "<boost_serialization> or a 'lasers:' list)");
}

rt::Status check_calibration(const Calibration& calibration) {
  return check_ranges(calibration.source, calibration);
}

rt::Status check_calibration_for(const Calibration& c, Model model) {
  const ModelTraits& t = traits(model);
  const std::string what = c.source + ": ";
  const std::string fix = "; is it another sensor's? (set velodyne.model or --model)";
  if (c.num_lasers < t.lasers) {
    return rt::make_error(what + "lists " + std::to_string(c.num_lasers) + " lasers, a " +
                          std::string(t.name) + " has " + std::to_string(t.lasers) + fix);
  }
  int highest_enabled = -1;
  for (int i = 0; i < c.num_lasers; ++i) {
    if (c.lasers[static_cast<std::size_t>(i)].enabled) highest_enabled = i;
  }
  // VeloView pads 16- and 32-laser files to 64 entries, the padding disabled.
  if (highest_enabled >= t.lasers) {
    return rt::make_error(what + "enables laser " + std::to_string(highest_enabled) + ", a " +
                          std::string(t.name) + " has lasers 0.." + std::to_string(t.lasers - 1) +
                          fix);
  }
  if (!is_hdl64(model) && std::abs(c.distance_resolution_m - t.distance_resolution_m) > 1e-9) {
    return rt::make_error(what + "has distance units of " +
                          std::to_string(c.distance_resolution_m * 1000.0) + " mm, a " +
                          std::string(t.name) + " sends " +
                          std::to_string(t.distance_resolution_m * 1000.0) +
                          " mm (distance_resolution / distLSB_)" + fix);
  }
  if (highest_enabled < t.lasers / 2) {
    return rt::make_error(what + "enables only lasers 0.." + std::to_string(highest_enabled) +
                          ", a " + std::string(t.name) + " has " + std::to_string(t.lasers) + fix);
  }
  return {};
}

Calibration lasers_of(const Calibration& c, Model model) {
  Calibration out = c;
  out.num_lasers = std::min(c.num_lasers, traits(model).lasers);
  return out;
}

rt::Status save_ros_yaml(const Calibration& c, const std::filesystem::path& path) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap << YAML::Key << "distance_resolution" << YAML::Value
      << c.distance_resolution_m << YAML::Key << "num_lasers" << YAML::Value << c.num_lasers
      << YAML::Key << "lasers" << YAML::Value << YAML::BeginSeq;
  for (int i = 0; i < c.num_lasers; ++i) {
    const LaserCalibration& l = c.lasers[static_cast<std::size_t>(i)];
    out << YAML::BeginMap;
    out << YAML::Key << "laser_id" << YAML::Value << l.laser_id;
    out << YAML::Key << "rot_correction" << YAML::Value << l.rot_correction_rad;
    out << YAML::Key << "vert_correction" << YAML::Value << l.vert_correction_rad;
    out << YAML::Key << "dist_correction" << YAML::Value << l.dist_correction_m;
    out << YAML::Key << "dist_correction_x" << YAML::Value << l.dist_correction_x_m;
    out << YAML::Key << "dist_correction_y" << YAML::Value << l.dist_correction_y_m;
    out << YAML::Key << "two_pt_correction_available" << YAML::Value
        << l.two_pt_correction_available;
    out << YAML::Key << "vert_offset_correction" << YAML::Value << l.vert_offset_m;
    out << YAML::Key << "horiz_offset_correction" << YAML::Value << l.horiz_offset_m;
    out << YAML::Key << "focal_distance" << YAML::Value << l.focal_distance_m;
    out << YAML::Key << "focal_slope" << YAML::Value << l.focal_slope;
    out << YAML::Key << "min_intensity" << YAML::Value << l.min_intensity;
    out << YAML::Key << "max_intensity" << YAML::Value << l.max_intensity;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  std::ofstream file(path);
  if (!file) return rt::make_error(path.string() + ": cannot write the calibration file");
  file << out.c_str() << '\n';
  if (!file) return rt::make_error(path.string() + ": write failed");
  return {};
}

}  // namespace stac::velodyne
