#include "tools/config_section.hpp"

namespace stac::tools {

rt::Result<ConfigSection> ConfigSection::open(const std::filesystem::path& file, const std::string& name) {
  ConfigSection s;
  s.file_ = file.string();
  s.name_ = name;
  YAML::Node root;
  try {
    root = YAML::LoadFile(s.file_);
  } catch (const YAML::Exception& e) {
    return rt::make_error(s.file_ + ": cannot read the configuration: " + e.what());
  }
  s.node_ = root[name];
  if (!s.node_ || !s.node_.IsMap()) return rt::make_error(s.file_ + ": missing the '" + name + ":' section");
  return s;
}

std::filesystem::path ConfigSection::path(const std::string& written) const {
  const std::filesystem::path p(written);
  return p.is_absolute() ? p : std::filesystem::path(file_).parent_path() / p;
}

}  // namespace stac::tools
