// The `classification:` section of config/stac.yaml (see settings/settings.hpp).
#include <string>

#include "settings/config_section.hpp"
#include "settings/settings.hpp"

namespace stac::settings {

rt::Result<ClassificationSettings> load_classification_settings(
    const std::filesystem::path& config_file) {
  auto section = ConfigSection::open(config_file, "classification");
  if (!section) return rt::Unexpected<rt::Error>{section.error()};
  const ConfigSection& c = *section;

  ClassificationSettings s;
  std::string model;
  std::uint64_t accumulated = 0, max_points = 0, every = 0;
#define STAC_GET(type, key, dst) STAC_CONFIG_GET(c, type, key, dst)
  STAC_GET(std::string, "model", model);
  STAC_GET(std::uint64_t, "accumulated_points", accumulated);
  STAC_GET(std::uint64_t, "holistic_every", every);
  STAC_GET(std::uint64_t, "max_segment_points", max_points);
#undef STAC_GET
  if (model.empty()) return c.error("model", "is empty; give a model file or 'none'");
  if (model != "none") s.model = c.path(model);
  if (accumulated < 1 || accumulated > 1'000'000)
    return c.error("accumulated_points", "must be in [1, 1000000]");
  if (every < 1 || every > 10'000) return c.error("holistic_every", "must be in [1, 10000]");
  if (max_points < 1 || max_points > 10'000'000)
    return c.error("max_segment_points", "must be in [1, 10000000]");
  s.classifier.accumulated_points = accumulated;
  s.classifier.holistic_every = static_cast<std::uint32_t>(every);
  s.classifier.descriptors.max_points = max_points;
  return s;
}

}  // namespace stac::settings
