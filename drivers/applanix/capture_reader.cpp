#include "drivers/applanix/capture_reader.hpp"

#include <cerrno>
#include <cstring>

namespace stac::applanix {
namespace {

bool looks_like_pcap(const std::uint8_t* m) noexcept {
  static constexpr std::uint8_t kMagics[][4] = {{0xD4, 0xC3, 0xB2, 0xA1},
                                                {0xA1, 0xB2, 0xC3, 0xD4},
                                                {0x4D, 0x3C, 0xB2, 0xA1},
                                                {0xA1, 0xB2, 0x3C, 0x4D},
                                                {0x0A, 0x0D, 0x0D, 0x0A}};
  for (const auto& magic : kMagics) {
    if (std::memcmp(m, magic, 4) == 0) return true;
  }
  return false;
}

// Both passes read every frame: frames are counted once, the rest per pass.
void add(io::PcapCounters& total, const io::PcapCounters& c, bool first_pass) noexcept {
  if (first_pass) total.frames = c.frames;
  total.datagrams += c.datagrams;
  total.segments += c.segments;
  total.truncated_frame += c.truncated_frame;
  total.bad_header += c.bad_header;
}

}  // namespace

void CaptureReader::FileCloser::operator()(std::FILE* f) const noexcept {
  if (f != nullptr) std::fclose(f);
}

rt::Result<CaptureReader> CaptureReader::open(const std::filesystem::path& path,
                                              std::optional<std::uint16_t> port) {
  CaptureReader r;
  r.path_ = path;
  r.port_ = port;
  r.file_.reset(std::fopen(path.c_str(), "rb"));
  if (!r.file_) return rt::make_error(path.string() + ": cannot open: " + std::strerror(errno));
  std::uint8_t magic[4] = {};
  const bool pcap = std::fread(magic, 1, 4, r.file_.get()) == 4 && looks_like_pcap(magic);
  if (pcap) {
    r.file_.reset();
    auto p = io::PcapReader::open(path);
    if (!p) return rt::make_error(p.error().message);
    r.pcap_ = std::make_unique<io::PcapReader>(std::move(*p));
    r.is_pcap_ = true;
  } else {
    std::rewind(r.file_.get());
    r.block_.resize(1 << 16);
  }
  return r;
}

bool CaptureReader::wanted(std::uint16_t port) const noexcept {
  if (port_) return port == *port_;
  return port >= kPortDisplay && port <= kPortLogging;
}

void CaptureReader::finish_pass() noexcept {
  add(pcap_totals_, pcap_->counters(), pass_ == 0);
  if (!pcap_->error().empty() && error_.empty()) error_ = pcap_->error();
  pcap_.reset();
  ++pass_;
  if (pass_ == 1) {
    auto p = io::PcapReader::open(path_);
    if (p) {
      pcap_ = std::make_unique<io::PcapReader>(std::move(*p));
    } else {
      error_ = p.error().message;
      pass_ = 2;
    }
  }
}

bool CaptureReader::refill() noexcept {
  if (file_) {
    const std::size_t n = std::fread(block_.data(), 1, block_.size(), file_.get());
    if (n == 0) {
      if (std::ferror(file_.get()) != 0) error_ = path_.string() + ": read error";
      parser_.end_of_stream();
      file_.reset();
      return false;
    }
    counters_.raw_bytes += n;
    parser_.feed({block_.data(), n});
    return true;
  }
  while (pcap_) {
    if (pass_ == 0) {
      io::Datagram d;
      while (pcap_->next(d)) {
        if (!wanted(d.dst_port)) continue;
        parser_.end_of_stream();  // each datagram holds whole messages
        parser_.feed(d.payload);
        ++counters_.datagrams;
        return true;
      }
      parser_.end_of_stream();
      finish_pass();
      continue;
    }
    std::span<const std::uint8_t> chunk;
    if (reassembler_.next(chunk)) {
      parser_.feed(chunk);
      return true;
    }
    io::TcpSegment s;
    bool added = false;
    while (!added && pcap_->next_tcp(s)) {
      if (!wanted(s.src_port)) continue;
      ++counters_.segments;
      if (reassembler_.add(s)) parser_.end_of_stream();  // a new connection
      added = true;
    }
    if (added) continue;
    if (!tcp_finished_) {
      tcp_finished_ = true;
      reassembler_.finish();
      continue;
    }
    parser_.end_of_stream();
    finish_pass();
  }
  return false;
}

bool CaptureReader::next(Parsed& out) noexcept {
  while (true) {
    if (parser_.next(out)) return true;
    if (!refill()) return false;
  }
}

}  // namespace stac::applanix
