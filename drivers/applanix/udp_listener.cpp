#include "drivers/applanix/udp_listener.hpp"

#include <algorithm>
#include <utility>

namespace stac::applanix {

rt::Result<UdpListener> UdpListener::open(const io::UdpReceiverConfig& config,
                                          std::size_t max_message_bytes) {
  io::UdpReceiverConfig c = config;
  c.batch = std::min(c.batch, 32);
  auto r = io::UdpReceiver::open(c);
  if (!r) return rt::make_error("Applanix " + r.error().message);
  return UdpListener(std::move(*r), max_message_bytes);
}

int UdpListener::receive(int timeout_ms) noexcept {
  if (index_ < count_) parser_.end_of_stream();
  const int n = receiver_.receive(batch_, timeout_ms);
  count_ = std::max(n, 0);
  index_ = 0;
  if (count_ > 0) {
    parser_.feed(batch_[0].payload);
    stamp_ns_ = batch_[0].stamp_ns;
  }
  return n;
}

bool UdpListener::next(Parsed& out) noexcept {
  while (index_ < count_) {
    if (parser_.next(out)) return true;
    parser_.end_of_stream();
    if (++index_ < count_) {
      parser_.feed(batch_[static_cast<std::size_t>(index_)].payload);
      stamp_ns_ = batch_[static_cast<std::size_t>(index_)].stamp_ns;
    }
  }
  return false;
}

}  // namespace stac::applanix
