#include "formats/kitti_tracklets.hpp"

#include <tinyxml2.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>

namespace stac::formats {
namespace {

// The text of child `tag` as a finite number; false when missing or not one.
bool number(const tinyxml2::XMLElement* parent, const char* tag, double& out) {
  const tinyxml2::XMLElement* e = parent->FirstChildElement(tag);
  if (e == nullptr || e->GetText() == nullptr) return false;
  char* end = nullptr;
  out = std::strtod(e->GetText(), &end);
  return end != e->GetText() && *end == '\0' && std::isfinite(out);
}

bool integer(const tinyxml2::XMLElement* parent, const char* tag, int& out) {
  double v = 0;
  if (!number(parent, tag, v) || v != std::floor(v) || std::abs(v) > 1e6) return false;
  out = static_cast<int>(v);
  return true;
}

// The <item> children after a <count>, which must match them.
bool counted_items(const tinyxml2::XMLElement* list,
                   std::vector<const tinyxml2::XMLElement*>& items) {
  int count = 0;
  if (!integer(list, "count", count) || count < 0) return false;
  items.clear();
  for (const auto* e = list->FirstChildElement("item"); e; e = e->NextSiblingElement("item"))
    items.push_back(e);
  return items.size() == static_cast<std::size_t>(count);
}

}  // namespace

std::string_view stac_class_of_kitti_type(std::string_view type) noexcept {
  if (type == "Car" || type == "Van" || type == "Truck" || type == "Tram") return "car";
  if (type == "Pedestrian" || type == "Person_sitting") return "pedestrian";
  if (type == "Cyclist") return "bicyclist";
  if (type == "Misc" || type == "DontCare") return "";
  return "?";
}

rt::Result<std::vector<Tracklet>> parse_kitti_tracklets(const std::string& text,
                                                        const std::string& name) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS)
    return rt::make_error(name + ": not readable as XML: " + doc.ErrorStr());
  const tinyxml2::XMLElement* root = doc.FirstChildElement("boost_serialization");
  const tinyxml2::XMLElement* list = root ? root->FirstChildElement("tracklets") : nullptr;
  if (list == nullptr)
    return rt::make_error(name +
                          ": missing <boost_serialization><tracklets> (KITTI raw's "
                          "tracklet_labels.xml)");
  std::vector<const tinyxml2::XMLElement*> items;
  if (!counted_items(list, items))
    return rt::make_error(name + ": <tracklets>' <count> is not the number of its <item>s");
  std::vector<Tracklet> out;
  out.reserve(items.size());
  for (std::size_t k = 0; k < items.size(); ++k) {
    const tinyxml2::XMLElement* item = items[k];
    const std::string where = name + ": tracklet " + std::to_string(k) + ": ";
    Tracklet t;
    const tinyxml2::XMLElement* type = item->FirstChildElement("objectType");
    if (type == nullptr || type->GetText() == nullptr)
      return rt::make_error(where + "missing <objectType>");
    t.object_type = type->GetText();
    if (stac_class_of_kitti_type(t.object_type) == "?")
      return rt::make_error(where + "<objectType> '" + t.object_type +
                            "' is none of KITTI's (Car, Van, Truck, Pedestrian, Person_sitting, "
                            "Cyclist, Tram, Misc, DontCare)");
    int first = 0;
    if (!number(item, "h", t.h) || !number(item, "w", t.w) || !number(item, "l", t.l) ||
        !integer(item, "first_frame", first))
      return rt::make_error(where + "<h>, <w>, <l> and <first_frame> must be numbers");
    for (const double size : {t.h, t.w, t.l})
      if (!(size > 0 && size <= 50))
        return rt::make_error(where + "a box size (h, w, l) is not in (0, 50] m");
    if (first < 0) return rt::make_error(where + "<first_frame> is negative");
    t.first_frame = static_cast<std::uint32_t>(first);
    const tinyxml2::XMLElement* poses = item->FirstChildElement("poses");
    std::vector<const tinyxml2::XMLElement*> pose_items;
    if (poses == nullptr || !counted_items(poses, pose_items))
      return rt::make_error(where + "<poses>' <count> is not the number of its <item>s");
    for (std::size_t f = 0; f < pose_items.size(); ++f) {
      TrackletPose p;
      const tinyxml2::XMLElement* e = pose_items[f];
      if (!number(e, "tx", p.tx) || !number(e, "ty", p.ty) || !number(e, "tz", p.tz) ||
          !number(e, "rx", p.rx) || !number(e, "ry", p.ry) || !number(e, "rz", p.rz) ||
          !integer(e, "state", p.state) || !integer(e, "occlusion", p.occlusion) ||
          !integer(e, "truncation", p.truncation))
        return rt::make_error(where + "pose " + std::to_string(f) +
                              ": tx, ty, tz, rx, ry, rz must be finite numbers and state, "
                              "occlusion, truncation integers");
      if (std::hypot(p.tx, p.ty, p.tz) > 1000)
        return rt::make_error(where + "pose " + std::to_string(f) +
                              ": farther than 1 km from the velodyne");
      t.poses.push_back(p);
    }
    out.push_back(std::move(t));
  }
  return out;
}

