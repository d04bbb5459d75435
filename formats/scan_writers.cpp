#include "formats/scan_writers.hpp"

#include <array>
#include <charconv>
#include <cstring>
#include <vector>

namespace stac::formats {
namespace {

class CsvWriter final : public ScanWriter {
 public:
  CsvWriter(std::FILE* f, std::filesystem::path path) : file_(f), path_(std::move(path)) {
    std::fputs("scan,laser,azimuth,distance,x,y,z,intensity,time\n", file_);
  }
  ~CsvWriter() override { (void)close(); }

  rt::Status write(const velodyne::Scan& scan) override {
    char line[256];
    for (const velodyne::Point& p : scan.points) {
      char* o = line;
      char* end = line + sizeof(line);
      auto put_int = [&](long long v) {
        o = std::to_chars(o, end, v).ptr;
        *o++ = ',';
      };
      auto put_f = [&](float v, int digits) {
        o = std::to_chars(o, end, v, std::chars_format::fixed, digits).ptr;
        *o++ = ',';
      };
      put_int(static_cast<long long>(scan.header.sequence));
      put_int(p.laser);
      put_int(p.azimuth);
      put_f(p.distance_m, 4);
      put_f(p.x, 4);
      put_f(p.y, 4);
      put_f(p.z, 4);
      put_f(p.intensity, 2);
      // Absolute time in seconds with nanosecond digits, without double rounding.
      const long long t = scan.header.stamp_ns + p.time_offset_ns;
      const long long sec = t / 1'000'000'000;
      const long long ns = t % 1'000'000'000;
      o = std::to_chars(o, end, sec).ptr;
      *o++ = '.';
      char frac[16];
      const auto r = std::to_chars(frac, frac + sizeof(frac), ns < 0 ? -ns : ns);
      const auto len = static_cast<std::size_t>(r.ptr - frac);
      std::memset(o, '0', 9 - len);
      std::memcpy(o + 9 - len, frac, len);
      o += 9;
      *o++ = '\n';
      std::fwrite(line, 1, static_cast<std::size_t>(o - line), file_);
    }
    if (std::ferror(file_)) return rt::make_error(path_.string() + ": write failed");
    return {};
  }
  rt::Status close() override {
    if (file_ == nullptr) return {};
    const bool ok = std::fclose(file_) == 0;
    file_ = nullptr;
    if (!ok) return rt::make_error(path_.string() + ": write failed on close");
    return {};
  }

 private:
  std::FILE* file_;
  std::filesystem::path path_;
};

class KittiWriter final : public ScanWriter {
 public:
  explicit KittiWriter(std::filesystem::path dir) : dir_(std::move(dir)) {}
  rt::Status write(const velodyne::Scan& scan) override {
    char name[32];
    std::snprintf(name, sizeof(name), "%06llu.bin",
                  static_cast<unsigned long long>(scan.header.sequence));
    const auto path = dir_ / name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (f == nullptr)
      return rt::make_error(path.string() + ": cannot create: " + std::strerror(errno));
    buffer_.resize(scan.points.size() * 4);
    std::size_t i = 0;
    for (const velodyne::Point& p : scan.points) {
      buffer_[i++] = p.x;
      buffer_[i++] = p.y;
      buffer_[i++] = p.z;
      buffer_[i++] = p.intensity / 255.0f;
    }
    const bool ok = std::fwrite(buffer_.data(), sizeof(float), buffer_.size(), f) == buffer_.size();
    if (std::fclose(f) != 0 || !ok) return rt::make_error(path.string() + ": write failed");
    return {};
  }
  rt::Status close() override { return {}; }

 private:
  std::filesystem::path dir_;
  std::vector<float> buffer_;
};

}  // namespace

rt::Result<std::unique_ptr<ScanWriter>> make_scan_writer(const std::string& format,
                                                         const std::filesystem::path& out) {
  if (format == "csv") {
    std::FILE* f = std::fopen(out.c_str(), "w");
    if (f == nullptr)
      return rt::make_error(out.string() + ": cannot create: " + std::strerror(errno));
    return std::unique_ptr<ScanWriter>(new CsvWriter(f, out));
  }
  if (format == "kitti") {
    std::error_code ec;
    std::filesystem::create_directories(out, ec);
    if (ec || !std::filesystem::is_directory(out)) {
      return rt::make_error(out.string() + ": cannot create the output directory for kitti files");
    }
    return std::unique_ptr<ScanWriter>(new KittiWriter(out));
  }
  return rt::make_error("unknown format '" + format + "': use csv or kitti");
}

}  // namespace stac::formats
