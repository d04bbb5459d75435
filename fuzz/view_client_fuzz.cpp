// What a Foxglove client sends `stac view` (view/client_messages.hpp): the input is split at
// '\n' into messages applied in turn to one client's subscriptions on a 4-channel server. Beyond
// the sanitizers, the server's limits are checked after every message: one subscription per
// channel (so never more than 4), every channel real, the subscriber changes adding up to the
// subscriptions held, and a bounded number of statuses per message.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "view/client_messages.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stac::view;
  constexpr std::size_t kChannels = 4;
  const std::string input(reinterpret_cast<const char*>(data), size);
  Subscriptions subscriptions;
  std::array<int, kChannels> subscribers{};
  std::size_t at = 0;
  while (at <= input.size()) {
    std::size_t end = input.find('\n', at);
    if (end == std::string::npos) end = input.size();
    const ClientMessageEffect effect =
        apply_client_message(input.substr(at, end - at), kChannels, subscriptions);
    at = end + 1;
    if (effect.errors.size() > kMaxStatusesPerMessage + 1) std::abort();
    for (const auto& [channel, change] : effect.subscriber_changes) {
      if (channel >= kChannels) std::abort();
      subscribers[channel] += change;
    }
    if (subscriptions.size() > kChannels) std::abort();
    std::array<int, kChannels> held{};
    for (const auto& [id, channel] : subscriptions) {
      if (channel >= kChannels || ++held[channel] > 1) std::abort();
    }
    if (held != subscribers) std::abort();
  }
  return 0;
}
