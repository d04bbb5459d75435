#include "settings/config_section.hpp"

#include <algorithm>
#include <exception>
#include <set>
#include <system_error>
#include <vector>

namespace stac::settings {

extern const char* const kShippedConfigYaml;  // default_config.cpp, generated from config/stac.yaml

namespace {

const char* kind(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Null:
      return "empty";
    case YAML::NodeType::Scalar:
      return "a single value";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    default:
      return "undefined";
  }
}

std::string line_of(const YAML::Node& n) {
  const int line = n.Mark().line;
  return line >= 0 ? " (line " + std::to_string(line + 1) + ")" : std::string{};
}

// Edit distance (insertions, deletions, substitutions and swaps of two neighbours).
std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] =
          std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

// "; did you mean 'x'?" when one of `known` is close to `key`, else "; the known ones: ...".
std::string hint(const std::string& key, const YAML::Node& known, bool list_all) {
  std::string best, all;
  std::size_t best_d = 4;  // at most 3 edits away
  for (const auto& kv : known) {
    const auto name = kv.first.as<std::string>();
    all += (all.empty() ? "" : ", ") + name;
    // The distance is at least the difference in length: no table for names that far apart
    // (a long garbage key would cost its length times each name's).
    const std::size_t longer = std::max(key.size(), name.size());
    if (longer - std::min(key.size(), name.size()) >= best_d) continue;
    const std::size_t d = distance(key, name);
    if (d < best_d) best_d = d, best = name;
  }
  if (!best.empty()) return "; did you mean '" + best + "'?";
  return list_all ? "; the known ones are " + all
                  : std::string{"; see config/stac.yaml for the known ones"};
}

// The keys of `map` (named `where`) must be unique and known to `schema` (a map).
rt::Status check_keys(const std::string& file, const YAML::Node& map, const YAML::Node& schema,
                      const std::string& where, bool sections) {
  std::set<std::string> seen;
  for (const auto& kv : map) {
    if (!kv.first.IsScalar()) {
      return rt::make_error(file + ": a key of " + where + line_of(kv.first) + " is " +
                            kind(kv.first) + ", not a name");
    }
    const auto key = kv.first.as<std::string>();
    const std::string named =
        sections ? "section '" + key + ":'" : "key '" + where + "." + key + "'";
    if (!seen.insert(key).second) {
      return rt::make_error(file + ": " + named + line_of(kv.first) +
                            " appears twice; keep one (a YAML reader would silently take either)");
    }
    if (!schema[key]) {
      return rt::make_error(file + ": unknown " + named + line_of(kv.first) +
                            hint(key, schema, sections));
    }
  }
  return {};
}

}  // namespace

thread_local ConfigSnapshot* t_snapshots = nullptr;  // the newest; each links the one before

ConfigSnapshot::ConfigSnapshot(const std::filesystem::path& file, const std::string& text)
    : file_(file.string()), previous_(t_snapshots) {
  try {
    root_ = YAML::Load(text);
  } catch (const std::exception& e) {
    parse_error_ = e.what();
  }
  t_snapshots = this;
}

ConfigSnapshot::~ConfigSnapshot() {
  for (ConfigSnapshot** at = &t_snapshots; *at != nullptr; at = &(*at)->previous_) {
    if (*at == this) {
      *at = previous_;
      break;
    }
  }
}

rt::Result<ConfigSection> ConfigSection::open(const std::filesystem::path& file,
                                              const std::string& name) {
  ConfigSection s;
  s.file_ = file.string();
  s.name_ = name;
  const ConfigSnapshot* snapshot = t_snapshots;
  while (snapshot != nullptr && snapshot->file_ != s.file_) snapshot = snapshot->previous_;
  YAML::Node root;
  if (snapshot != nullptr) {
    if (!snapshot->parse_error_.empty()) {
      return rt::make_error(s.file_ + ": cannot read the configuration: " + snapshot->parse_error_);
    }
    root = snapshot->root_;
  } else {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) {
      return rt::make_error(s.file_ +
                            " is a directory; give the configuration file (e.g. config/stac.yaml)");
    }
    if (!std::filesystem::exists(file, ec))
      return rt::make_error(s.file_ + ": no such configuration file");
    try {
      root = YAML::LoadFile(s.file_);
    } catch (const YAML::Exception& e) {
      return rt::make_error(s.file_ + ": cannot read the configuration: " + e.what());
    } catch (const std::exception& e) {
      return rt::make_error(s.file_ + ": cannot read the configuration: " + e.what());
    }
  }
  if (!root.IsMap()) {
    return rt::make_error(
        s.file_ + ": the configuration is " + kind(root) +
        "; it must be a map of sections (velodyne:, ego:, segmentation:, ... as in "
        "config/stac.yaml)");
  }
  static const YAML::Node schema = YAML::Load(kShippedConfigYaml);
  if (auto ok = check_keys(s.file_, root, schema, "the file", true); !ok) {
    return rt::Unexpected<rt::Error>{ok.error()};
  }
  s.node_ = root[name];
  if (!s.node_) return rt::make_error(s.file_ + ": missing the '" + name + ":' section");
  if (!s.node_.IsMap()) {
    return rt::make_error(s.file_ + ": the '" + name + ":' section" + line_of(s.node_) + " is " +
                          kind(s.node_) + "; it must be a map of keys");
  }
  if (schema[name].IsMap()) {
    if (auto ok = check_keys(s.file_, s.node_, schema[name], name, false); !ok) {
      return rt::Unexpected<rt::Error>{ok.error()};
    }
  }
  return s;
}

std::filesystem::path ConfigSection::path(const std::string& written) const {
  const std::filesystem::path p(written);
  return p.is_absolute() ? p : std::filesystem::path(file_).parent_path() / p;
}

rt::Unexpected<rt::Error> ConfigSection::error(const char* key, const std::string& what) const {
  const YAML::Node v = node_[key];
  return rt::make_error(file_ + ": '" + name_ + "." + key + "' " + what +
                        (v ? line_of(v) : std::string{}));
}

rt::Unexpected<rt::Error> ConfigSection::error_about(const std::string& message) const {
  const std::size_t space = message.find(' ');
  if (space != std::string::npos) {
    const std::string key = message.substr(0, space);
    if (node_[key]) return error(key.c_str(), message.substr(space + 1));
  }
  return rt::make_error(file_ + ": the '" + name_ + ":' section: " + message);
}

}  // namespace stac::settings