rt::Result<std::vector<Tracklet>> read_kitti_tracklets(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) return rt::make_error(file.string() + ": cannot read");
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  return parse_kitti_tracklets(text, file.string());
}

std::string format_kitti_tracklets(const std::vector<Tracklet>& tracklets) {
  std::string s =
      "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\" ?>\n"
      "<!DOCTYPE boost_serialization>\n"
      "<boost_serialization signature=\"serialization::archive\" version=\"9\">\n"
      "<tracklets class_id=\"0\" tracking_level=\"0\" version=\"0\">\n";
  char line[512];
  std::snprintf(line, sizeof line, "\t<count>%zu</count>\n\t<item_version>1</item_version>\n",
                tracklets.size());
  s += line;
  for (std::size_t k = 0; k < tracklets.size(); ++k) {
    const Tracklet& t = tracklets[k];
    s += k == 0 ? "\t<item class_id=\"1\" tracking_level=\"0\" version=\"1\">\n" : "\t<item>\n";
    std::snprintf(line, sizeof line,
                  "\t\t<objectType>%s</objectType>\n\t\t<h>%.6f</h>\n\t\t<w>%.6f</w>\n"
                  "\t\t<l>%.6f</l>\n\t\t<first_frame>%u</first_frame>\n",
                  t.object_type.c_str(), t.h, t.w, t.l, t.first_frame);
    s += line;
    s += k == 0 ? "\t\t<poses class_id=\"2\" tracking_level=\"0\" version=\"0\">\n"
                : "\t\t<poses>\n";
    std::snprintf(line, sizeof line,
                  "\t\t\t<count>%zu</count>\n\t\t\t<item_version>2</item_version>\n",
                  t.poses.size());
    s += line;
    for (std::size_t f = 0; f < t.poses.size(); ++f) {
      const TrackletPose& p = t.poses[f];
      s += k == 0 && f == 0 ? "\t\t\t<item class_id=\"3\" tracking_level=\"0\" version=\"2\">\n"
                            : "\t\t\t<item>\n";
      std::snprintf(line, sizeof line,
                    "\t\t\t\t<tx>%.6f</tx>\n\t\t\t\t<ty>%.6f</ty>\n\t\t\t\t<tz>%.6f</tz>\n"
                    "\t\t\t\t<rx>%.6f</rx>\n\t\t\t\t<ry>%.6f</ry>\n\t\t\t\t<rz>%.6f</rz>\n"
                    "\t\t\t\t<state>%d</state>\n\t\t\t\t<occlusion>%d</occlusion>\n"
                    "\t\t\t\t<occlusion_kf>%d</occlusion_kf>\n"
                    "\t\t\t\t<truncation>%d</truncation>\n",
                    p.tx, p.ty, p.tz, p.rx, p.ry, p.rz, p.state, p.occlusion, p.occlusion,
                    p.truncation);
      s += line;
      s += "\t\t\t\t<amt_occlusion>0.0</amt_occlusion>\n"
           "\t\t\t\t<amt_occlusion_kf>-1</amt_occlusion_kf>\n"
           "\t\t\t\t<amt_border_l>0.0</amt_border_l>\n"
           "\t\t\t\t<amt_border_r>0.0</amt_border_r>\n"
           "\t\t\t\t<amt_border_kf>-1</amt_border_kf>\n\t\t\t</item>\n";
    }
    s += "\t\t</poses>\n\t\t<finished>1</finished>\n\t</item>\n";
  }
  s += "</tracklets>\n</boost_serialization>\n";
  return s;
}

}  // namespace stac::formats
