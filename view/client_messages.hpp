// What a Foxglove client may send stac view (docs/view.md): subscribe and unsubscribe, as JSON
// text. Applied to one client's subscriptions without any networking, so the server and the
// fuzzing harness (fuzz/view_client_fuzz.cpp) run the same code. C++17, as the server is.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace stac::view {

// A client's subscriptions: its id -> channel index (0-based).
using Subscriptions = std::map<std::uint32_t, std::size_t>;

// At most this many error statuses answer one message (then one saying how many more).
inline constexpr std::size_t kMaxStatusesPerMessage = 8;

struct ClientMessageEffect {
  std::vector<std::string> errors;  // each answered with a status of level 2, and counted
  // Per channel subscribed (+1) or unsubscribed (-1) by this message, in order.
  std::vector<std::pair<std::size_t, int>> subscriber_changes;
};

// Applies `payload` (a text message) to `subscriptions` for a server of `channels` channels.
// A client holds one subscription per channel, under a 32-bit id; anything else is an error
// whose message quotes at most 80 characters of the client's text.
ClientMessageEffect apply_client_message(const std::string& payload, std::size_t channels,
                                         Subscriptions& subscriptions);

}  // namespace stac::view
