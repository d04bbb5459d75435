// One section of config/stac.yaml, read once at start-up (STYLE rule 4): every key is required
// unless read with get_or(), and every error names the file and `section.key`. The shipped
// config/stac.yaml, built in, is the schema: a section or key it does not have (a misspelling),
// a key written twice, a file that is not a map of sections or a section that is not a map of
// keys is an error naming the line (with the nearest known name when one is close).
//
//   auto s = ConfigSection::open(file, "velodyne");     if (!s) return error;
//   auto port = s->get<int>("port");                     if (!port) return port.error();
//   if (*port > 65535) return s->error("port", "must be 1..65535");   // FILE: 'velodyne.port'
//                                                                    // must be 1..65535 (line 7)
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <type_traits>

#include "rt/expected.hpp"

namespace stac::settings {

// A configuration held in memory: while one lives, ConfigSection::open of its file name on this
// thread reads it instead of the disk (parsed once, at construction). The libFuzzer harness of
// the configuration loads every section this way, without a file per input; `file` names it in
// messages and anchors the relative paths it holds. Not copyable or movable (it registers its
// own address); the newest one of a name wins.
class ConfigSnapshot {
 public:
  ConfigSnapshot(const std::filesystem::path& file, const std::string& text);
  ~ConfigSnapshot();
  ConfigSnapshot(const ConfigSnapshot&) = delete;
  ConfigSnapshot& operator=(const ConfigSnapshot&) = delete;

 private:
  friend class ConfigSection;
  std::string file_;
  YAML::Node root_;
  std::string parse_error_;  // empty: root_ holds the parsed text
  ConfigSnapshot* previous_;
};

class ConfigSection {
 public:
  static rt::Result<ConfigSection> open(const std::filesystem::path& file, const std::string& name);

  template <class T>
  rt::Result<T> get(const char* key) const {
    const YAML::Node v = node_[key];
    if (!v) return rt::make_error(file_ + ": missing required key '" + name_ + "." + key + "'");
    return convert<T>(v, key);
  }
  template <class T>
  rt::Result<T> get_or(const char* key, T fallback) const {
    const YAML::Node v = node_[key];
    if (!v) return fallback;
    return convert<T>(v, key);
  }
  // get() into an existing variable, for reading many keys in one list.
  template <class T>
  rt::Status read(const char* key, T& out) const {
    auto v = get<T>(key);
    if (!v) return rt::Unexpected<rt::Error>{v.error()};
    out = *v;
    return {};
  }
  // The one form of a configuration error: "FILE: 'section.key' WHAT (line N)", the line the
  // key's value is on (none for a key the file leaves out). Every check of a value says it so.
  rt::Unexpected<rt::Error> error(const char* key, const std::string& what) const;
  // A check's message that starts with the key it is about ("cell_m must be in ..."; a library's
  // own validation, e.g. segmentation::validate) as error() gives it; a message about no single
  // key of the section names the section.
  rt::Unexpected<rt::Error> error_about(const std::string& message) const;
  // A path written in the file, relative to the file's folder unless absolute.
  std::filesystem::path path(const std::string& written) const;
  const YAML::Node& node() const noexcept { return node_; }

 private:
  template <class T>
  rt::Result<T> convert(const YAML::Node& v, const char* key) const {
    try {
      const T value = v.as<T>();
      // .nan and .inf are numbers to YAML; no setting means them, and NaN would pass every
      // range check after this one (each comparison is false).
      if constexpr (std::is_floating_point_v<T>) {
        if (!std::isfinite(value)) {
          return error(key, "must be a finite number, not '" + v.Scalar() + "'");
        }
      }
      return value;
    } catch (const YAML::Exception&) {
      return error(key, "has the wrong type");
    }
  }
  YAML::Node node_;
  std::string file_, name_;
};

}  // namespace stac::settings

// Reads `key` of section `s` into `dst`, returning the error from the enclosing function.
#define STAC_CONFIG_GET(s, type, key, dst)                                   \
  do {                                                                       \
    auto stac_value_ = (s).get<type>(key);                                   \
    if (!stac_value_) return rt::Unexpected<rt::Error>{stac_value_.error()}; \
    dst = *stac_value_;                                                      \
  } while (0)
