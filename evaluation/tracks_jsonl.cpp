#include "evaluation/tracks_jsonl.hpp"

#include <algorithm>
#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "perception/classification/grid_classifier.hpp"
#include "rt/json_number.hpp"

namespace stac::evaluation {
namespace {

using nlohmann::json;

// A field read failure: carries the key path for the message.
struct FieldError {
  std::string what;
};

const json& field(const json& j, const char* key, const std::string& where) {
  if (!j.is_object()) {
    throw FieldError{where.empty()
                         ? std::string("the line is not a JSON object (one scan per line)")
                         : "'" + where.substr(0, where.size() - 1) + "' is not an object"};
  }
  const auto it = j.find(key);
  if (it == j.end()) throw FieldError{"missing key '" + where + key + "'"};
  return *it;
}

double number(const json& j, const char* key, const std::string& where = "") {
  const json& v = field(j, key, where);
  if (!v.is_number()) throw FieldError{"'" + where + key + "' is not a number"};
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw FieldError{"'" + where + key + "' is not finite"};
  return d;
}

template <class T>
T integer(const json& j, const char* key, const std::string& where = "") {
  const json& v = field(j, key, where);
  if (!v.is_number_integer()) throw FieldError{"'" + where + key + "' is not an integer"};
  if (v.is_number_unsigned()) return static_cast<T>(v.get<std::uint64_t>());
  const auto i = v.get<std::int64_t>();
  if (std::is_unsigned_v<T> && i < 0) throw FieldError{"'" + where + key + "' is negative"};
  return static_cast<T>(i);
}

std::string text(const json& j, const char* key, const std::string& where = "") {
  const json& v = field(j, key, where);
  if (!v.is_string()) throw FieldError{"'" + where + key + "' is not a string"};
  return v.get<std::string>();
}

const json& array(const json& j, const char* key) {
  const json& v = field(j, key, "");
  if (!v.is_array()) throw FieldError{"'" + std::string(key) + "' is not an array"};
  return v;
}

std::int64_t stamp(const json& j) {
  return std::llround(number(j, "time") * 1e9);
}

// "origin": [lat, lon, alt] (deg, deg, m), a place on Earth.
std::array<double, 3> origin(const json& j) {
  const json& o = field(j, "origin", "");
  const auto finite = [&](std::size_t i) {
    return o[i].is_number() && std::isfinite(o[i].get<double>());
  };
  if (!o.is_array() || o.size() != 3 || !finite(0) || !finite(1) || !finite(2))
    throw FieldError{"'origin' must be [lat, lon, alt]"};
  const std::array<double, 3> g{o[0].get<double>(), o[1].get<double>(), o[2].get<double>()};
  if (std::abs(g[0]) > 90 || std::abs(g[1]) > 180 || std::abs(g[2]) > 100'000)
    throw FieldError{
        "'origin' is not a place on Earth (lat -90..90, lon -180..180, alt within "
        "100 km)"};
  return g;
}

EgoRecord ego(const json& j) {
  const json& e = field(j, "ego", "");
  return {number(e, "x", "ego."), number(e, "y", "ego."), number(e, "z", "ego."),
          number(e, "yaw", "ego.")};
}

template <class Record, class Fill>
rt::Result<Record> parse(std::string_view line, Fill fill) {
  try {
    const json j = json::parse(line);
    Record r;
    fill(j, r);
    return r;
  } catch (const json::exception& e) {
    return rt::make_error(std::string("not valid JSON: ") + e.what());
  } catch (const FieldError& e) {
    return rt::make_error(e.what);
  }
}

template <class Record, class Parser>
rt::Result<std::vector<Record>> read_file(const std::filesystem::path& file, Parser parser,
                                          const ReadProgress& progress) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return rt::make_error(file.string() + ": cannot open");
  std::vector<Record> out;
  std::string line;
  std::uint64_t number_of_line = 0, bytes = 0;
  while (std::getline(in, line)) {
    ++number_of_line;
    bytes += line.size() + 1;
    if (progress && number_of_line % 64 == 0) progress(bytes);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    auto r = parser(line);
    if (!r)
      return rt::make_error(file.string() + ":" + std::to_string(number_of_line) + ": " +
                            r.error().message);
    if (!out.empty() && r->scan <= out.back().scan) {  // one line per scan, in order
      return rt::make_error(file.string() + ":" + std::to_string(number_of_line) + ": scan " +
                            std::to_string(r->scan) + " after scan " +
                            std::to_string(out.back().scan) +
                            " (each scan once, in increasing order)");
    }
    out.push_back(std::move(*r));
  }
  if (in.bad()) return rt::make_error(file.string() + ": read error");
  return out;
}

void append_time(std::int64_t ns, std::string& out) {
  char buf[48];
  const std::uint64_t mag =
      ns < 0 ? static_cast<std::uint64_t>(-(ns + 1)) + 1 : static_cast<std::uint64_t>(ns);
  std::snprintf(buf, sizeof(buf), "%s%" PRIu64 ".%09" PRIu64, ns < 0 ? "-" : "",
                mag / 1'000'000'000u, mag % 1'000'000'000u);
  out += buf;
}

}  // namespace

TrackRecord track_record(const tracking::Track& t) {
  TrackRecord r;
  r.id = t.id;
  r.state = tracking::state_name(t.state);
  r.x = t.position.x();
  r.y = t.position.y();
  r.z = t.position.z();
  r.vx = t.velocity.x();
  r.vy = t.velocity.y();
  r.length = t.length;
  r.width = t.width;
  r.height = t.height;
  r.yaw = t.yaw;
  r.points = t.points;
  r.age = t.age;
  r.segment = t.segment;
  return r;
}

void append_json_line(const TracksScan& s, std::string& out) {
  char buf[1024];
  out += '{';
  if (s.frame == TracksFrame::kEnu) {
    std::snprintf(buf, sizeof(buf), "\"frame\":\"enu\",\"origin\":[%s,%s,%s],",
                  rt::json_number(s.origin[0], 10).c_str(),
                  rt::json_number(s.origin[1], 10).c_str(),
                  rt::json_number(s.origin[2], 4).c_str());
    out += buf;
  } else if (s.frame == TracksFrame::kVehicle) {
    out += "\"frame\":\"vehicle\",";
  }
  std::snprintf(buf, sizeof(buf), "\"scan\":%" PRIu64 ",\"time\":", s.scan);
  out += buf;
  append_time(s.stamp_ns, out);
  std::snprintf(buf, sizeof(buf), ",\"ego\":{\"x\":%s,\"y\":%s,\"z\":%s,\"yaw\":%s},\"segments\":[",
                rt::json_number(s.ego.x, 4).c_str(), rt::json_number(s.ego.y, 4).c_str(),
                rt::json_number(s.ego.z, 4).c_str(), rt::json_number(s.ego.yaw, 6).c_str());
  out += buf;
  for (std::size_t i = 0; i < s.segments.size(); ++i) {
    const SegmentRecord& g = s.segments[i];
    std::snprintf(buf, sizeof(buf),
                  "%s{\"id\":%u,\"points\":%u,\"x\":%s,\"y\":%s,\"z\":%s,\"length\":%s,"
                  "\"width\":%s,\"height\":%s,\"yaw\":%s",
                  i == 0 ? "" : ",", g.id, g.points, rt::json_number(g.x, 4).c_str(),
                  rt::json_number(g.y, 4).c_str(), rt::json_number(g.z, 4).c_str(),
                  rt::json_number(g.length, 3).c_str(), rt::json_number(g.width, 3).c_str(),
                  rt::json_number(g.height, 3).c_str(), rt::json_number(g.yaw, 5).c_str());
    out += buf;
    if (g.has_truth) {
      out += ",\"truth\":{";
      for (std::size_t k = 0; k < g.truth.size(); ++k) {
        std::snprintf(buf, sizeof(buf), "%s\"%" PRId64 "\":%u", k == 0 ? "" : ",", g.truth[k].first,
                      g.truth[k].second);
        out += buf;
      }
      out += '}';
    }
    out += '}';
  }
  out += "],\"tracks\":[";
  for (std::size_t i = 0; i < s.tracks.size(); ++i) {
    const TrackRecord& t = s.tracks[i];
    std::snprintf(buf, sizeof(buf),
                  "%s{\"id\":%" PRIu64
                  ",\"state\":\"%s\",\"x\":%s,\"y\":%s,\"z\":%s,\"vx\":%s,"
                  "\"vy\":%s,\"length\":%s,\"width\":%s,\"height\":%s,\"yaw\":%s,"
                  "\"points\":%u,\"age\":%u,\"segment\":%d",
                  i == 0 ? "" : ",", t.id, t.state.c_str(), rt::json_number(t.x, 4).c_str(),
                  rt::json_number(t.y, 4).c_str(), rt::json_number(t.z, 4).c_str(),
                  rt::json_number(t.vx, 4).c_str(), rt::json_number(t.vy, 4).c_str(),
                  rt::json_number(t.length, 3).c_str(), rt::json_number(t.width, 3).c_str(),
                  rt::json_number(t.height, 3).c_str(), rt::json_number(t.yaw, 5).c_str(), t.points,
                  t.age, t.segment);
    out += buf;
    if (t.classified) {
      out += ",\"class\":\"" + t.cls + "\",\"log_odds\":[";
      for (std::size_t k = 0; k < t.log_odds.size(); ++k) {
        std::snprintf(buf, sizeof(buf), "%s%s", k == 0 ? "" : ",",
                      rt::json_number(t.log_odds[k], 4).c_str());
        out += buf;
      }
      out += ']';
    }
    out += '}';
  }
  out += "]}\n";
}

// A box's sides are lengths: never negative.
static void sizes(double length, double width, double height, const char* what) {
  if (length < 0 || width < 0 || height < 0) {
    throw FieldError{std::string("'") + what + "' has a negative length, width or height"};
  }
}

rt::Result<TracksScan> parse_tracks_line(std::string_view line) {
  return parse<TracksScan>(line, [](const json& j, TracksScan& s) {
    if (j.is_object() && j.contains("frame")) {
      const std::string f = text(j, "frame");
      if (f == "enu") {
        s.frame = TracksFrame::kEnu;
        s.origin = origin(j);
      } else if (f == "vehicle") {
        s.frame = TracksFrame::kVehicle;
        if (j.contains("origin")) throw FieldError{"'origin' is given with frame 'vehicle'"};
      } else {
        throw FieldError{"'frame' is '" + f + "'; expected enu or vehicle"};
      }
    } else if (j.is_object() && j.contains("origin")) {
      throw FieldError{"'origin' is given without 'frame'"};
    }
    s.scan = integer<std::uint64_t>(j, "scan");
    s.stamp_ns = stamp(j);
    s.ego = ego(j);
    for (const json& g : array(j, "segments")) {
      SegmentRecord r;
      const std::string w = "segments[].";
      r.id = integer<std::uint32_t>(g, "id", w);
      r.points = integer<std::uint32_t>(g, "points", w);
      r.x = number(g, "x", w);
      r.y = number(g, "y", w);
      r.z = number(g, "z", w);
      r.length = number(g, "length", w);
      r.width = number(g, "width", w);
      r.height = number(g, "height", w);
      r.yaw = number(g, "yaw", w);
      sizes(r.length, r.width, r.height, "segments[]");
      if (const auto it = g.find("truth"); it != g.end()) {
        if (!it->is_object()) throw FieldError{"'segments[].truth' is not an object"};
        r.has_truth = true;
        for (const auto& [key, value] : it->items()) {
          std::int64_t id = 0;
          const auto [end, ec] = std::from_chars(key.data(), key.data() + key.size(), id);
          if (ec != std::errc{} || end != key.data() + key.size() || key.empty()) {
            throw FieldError{"'segments[].truth' key '" + key + "' is not an object id"};
          }
          if (!value.is_number_unsigned()) {
            throw FieldError{"'segments[].truth." + key + "' is not a point count"};
          }
          r.truth.emplace_back(id, value.get<std::uint32_t>());
        }
      }
      s.segments.push_back(std::move(r));
    }
    for (const json& t : array(j, "tracks")) {
      TrackRecord r;
      const std::string w = "tracks[].";
      r.id = integer<std::uint64_t>(t, "id", w);
      r.state = text(t, "state", w);
      if (r.state != "tentative" && r.state != "confirmed" && r.state != "coasting") {
        throw FieldError{"'tracks[].state' is '" + r.state +
                         "'; expected tentative, confirmed or coasting"};
      }
      r.x = number(t, "x", w);
      r.y = number(t, "y", w);
      r.z = number(t, "z", w);
      r.vx = number(t, "vx", w);
      r.vy = number(t, "vy", w);
      r.length = number(t, "length", w);
      r.width = number(t, "width", w);
      r.height = number(t, "height", w);
      r.yaw = number(t, "yaw", w);
      r.points = integer<std::uint32_t>(t, "points", w);
      r.age = integer<std::uint32_t>(t, "age", w);
      r.segment = integer<std::int32_t>(t, "segment", w);
      // The id of one of the scan's segments when they are written, or -1 (none).
      const bool listed = std::any_of(
          s.segments.begin(), s.segments.end(),
          [&](const SegmentRecord& g) { return static_cast<std::int64_t>(g.id) == r.segment; });
      if (r.segment < -1 || (r.segment >= 0 && !s.segments.empty() && !listed)) {
        throw FieldError{"'tracks[].segment' is " + std::to_string(r.segment) +
                         ", the id of no segment of the scan (-1: none)"};
      }
      for (const TrackRecord& other : s.tracks) {
        if (other.id == r.id)
          throw FieldError{"track " + std::to_string(r.id) + " appears twice in the scan"};
      }
      sizes(r.length, r.width, r.height, "tracks[]");
      if (t.contains("class")) {
        r.classified = true;
        r.cls = text(t, "class", w);
        if (r.cls != "background" && !classification::check_class_names({r.cls}).empty()) {
          throw FieldError{"'tracks[].class' is '" + r.cls +
                           "'; expected a model class name (e.g. car) or background"};
        }
        const auto lo = t.find("log_odds");
        if (lo == t.end() || !lo->is_array() || lo->empty() ||
            lo->size() > classification::kMaxClasses) {
          throw FieldError{"'tracks[].log_odds' must be 1.." +
                           std::to_string(classification::kMaxClasses) +
                           " numbers (one per model class) when 'class' is given"};
        }
        for (const auto& v : *lo) {
          if (!v.is_number()) throw FieldError{"'tracks[].log_odds' must be numbers"};
          r.log_odds.push_back(v.get<double>());
        }
      }
      s.tracks.push_back(std::move(r));
    }
  });
}

rt::Result<TruthScanRecord> parse_truth_line(std::string_view line) {
  return parse<TruthScanRecord>(line, [](const json& j, TruthScanRecord& s) {
    if (j.is_object() && j.contains("origin")) s.origin = origin(j);
    s.scan = integer<std::uint64_t>(j, "scan");
    s.stamp_ns = stamp(j);
    if (j.is_object() && j.contains("end_time"))
      s.end_stamp_ns = std::llround(number(j, "end_time") * 1e9);
    s.ego = ego(j);
    for (const json& o : array(j, "objects")) {
      TruthObjectRecord r;
      r.id = integer<std::uint32_t>(o, "id", "objects[].");
      r.cls = text(o, "class", "objects[].");
      const json& b = field(o, "box", "objects[].");
      const std::string w = "objects[].box.";
      r.x = number(b, "x", w);
      r.y = number(b, "y", w);
      r.z = number(b, "z", w);
      r.length = number(b, "length", w);
      r.width = number(b, "width", w);
      r.height = number(b, "height", w);
      r.yaw = number(b, "yaw", w);
      const json& v = field(o, "velocity", "objects[].");
      r.vx = number(v, "x", "objects[].velocity.");
      r.vy = number(v, "y", "objects[].velocity.");
      r.points = integer<std::uint32_t>(o, "points", "objects[].");
      sizes(r.length, r.width, r.height, "objects[].box");
      for (const TruthObjectRecord& other : s.objects) {
        if (other.id == r.id)
          throw FieldError{"object " + std::to_string(r.id) + " appears twice in the scan"};
      }
      s.objects.push_back(std::move(r));
    }
  });
}

rt::Result<std::vector<TracksScan>> read_tracks_file(const std::filesystem::path& file,
                                                     const ReadProgress& progress) {
  return read_file<TracksScan>(file, parse_tracks_line, progress);
}

rt::Result<std::vector<TruthScanRecord>> read_truth_file(const std::filesystem::path& file,
                                                         const ReadProgress& progress) {
  return read_file<TruthScanRecord>(file, parse_truth_line, progress);
}

}  // namespace stac::evaluation
