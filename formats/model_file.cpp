#include "formats/model_file.hpp"

#include <cstdint>
#include <fstream>
#include <iterator>
#include <system_error>
#include <vector>

#include "formats/durable_file.hpp"

namespace stac::formats {

rt::Status write_model_file(const std::filesystem::path& path,
                            const classification::TrackClassifierModel& model) {
  return write_file_durably(path, classification::serialize(model));
}

rt::Result<classification::TrackClassifierModel> read_model_file(
    const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return rt::make_error(
        name + ": no such model file; train one with `stac train --data DIR --out " + name + "`");
  }
  if (std::filesystem::is_directory(path, ec)) {
    return rt::make_error(name + ": is a folder, not a model file (`stac train --out` writes one)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return rt::make_error(name + ": cannot open the model file (permissions?)");
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  if (in.bad()) return rt::make_error(name + ": read failed");
  auto model = classification::deserialize(bytes);
  if (!model) {
    return rt::make_error(name + ": not a usable track classifier model (" + model.error().message +
                          "); retrain it with this build's `stac train`");
  }
  return std::move(*model);
}

rt::Result<std::shared_ptr<const classification::TrackClassifierModel>> job_model(
    const std::string& option, const std::filesystem::path& configured) {
  const std::filesystem::path path = option.empty()     ? configured
                                     : option == "none" ? std::filesystem::path{}
                                                        : std::filesystem::path(option);
  if (path.empty()) return std::shared_ptr<const classification::TrackClassifierModel>{};
  auto m = read_model_file(path);
  if (!m) return rt::Unexpected<rt::Error>{m.error()};
  return std::make_shared<const classification::TrackClassifierModel>(std::move(*m));
}

}  // namespace stac::formats
